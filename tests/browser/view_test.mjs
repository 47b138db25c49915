// The cohort page tested as a person would use it, in headless Chromium (issues 14 and 37):
//   node tests/browser/view_test.mjs PAGE.html RESULTS_DIR SCREENSHOT_DIR
// loads without console errors; every cell draws a brain; a drag in one cell turns every cell;
// hovering lights one element in all cells and names it in a tooltip that stays inside the
// window and goes on a click; clicking a patient's cell opens the detail (plot with its title
// clear of the value line, slices with L/R marks, foci table) whose picked element stays marked
// when the pointer leaves; a foci row jumps to its focus and is marked as chosen; closing the
// detail puts the shell back; no absolute path in the page; the foci counts are vpm compare's
// (and their volumes, also when the page draws coarser elements than compare used).
import fs from 'node:fs';
import path from 'node:path';
import { launch, openPage } from './browser.mjs';
import { Checks, shot, cellsOf, settled } from './check.mjs';

const [pagePath, results, shots] = process.argv.slice(2);
if (!shots) {
  console.error('usage: view_test.mjs PAGE.html RESULTS_DIR SCREENSHOT_DIR');
  process.exit(2);
}
fs.mkdirSync(shots, { recursive: true });
const t = new Checks();
const browser = await launch();
const box = (page, sel) => page.evaluate((s) => document.querySelector(s).getBoundingClientRect().toJSON(), sel);
const cellBox = (page, i) => page.evaluate((j) => document.querySelectorAll('#table-area .cell')[j].getBoundingClientRect().toJSON(), i);

try {
  const { page, errors } = await openPage(browser, pagePath);
  const manifest = await page.evaluate(() => window.vpmView.manifest);
  const cells = await cellsOf(page);
  const features = manifest.features.length;
  const K = manifest.shells;
  t.check(cells.length === (manifest.subjects.length + 1) * 2 * features,
    `${cells.length} cells for ${manifest.subjects.length} subjects and the normals' reference row`);

  await t.step('every cell draws a brain', async () => {
    const blank = [];
    for (const c of cells) {
      const p = await page.evaluate(async (i) => {
        document.querySelectorAll('#table-area .cell')[i].scrollIntoView({ block: 'center' });
        return window.vpmView.pixels(i);
      }, c.i);
      if (p.covered < 0.05 * p.total) blank.push(`${c.subject}/${c.column} (${p.covered} of ${p.total})`);
    }
    t.check(blank.length === 0, `every cell draws a brain${blank.length ? ': blank ' + blank.join(', ') : ''}`);
    await page.evaluate(() => document.getElementById('table-area').scrollTo(0, 0));
    await settled(page);
    await page.screenshot({ path: path.join(shots, 'table.png') });
  });

  const patientZ = cells.find((c) => c.group === 'patient' && c.kind === 'z').i;
  await t.step('a drag turns every cell', async () => {
    const other = cells.find((c) => c.subject !== cells[patientZ].subject && c.rect.top > 0 && c.rect.bottom < 800).i;
    const before = await page.evaluate((i) => Promise.all([window.vpmView.camera(), window.vpmView.pixels(i)]), other);
    const b0 = await cellBox(page, patientZ);
    await page.mouse.move(b0.x + b0.width / 2, b0.y + b0.height / 2);
    await page.mouse.down();
    for (let k = 1; k <= 8; ++k) await page.mouse.move(b0.x + b0.width / 2 + 10 * k, b0.y + b0.height / 2 + 2 * k);
    await page.mouse.up();
    const after = await page.evaluate((i) => Promise.all([window.vpmView.camera(), window.vpmView.pixels(i)]), other);
    t.check(Math.abs(after[0].yaw - before[0].yaw) > 0.3, `drag turns the shared view (yaw ${before[0].yaw.toFixed(2)} -> ${after[0].yaw.toFixed(2)})`);
    t.check(after[1].checksum !== before[1].checksum, `another subject's cell (${cells[other].subject}) turned too`);
    t.check(!(await page.evaluate(() => window.vpmView.state.detail)), 'a drag does not open the detail');
    await page.waitForTimeout(300);
    t.check(!(await page.evaluate(() => window.vpmView.scene.moving)), 'at rest again, cells are drawn in full detail');
  });

  await t.step('hovering lights an element in every cell', async () => {
    const bz = await cellBox(page, patientZ);
    await page.mouse.move(bz.x + bz.width / 2, bz.y + bz.height / 2);
    await page.waitForTimeout(100);
    const hover = await page.evaluate(async () => {
      const v = window.vpmView;
      const list = v.cells().filter((c) => (c.kind ?? (/z-score/.test(c.column) ? 'z' : '')) === 'z' && c.rect.top >= 0 && c.rect.bottom < innerHeight);
      const green = [];
      for (const c of list) green.push((await v.pixels(c.i)).green);
      return { element: v.state.hover ?? v.state.highlight, tooltip: document.getElementById('tooltip').textContent, green };
    });
    t.check(hover.element >= 0 && hover.tooltip.includes(`element ${hover.element}`), `hover picks element ${hover.element}: "${hover.tooltip.split('\n')[0]}"`);
    const lit = hover.green.filter((g) => g > 0).length;
    t.check(lit >= Math.ceil(hover.green.length / 2), `the element is lit in ${lit} of ${hover.green.length} visible z cells`);
    await page.screenshot({ path: path.join(shots, 'hover.png') });
  });

  await t.step("the foci counts shown are vpm compare's", async () => {
    const shown = await page.evaluate(() => [...document.querySelectorAll('.foci')].map((e) => [e.dataset.subject, e.dataset.feature, Number(e.dataset.count)]));
    const patients = manifest.subjects.filter((s) => s.group === 'patient').length;
    t.check(shown.length === patients * features, `${shown.length} foci counts shown for ${patients} patients`);
    for (const [sub, feature, n] of shown) {
      const side = JSON.parse(fs.readFileSync(path.join(results, 'compare', `${sub}_${feature}.json`), 'utf8'));
      t.check(side.result.clusters.length === n, `${sub}: ${n} foci shown, vpm compare found ${side.result.clusters.length}`);
      const drawn = await page.evaluate(async ([id, f]) => {
        const v = window.vpmView, s = v.manifest.subjects.find((x) => x.id === id);
        if (v.cohort) await v.cohort.load([s]);
        return Array.from(v.cohort ? v.cohort.cluster(s, f) : v.array(s.cluster[f])).filter((x) => x > 0).length;
      }, [sub, feature]);
      const want = side.result.clusters.reduce((k, c) => k + c.elements, 0);
      if (!manifest.compared) {
        t.check(drawn === want, `${sub} ${feature}: ${drawn} focus elements drawn saturated, vpm compare's clusters hold ${want}`);
        continue;
      }
      // drawn coarser than compared (vpm view --display-level): the foci keep their volume
      const volume = drawn * manifest.compared.elements / manifest.elements;
      t.check(Math.abs(volume - want) <= 0.2 * want + 8 * manifest.compared.elements / manifest.elements,
        `${sub} ${feature}: ${drawn} focus elements drawn, as many level-${manifest.compared.level} elements as ${volume.toFixed(0)}; vpm compare's clusters hold ${want}`);
    }
  });

  let fociRows = 0, shellBefore = -1;
  await t.step('a click opens the detail; the tooltip goes', async () => {
    shellBefore = await page.evaluate(() => window.vpmView.state.shell);
    const bz = await cellBox(page, patientZ);
    await page.mouse.move(bz.x + bz.width / 2, bz.y + bz.height / 2);
    await page.mouse.click(bz.x + bz.width / 2, bz.y + bz.height / 2);
    await page.waitForSelector('#detail:not([hidden])', { timeout: 5000 });
    await page.waitForSelector('#plot[data-state=drawn]', { timeout: 10000 }).catch(() => console.log('     (the plot never says it is drawn)'));
    t.check(await page.evaluate(() => document.getElementById('tooltip').hidden), 'the tooltip is hidden after the click (it covered the plot)');
    const d = await page.evaluate(async () => {
      const ink = (id) => {
        const c = document.getElementById(id);
        const px = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
        const seen = new Set();
        for (let i = 0; i < px.length; i += 4) seen.add((px[i] << 16) | (px[i + 1] << 8) | px[i + 2]);
        return seen.size;
      };
      await new Promise((r) => setTimeout(r, 300));
      return { title: document.getElementById('detail-title').textContent, info: document.getElementById('detail-info').textContent,
        plot: ink('plot'), slices: document.getElementById('slices').hidden ? -1 : ink('slice-2'),
        rows: document.querySelectorAll('#foci-table tr[data-focus]').length };
    });
    const view = await shot(page, await box(page, '#detail-view'));
    d.view = { covered: view.total - view.dark, total: view.total };
    t.check(d.title.startsWith(cells[patientZ].subject), `the detail opens for ${d.title}: ${d.info}`);
    t.check(d.plot > 10, `the distribution plot is drawn (${d.plot} colours)`);
    t.check(d.slices > 10, `the patient's slices are drawn (${d.slices} colours)`);
    const want = manifest.subjects.find((s) => s.id === cells[patientZ].subject).foci_table?.[manifest.features[0].name]?.length ?? 0;
    t.check(d.rows === want, `foci table: ${d.rows} rows`);
    fociRows = d.rows;
    t.check(d.view.covered > 0.05 * d.view.total, `the detail's 3-D view draws the brain (${d.view.covered} px)`);
    await page.screenshot({ path: path.join(shots, 'detail.png') });
  });

  await t.step("the plot's title is clear of the value line", async () => {
    const band = await page.evaluate(() => {
      const c = document.getElementById('plot');
      const px = c.getContext('2d').getImageData(0, 0, c.width, 34).data;
      let red = 0;
      for (let i = 0; i < px.length; i += 4) if (px[i] > 150 && px[i + 1] < 90 && px[i + 2] < 90) ++red;
      return red;
    });
    t.check(band === 0, `no red (the value line) in the plot's title band: ${band} px`);
  });

  await t.step('slices carry L/R marks; the note names the image by a relative path', async () => {
    const s = await page.evaluate(() => ({ labels: ['slice-2', 'slice-1', 'slice-0'].map((id) => document.getElementById(id).getAttribute('aria-label') || ''),
      edges: ['slice-2', 'slice-1'].map((id) => document.getElementById(id).dataset.edges || ''), note: document.getElementById('slices-note').textContent }));
    t.check(s.edges.every((e) => e.includes('L') && e.includes('R')), `axial and coronal slices marked left and right (${s.edges.join(', ')})`);
    t.check(/\bA\b/.test(s.labels[2]) || s.labels[2].includes('A on'), `the sagittal slice is marked anterior/posterior: ${s.labels[2]}`);
    t.check(!s.note.startsWith('/') && !s.note.includes(path.resolve(results)), `the slices' note names no absolute path: "${s.note.slice(0, 80)}"`);
    const html = fs.readFileSync(pagePath, 'utf8');
    const root = path.dirname(path.resolve(results));
    t.check(!html.includes(root), `the page holds no absolute path (${root} appears ${html.split(root).length - 1} times)`);
  });

  await t.step("the detail's picked element stays marked when the pointer leaves", async () => {
    await page.mouse.move(5, 5);  // the page's title bar
    await page.waitForTimeout(250);
    const v = await shot(page, await box(page, '#detail-view'));
    t.check(v.green > 0, `the detail's 3-D view still marks the picked element (${v.green} highlight pixels)`);
    t.check(await page.evaluate(() => window.vpmView.state.detail?.element >= 0), 'the panel still names it');
  });

  await t.step('the tooltip stays inside the window and off the detail panel', async () => {
    const area = await box(page, '#table-area');
    // a cell whose middle (where its brain is) is at the window's bottom edge
    const c = await page.evaluate(() => {
      const cells = [...document.querySelectorAll('#table-area .cell')];
      const el = cells[Math.min(cells.length - 1, 3)];
      el.scrollIntoView({ block: 'end' });
      document.getElementById('table-area').scrollBy(0, el.getBoundingClientRect().height / 2);
      return el.getBoundingClientRect().toJSON();
    });
    await settled(page);
    let inside = true, seen = 0;
    for (let x = c.x + 10; x < Math.min(c.right, area.right) - 4; x += 24) {
      await page.mouse.move(x, 800 - 8);
      const tip = await page.evaluate(() => { const el = document.getElementById('tooltip'); return el.hidden ? null : el.getBoundingClientRect().toJSON(); });
      if (!tip) continue;
      ++seen;
      const panel = await box(page, '#detail');
      if (tip.bottom > 800 || tip.right > 1280 || tip.left < 0 || tip.top < 0 || tip.right > panel.left + 1) inside = false;
    }
    t.check(seen > 0 && inside, `the tooltip at the bottom edge stays in the window, left of the detail (${seen} positions)`);
  });

  if (fociRows > 0) {
    await t.step('a foci row jumps to its focus and is marked chosen; closing restores the shell', async () => {
      const before = shellBefore;
      // a row whose peak is on another shell than the one shown, if any
      const pick = await page.evaluate(() => {
        const v = window.vpmView, d = v.state.detail, rows = d.subject.foci_table[d.feature];
        const i = rows.findIndex((r) => v.model.ids.shellOf(r.peak_element) !== v.state.shell);
        return Math.max(0, i);
      });
      await page.locator('#foci-table tr[data-focus]').nth(pick).click();
      const j = await page.evaluate(async (i) => {
        const v = window.vpmView, d = v.state.detail, row = d.subject.foci_table[d.feature][i];
        await new Promise((r) => setTimeout(r, 200));
        return { peak: row.peak_element, element: d.element, shell: v.state.shell, peakShell: v.model.ids.shellOf(row.peak_element),
          chosen: [...document.querySelectorAll('#foci-table tr[data-focus]')].map((tr) => tr.getAttribute('aria-selected') === 'true'),
          info: document.getElementById('detail-info').textContent };
      }, pick);
      t.check(j.element === j.peak && j.shell === j.peakShell, `a foci row opens its peak element ${j.peak} on shell ${j.shell + 1}: ${j.info}`);
      t.check(j.chosen[pick] && j.chosen.filter(Boolean).length === 1, `the chosen foci row is marked (${j.chosen.join(', ')})`);
      await page.screenshot({ path: path.join(shots, 'focus.png') });
      await page.click('#detail-close');
      const after = await page.evaluate(() => ({ shell: window.vpmView.state.shell, slider: Number(document.getElementById('shell').value) }));
      t.check(after.shell === before && after.slider === before + 1,
        `closing the detail puts the shell back (${before + 1} of ${K} before, ${j.shell + 1} in the detail, ${after.shell + 1} after)`);
    });
  }

  await t.step('ball mode and another shell still draw', async () => {
    for (const [what, act] of [['ball', () => document.getElementById('mode-ball').click()],
      ['shell 4', () => { const s = document.getElementById('shell'); s.value = '4'; s.dispatchEvent(new Event('input')); }]]) {
      await page.evaluate(act);
      const px = await page.evaluate(async () => {
        const v = window.vpmView, out = [];
        for (const c of v.cells().filter((x) => x.rect.top >= 0 && x.rect.bottom < innerHeight).slice(0, 4)) out.push((await v.pixels(c.i)).covered);
        return out;
      });
      t.check(px.length > 0 && px.every((n) => n > 500), `${what}: the first cells draw (${px.join(', ')} px)`);
      await page.screenshot({ path: path.join(shots, `${what.replace(' ', '_')}.png`) });
    }
  });
  t.check(errors.length === 0, `no console errors${errors.length ? ': ' + errors.join(' | ') : ''}`);
} finally {
  await browser.close();
}
t.finish();

