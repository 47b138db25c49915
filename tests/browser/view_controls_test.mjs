// The cohort page's controls, keyboard, layout and start-up, in headless Chromium (issue 37):
//   node tests/browser/view_controls_test.mjs PAGE.html RESULTS_DIR SCREENSHOT_DIR
// a loading indicator shows while the data loads and no control shows a wrong value; the title is
// the dataset's; the legend explains units, leave-one-out z and the tested direction; the shell
// slider stays under the pointer while dragged; Escape closes the detail, Tab reaches cells and
// foci rows, arrow keys turn, Enter opens; every control and cell has an accessible name; cells
// fill the window at 1280x800 and 1920x1080 and follow the size control; Ctrl + wheel zooms;
// column headers and colour bars stay on screen while the table scrolls, no brain drawn over
// them; each patient faces its strongest focus at the start; the hover marker is large enough to see.
import fs from 'node:fs';
import path from 'node:path';
import { launch, openPage } from './browser.mjs';
import { Checks, shot, unnamed, cellsOf, settled } from './check.mjs';

const [pagePath, results, shots] = process.argv.slice(2);
if (!shots) {
  console.error('usage: view_controls_test.mjs PAGE.html RESULTS_DIR SCREENSHOT_DIR');
  process.exit(2);
}
fs.mkdirSync(shots, { recursive: true });
const t = new Checks();
const browser = await launch();
const rectOf = (page, sel) => page.evaluate((s) => document.querySelector(s)?.getBoundingClientRect().toJSON(), sel);

// recorded from the first moment of the page, before its own script: what a person sees while it loads
function recordLoading() {
  window.__frames = [];
  const look = () => {
    const el = document.getElementById('loading'), shell = document.getElementById('shell'), controls = document.querySelector('.controls');
    if (document.body && !document.body.dataset.ready)
      window.__frames.push({ loading: !!el && !el.hidden && el.getClientRects().length > 0,
        controlsShown: !!controls && getComputedStyle(controls).visibility !== 'hidden', shell: shell ? `${shell.value}/${shell.max}` : '' });
    if (!document.body?.dataset.ready) requestAnimationFrame(look);
  };
  requestAnimationFrame(look);
}

try {
  const { page, errors } = await openPage(browser, pagePath, { width: 1280, height: 800 }, recordLoading);
  const manifest = await page.evaluate(() => window.vpmView.manifest);
  const K = manifest.shells;

  await t.step('a loading indicator, no control with a wrong value', async () => {
    const frames = await page.evaluate(() => window.__frames);
    t.check(frames.some((f) => f.loading), `a loading indicator shows before the cells are drawn (${frames.length} frames seen)`);
    const wrong = frames.filter((f) => f.controlsShown && f.shell !== `${K}/${K}`);
    t.check(wrong.length === 0, `no frame shows the shell slider at a wrong value (${wrong.map((f) => f.shell).join(' ') || 'none'})`);
    t.check(await page.evaluate(() => document.getElementById('loading')?.hidden !== false), 'the indicator goes when the cells are drawn');
  });

  await t.step("the title is the dataset's; the legend explains the numbers", async () => {
    const title = await page.title();
    const desc = path.join(path.dirname(path.resolve(results)), 'bids', 'dataset_description.json');
    const want = fs.existsSync(desc) ? JSON.parse(fs.readFileSync(desc, 'utf8')).Name : null;
    t.check(title !== 'vpm cohort' && (!want || title === want), `title "${title}"${want ? ` (the dataset's Name: "${want}")` : ''}`);
    const legend = await page.evaluate(() => document.getElementById('legend')?.textContent || '');
    t.check(/leave-one-out/.test(legend), 'the legend says normals\' z is leave-one-out');
    t.check(/proportional/.test(legend) && /global mean|subject.s mean/.test(legend), 'the legend explains proportional scaling');
    const sign = manifest.features[0].sign;
    const dir = sign < 0 ? /below the normals only/ : sign > 0 ? /above the normals only/ : /above and below/;
    t.check(dir.test(legend), `the legend names the direction searched (sign ${sign})`);
  });

  await t.step('at the start each patient faces its strongest focus; the hover marker is large', async () => {
    const patients = (await cellsOf(page)).filter((c) => c.group === 'patient' && c.kind === 'z');
    for (const c of patients) {
      const has = manifest.subjects.find((s) => s.id === c.subject).foci_table?.[c.feature]?.length;
      if (!has) continue;
      await page.evaluate((i) => document.querySelectorAll('#table-area .cell')[i].scrollIntoView({ block: 'center' }), c.i);
      await settled(page);
      const r = await page.evaluate((i) => document.querySelectorAll('#table-area .cell')[i].getBoundingClientRect().toJSON(), c.i);
      // the middle of the cell: a row facing its focus has it there
      // (as a share of the focus pixels the whole cell shows: a focus's size depends on the analysis'
      // settings, its place in the cell on the view)
      const px = await shot(page, { x: r.x + 0.3 * r.width, y: r.y + 0.3 * r.height, width: 0.4 * r.width, height: 0.4 * r.height });
      const all = await shot(page, r);
      const mid = px.red + px.blue, whole = all.red + all.blue;
      t.check(mid >= 10 && mid >= 0.4 * whole,
        `${c.subject}'s z cell shows its strongest focus in its middle (${mid} of the cell's ${whole} saturated pixels)`);
      await page.mouse.move(r.x + r.width / 2, r.y + r.height / 2);
      await page.waitForTimeout(150);
      const lit = await shot(page, r);
      t.check(lit.greenBox[0] >= 18 && lit.greenBox[1] >= 18, `the hover marker is ${lit.greenBox.join(' x ')} px`);
      // and in the other cell of the row (the value column), where the pointer is not
      const v = (await cellsOf(page)).find((x) => x.subject === c.subject && x.kind === 'value');
      const other = await shot(page, v.rect);
      t.check(other.greenBox[0] >= 18 && other.greenBox[1] >= 18, `the marker in ${c.subject}'s value cell is ${other.greenBox.join(' x ')} px`);
      await page.screenshot({ path: path.join(shots, 'marker.png') });
      // the row's button turns it to the shared view and back
      const face = `.row[data-subject="${c.subject}"] .face`;
      const pressed = () => page.evaluate((sel) => document.querySelector(sel)?.getAttribute('aria-pressed'), face);
      const was = await pressed();
      await page.click(face).catch(() => {});
      const off = await pressed();
      await page.click(face).catch(() => {});
      t.check(was === 'true' && off === 'false' && (await pressed()) === 'true', `${c.subject}'s "face focus" button toggles its own view (${was} -> ${off} -> ${await pressed()})`);
    }
    await page.mouse.move(5, 5);
  });

  await t.step('the shell slider stays under the pointer while dragged', async () => {
    const s = await rectOf(page, '#shell');
    const y = s.y + s.height / 2;
    await page.mouse.move(s.right - 6, y);
    await page.mouse.down();
    const seen = [];
    for (let dx = 0; dx <= 24; dx += 3) {
      await page.mouse.move(s.right - 6 - dx, y);
      seen.push(await page.evaluate(() => ({ x: document.getElementById('shell').getBoundingClientRect().x, v: Number(document.getElementById('shell').value) })));
    }
    await page.mouse.up();
    const moved = Math.max(...seen.map((p) => Math.abs(p.x - s.x)));
    const values = seen.map((p) => p.v);
    const steady = values.every((v, i) => i === 0 || (v <= values[i - 1] && values[i - 1] - v <= 2));
    t.check(moved < 1, `the slider does not move while dragged (${moved.toFixed(1)} px)`);
    // 24 px of a slider of K shells over its width: about 24 (K - 1) / width shells, not a jump
    const expect = (24 * (K - 1)) / s.width;
    t.check(steady && K - values.at(-1) <= 2 * expect + 1, `a 24 px drag steps the shell evenly (about ${expect.toFixed(1)} shells): ${values.join(' -> ')}`);
    await page.evaluate((k) => { const el = document.getElementById('shell'); el.value = String(k); el.dispatchEvent(new Event('input')); }, K);
  });

  await t.step('every control and cell has an accessible name', async () => {
    const missing = await unnamed(page, 'button, input, select, .cell, canvas[role=img], [tabindex]');
    t.check(missing.length === 0, `accessible names: ${missing.length ? 'missing on ' + missing.slice(0, 6).join(', ') : 'all present'}`);
  });

  await t.step('keyboard: Tab reaches a cell, arrows turn, Enter opens, Tab reaches foci rows, Escape closes', async () => {
    await page.evaluate(() => document.activeElement?.blur());
    let onCell = false;
    for (let k = 0; k < 30 && !onCell; ++k) {
      await page.keyboard.press('Tab');
      onCell = await page.evaluate(() => document.activeElement?.classList.contains('cell'));
    }
    t.check(onCell, 'Tab reaches a cell of the table');
    const before = await page.evaluate(() => window.vpmView.camera());
    await page.keyboard.press('ArrowRight');
    await page.keyboard.press('ArrowRight');
    const after = await page.evaluate(() => window.vpmView.camera());
    t.check(Math.abs(after.yaw - before.yaw) > 0.1, `arrow keys turn the view (yaw ${before.yaw.toFixed(2)} -> ${after.yaw.toFixed(2)})`);
    // a patient's z cell: Enter opens its detail at its strongest focus
    const pz = (await cellsOf(page)).find((c) => c.group === 'patient' && c.kind === 'z').i;
    await page.evaluate((i) => document.querySelectorAll('#table-area .cell')[i].focus(), pz);
    await page.keyboard.press('Enter');
    const open = await page.evaluate(() => !document.getElementById('detail').hidden);
    t.check(open, 'Enter opens the detail');
    let onRow = false;
    for (let k = 0; k < 12 && !onRow; ++k) {
      await page.keyboard.press('Tab');
      onRow = await page.evaluate(() => document.activeElement?.matches('#foci-table tr[data-focus]'));
    }
    t.check(onRow, 'Tab reaches the foci rows');
    if (onRow) {
      await page.keyboard.press('Enter');
      t.check(await page.evaluate(() => document.activeElement?.getAttribute('aria-selected') === 'true'), 'Enter on a foci row chooses it');
    }
    if (!(await page.evaluate(() => !document.getElementById('detail').hidden))) {  // opened by a click then
      const r = await page.evaluate((i) => document.querySelectorAll('#table-area .cell')[i].getBoundingClientRect().toJSON(), pz);
      await page.mouse.click(r.x + r.width / 2, r.y + r.height / 2);
    }
    await page.keyboard.press('Escape');
    t.check(await page.evaluate(() => document.getElementById('detail').hidden), 'Escape closes the detail');
    t.check(await page.evaluate(() => document.activeElement?.classList.contains('cell')), 'the keyboard focus goes back to the cell');
  });

  await t.step('Ctrl + wheel zooms', async () => {
    const c = (await cellsOf(page)).find((x) => x.rect.top > 0 && x.rect.bottom < 800 && x.group !== 'reference');
    const before = await page.evaluate(async (i) => [window.vpmView.camera(), await window.vpmView.pixels(i)], c.i);
    await page.mouse.move(c.rect.x + c.rect.width / 2, c.rect.y + c.rect.height / 2);
    await page.keyboard.down('Control');
    for (let k = 0; k < 4; ++k) await page.mouse.wheel(0, -120);
    await page.keyboard.up('Control');
    await page.waitForTimeout(250);
    const after = await page.evaluate(async (i) => [window.vpmView.camera(), await window.vpmView.pixels(i)], c.i);
    t.check(after[1].covered > 1.15 * before[1].covered, `the brain grows in its cell (${before[1].covered} -> ${after[1].covered} px)`);
    await page.evaluate(() => { window.vpmView.scene.zoom = 1; window.vpmView.render?.(); });
  });

  await t.step('headers and colour bars stay on screen while the table scrolls', async () => {
    await page.evaluate(() => { const a = document.getElementById('table-area'); a.scrollTo(0, Math.min(700, a.scrollHeight)); });
    await settled(page);
    const bar = await page.evaluate(() => {
      const area = document.getElementById('table-area').getBoundingClientRect();
      const bars = [...document.querySelectorAll('.bar')].map((b) => b.getBoundingClientRect()).filter((r) => r.top >= area.top - 1 && r.bottom <= area.bottom && r.width > 0);
      return bars.length ? bars[0].toJSON() : null;
    });
    t.check(!!bar, 'a colour bar is on screen after scrolling 700 px');
    if (bar) {
      const px = await shot(page, { x: bar.x, y: bar.y, width: bar.width, height: bar.height });
      t.check(px.dark < 0.05 * px.total, `no brain drawn over the colour bar (${px.dark} dark pixels of ${px.total})`);
    }
    await page.screenshot({ path: path.join(shots, 'scrolled.png') });
    await page.evaluate(() => document.getElementById('table-area').scrollTo(0, 0));
  });

  await t.step('cells fill the window and follow the size control', async () => {
    for (const vp of [{ width: 1280, height: 800 }, { width: 1920, height: 1080 }]) {
      await page.setViewportSize(vp);
      await page.waitForTimeout(200);
      const use = await page.evaluate(() => {
        const area = document.getElementById('table-area'), a = area.getBoundingClientRect();
        const rows = [...document.querySelectorAll('#table-area .row')].map((r) => r.getBoundingClientRect()).filter((r) => r.top < a.bottom && r.bottom > a.top);
        const left = Math.min(...rows.map((r) => r.left)), right = Math.max(...rows.map((r) => r.right));
        const cell = document.querySelector('#table-area .cell').getBoundingClientRect().width;
        return { used: (right - left) / a.width, cell };
      });
      t.check(use.used > 0.75 && use.cell > 150, `${vp.width}x${vp.height}: the rows use ${(100 * use.used).toFixed(0)} % of the table's width, cells ${use.cell.toFixed(0)} px`);
      await settled(page);
      await page.screenshot({ path: path.join(shots, `table_${vp.width}.png`) });
    }
    await page.selectOption('#cell-size', '180');
    const w = await page.evaluate(() => document.querySelector('#table-area .cell').getBoundingClientRect().width);
    t.check(Math.abs(w - 180) < 1, `the size control sets the cells to 180 px (${w})`);
    await page.selectOption('#cell-size', 'auto');
  });
  t.check(errors.length === 0, `no console errors${errors.length ? ': ' + errors.join(' | ') : ''}`);
} finally {
  await browser.close();
}
t.finish();
