// The cohort page tested as a person would use it, in headless Chromium (issue 14):
//   node tests/browser/view_test.mjs PAGE.html RESULTS_DIR SCREENSHOT_DIR
// loads without console errors; every cell draws a brain (non-background pixels); a drag in one
// cell turns every cell; hovering highlights one element in all cells; clicking a patient's
// cell opens the detail with its plot, slices and foci table; the foci counts shown equal
// vpm compare's; native/ball and shell switches keep every cell drawn. Screenshots saved.
import fs from 'node:fs';
import path from 'node:path';
import { launch, openPage } from './browser.mjs';

const [pagePath, results, shots] = process.argv.slice(2);
if (!shots) {
  console.error('usage: view_test.mjs PAGE.html RESULTS_DIR SCREENSHOT_DIR');
  process.exit(2);
}
fs.mkdirSync(shots, { recursive: true });
let failures = 0;
function check(ok, what) {
  console.log(`${ok ? 'ok  ' : 'FAIL'} ${what}`);
  if (!ok) failures++;
}

const browser = await launch();
try {
  const { page, errors } = await openPage(browser, pagePath);
  const cells = await page.evaluate(() => window.vpmView.cells());
  const manifest = await page.evaluate(() => window.vpmView.manifest);
  const features = manifest.features.length;
  check(cells.length === manifest.subjects.length * 2 * features, `${cells.length} cells for ${manifest.subjects.length} subjects`);

  // every cell draws something: scroll each into view, count pixels off the background
  const blank = [];
  for (const c of cells) {
    const p = await page.evaluate((i) => {
      const cell = window.vpmView.scene.cells[i];
      cell.el.scrollIntoView({ block: 'center' });
      return window.vpmView.pixels(i);
    }, c.i);
    if (p.covered < 0.05 * p.total) blank.push(`${c.subject}/${c.column} (${p.covered} of ${p.total})`);
  }
  check(blank.length === 0, `every cell draws a brain${blank.length ? ': blank ' + blank.join(', ') : ''}`);
  await page.evaluate(() => document.getElementById('table-area').scrollTo(0, 0));
  await page.screenshot({ path: path.join(shots, 'table.png') });

  // a drag in the first cell turns the camera, and a cell elsewhere in the table changes with it
  const box = (i) => page.evaluate((j) => window.vpmView.scene.cells[j].el.getBoundingClientRect().toJSON(), i);
  const other = cells.find((c) => c.subject !== cells[0].subject && c.rect.top > 0).i;
  const before = await page.evaluate((i) => [window.vpmView.camera(), window.vpmView.pixels(i)], other);
  const b0 = await box(0);
  await page.mouse.move(b0.x + b0.width / 2, b0.y + b0.height / 2);
  await page.mouse.down();
  for (let k = 1; k <= 8; ++k) await page.mouse.move(b0.x + b0.width / 2 + 10 * k, b0.y + b0.height / 2 + 2 * k);
  await page.mouse.up();
  const after = await page.evaluate((i) => [window.vpmView.camera(), window.vpmView.pixels(i)], other);
  check(Math.abs(after[0].yaw - before[0].yaw) > 0.3, `drag turns the shared camera (yaw ${before[0].yaw.toFixed(2)} -> ${after[0].yaw.toFixed(2)})`);
  check(after[1].checksum !== before[1].checksum, `another subject's cell (${cells[other].subject}) turned too`);
  check(!(await page.evaluate(() => window.vpmView.state.detail)), 'a drag does not open the detail');
  await page.waitForTimeout(300);
  check(!(await page.evaluate(() => window.vpmView.scene.moving)), 'at rest again, cells are drawn in full detail');

  // hovering a z cell highlights its element in every visible cell of the table
  const zcell = cells.find((c) => c.column.includes('z-score')).i;
  const bz = await box(zcell);
  await page.mouse.move(bz.x + bz.width / 2, bz.y + bz.height / 2);
  const hover = await page.evaluate(() => {
    const v = window.vpmView;
    const shown = v.scene.cells.filter((c) => c.column.kind === 'z' && !c.hidden && c.el.getBoundingClientRect().bottom < innerHeight);
    return { element: v.state.highlight, tooltip: document.getElementById('tooltip').textContent,
      green: shown.map((c) => v.pixels(v.scene.cells.indexOf(c)).green) };
  });
  check(hover.element >= 0 && hover.tooltip.includes(`element ${hover.element}`), `hover picks element ${hover.element}: "${hover.tooltip.split('\n')[0]}"`);
  const lit = hover.green.filter((g) => g > 0).length;
  check(lit >= Math.ceil(hover.green.length / 2), `the element is highlighted in ${lit} of ${hover.green.length} visible z cells`);
  await page.screenshot({ path: path.join(shots, 'hover.png') });

  // the foci counts shown are vpm compare's
  const shown = await page.evaluate(() => [...document.querySelectorAll('.foci')].map((e) => [e.dataset.subject, e.dataset.feature, Number(e.dataset.count)]));
  const patients = manifest.subjects.filter((s) => s.group === 'patient').length;
  check(shown.length === patients * features, `${shown.length} foci counts shown for ${patients} patients`);
  for (const [sub, feature, n] of shown) {
    const side = JSON.parse(fs.readFileSync(path.join(results, 'compare', `${sub}_${feature}.json`), 'utf8'));
    check(side.result.clusters.length === n, `${sub}: ${n} foci shown, vpm compare found ${side.result.clusters.length}`);
  }

  // the foci on the patient's brain are vpm compare's elements
  const focusElements = await page.evaluate(() => {
    const v = window.vpmView;
    return v.manifest.subjects.filter((s) => s.group === 'patient').map((s) => [s.id, Object.fromEntries(
      Object.entries(s.cluster).map(([f, b]) => [f, Array.from(v.array(b)).filter((id) => id > 0).length]))]);
  });
  for (const [sub, perFeature] of focusElements)
    for (const [feature, n] of Object.entries(perFeature)) {
      const side = JSON.parse(fs.readFileSync(path.join(results, 'compare', `${sub}_${feature}.json`), 'utf8'));
      const want = side.result.clusters.reduce((k, c) => k + c.elements, 0);  // "elements": the count
      check(n === want, `${sub} ${feature}: ${n} focus elements drawn saturated, vpm compare's clusters hold ${want}`);
    }

  // a click on the first patient's z cell opens the detail: plot, slices, foci table, 3-D view
  await page.mouse.click(bz.x + bz.width / 2, bz.y + bz.height / 2);
  await page.waitForSelector('#detail:not([hidden])', { timeout: 5000 });
  const detail = await page.evaluate(() => {
    const ink = (id) => {
      const c = document.getElementById(id);
      const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
      const seen = new Set();
      for (let i = 0; i < d.length; i += 4) seen.add((d[i] << 16) | (d[i + 1] << 8) | d[i + 2]);
      return seen.size;
    };
    const v = window.vpmView;
    const dcell = v.scene.cells.find((c) => c.el.id === 'detail-view');
    return { title: document.getElementById('detail-title').textContent, info: document.getElementById('detail-info').textContent,
      plotColours: ink('plot'), sliceColours: document.getElementById('slices').hidden ? -1 : ink('slice-2'),
      fociRows: document.querySelectorAll('#foci-table tr[data-focus]').length,
      view: v.pixels(v.scene.cells.indexOf(dcell)), subject: v.state.detail.subject };
  });
  const first = manifest.subjects[cells[zcell].i % manifest.subjects.length] && detail.subject;
  check(detail.title.startsWith(cells[zcell].subject), `the detail opens for ${detail.title}: ${detail.info}`);
  check(detail.plotColours > 10, `the distribution plot is drawn (${detail.plotColours} colours)`);
  if (first.group === 'patient') {
    check(detail.sliceColours > 10, `the patient's slices are drawn (${detail.sliceColours} colours)`);
    check(detail.fociRows === (first.foci_table?.[manifest.features[0].name]?.length ?? 0), `foci table: ${detail.fociRows} rows`);
  }
  check(detail.view.covered > 0.05 * detail.view.total, `the detail's 3-D view draws the brain (${detail.view.covered} px)`);
  await page.screenshot({ path: path.join(shots, 'detail.png') });

  // a row of the foci table jumps to that focus: its peak element, on its shell, in every cell
  if (detail.fociRows > 0) {
    await page.click('#foci-table tr[data-focus]');
    const jump = await page.evaluate(() => {
      const v = window.vpmView, d = v.state.detail;
      const row = d.subject.foci_table[d.feature][0];
      const z = v.scene.cells.findIndex((c) => c.subject === d.subject && c.column.kind === 'z' && c.column.feature === d.feature);
      v.scene.cells[z].el.scrollIntoView({ block: 'center' });
      return { peak: row.peak_element, element: d.element, shell: v.state.shell, peakShell: v.model.ids.shellOf(row.peak_element),
        info: document.getElementById('detail-info').textContent, blue: v.pixels(z).blue };
    });
    check(jump.element === jump.peak && jump.shell === jump.peakShell,
      `a foci row opens its peak element ${jump.peak} on shell ${jump.shell + 1}: ${jump.info}`);
    check(jump.blue > 20, `the brains turn to the focus: ${jump.blue} deep-blue pixels in the patient's z cell`);
    await page.screenshot({ path: path.join(shots, 'focus.png') });
  }

  // ball mode and another shell: still every visible cell drawn
  for (const [what, act] of [['ball', () => document.getElementById('mode-ball').click()],
    ['shell 4', () => { const s = document.getElementById('shell'); s.value = '4'; s.dispatchEvent(new Event('input')); }]]) {
    await page.evaluate(act);
    const px = await page.evaluate(() => window.vpmView.scene.cells.slice(0, 4).map((c, i) => window.vpmView.pixels(i).covered));
    check(px.every((n) => n > 500), `${what}: the first cells draw (${px.join(', ')} px)`);
    await page.screenshot({ path: path.join(shots, `${what.replace(' ', '_')}.png`) });
  }
  check(errors.length === 0, `no console errors${errors.length ? ': ' + errors.join(' | ') : ''}`);
} finally {
  await browser.close();
}
console.log(failures ? `${failures} check(s) failed` : 'all checks passed');
process.exit(failures ? 1 : 0);
