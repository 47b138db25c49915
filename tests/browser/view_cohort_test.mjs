// A larger cohort's page with its data in a folder beside it (vpm view --data folder), in headless
// Chromium (issue 37): the synthetic cohort of tests/browser/synthetic_cohort.sh (normals and
// patients with foci at random places, derived from the workflow test's results).
//   node tests/browser/view_cohort_test.mjs PAGE.html RESULTS_DIR SCREENSHOT_DIR
// only the rows on screen are read at first; rows further down load and draw when scrolled to;
// the normals' reference row draws; each patient faces its strongest focus at the start; a
// normal's detail plots the other normals (its leave-one-out reference) and its z agrees with
// the plot; a data file missing is reported on the page, not a blank table.
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { launch, openPage } from './browser.mjs';
import { Checks, shot, cellsOf, settled } from './check.mjs';

const [pagePath, results, shots] = process.argv.slice(2);
if (!shots) {
  console.error('usage: view_cohort_test.mjs PAGE.html RESULTS_DIR SCREENSHOT_DIR');
  process.exit(2);
}
fs.mkdirSync(shots, { recursive: true });
const t = new Checks();
const browser = await launch();
const cellRect = (page, i) => page.evaluate((j) => document.querySelectorAll('#table-area .cell')[j].getBoundingClientRect().toJSON(), i);

try {
  const { page, errors } = await openPage(browser, pagePath);
  const manifest = await page.evaluate(() => window.vpmView.manifest);
  const total = Object.values(manifest.chunks ?? {}).reduce((n, c) => n + c.bytes, 0);

  await t.step('only the rows on screen are read at first', async () => {
    t.check(manifest.layout === 'folder', `the data is in ${manifest.data_dir}/ beside the page`);
    const read = await page.evaluate(() => (typeof window.vpmView.bytes === 'function' ? window.vpmView.bytes() : window.vpmView.bytes));
    t.check(total > 0 && read < 0.6 * total, `the first frame read ${(read / 1e6).toFixed(1)} of ${(total / 1e6).toFixed(1)} MB`);
    await page.screenshot({ path: path.join(shots, 'cohort.png') });
  });

  await t.step('the reference row draws the normals\' mean and spread', async () => {
    const ref = (await cellsOf(page)).filter((c) => c.group === 'reference');
    t.check(ref.length === 2 * manifest.features.length, `${ref.length} reference cells`);
    for (const c of ref) {
      const p = await page.evaluate((i) => window.vpmView.pixels(i), c.i);
      t.check(p.covered > 0.1 * p.total, `reference ${c.column}: ${p.covered} px drawn`);
    }
  });

  await t.step('each patient faces its strongest focus at the start', async () => {
    const patients = (await cellsOf(page)).filter((c) => c.group === 'patient' && c.kind === 'z');
    let shown = 0, tried = 0;
    for (const c of patients) {
      if (!manifest.subjects.find((s) => s.id === c.subject).foci_table?.[c.feature]?.length) continue;
      ++tried;
      await page.evaluate((i) => document.querySelectorAll('#table-area .cell')[i].scrollIntoView({ block: 'center' }), c.i);
      await settled(page);
      const r = await cellRect(page, c.i);
      const px = await shot(page, { x: r.x + 0.3 * r.width, y: r.y + 0.3 * r.height, width: 0.4 * r.width, height: 0.4 * r.height });
      if (px.red + px.blue >= 40) ++shown;
      else console.log(`     ${c.subject}: ${px.red + px.blue} saturated pixels`);
    }
    t.check(tried > 0 && shown === tried, `${shown} of ${tried} patients with foci show their strongest focus in the middle of their z cell in the opening view`);
  });

  await t.step("a normal's detail plots the other normals; its z agrees", async () => {
    const n = (await cellsOf(page)).find((c) => c.group === 'normal' && c.kind === 'value');
    await page.evaluate((i) => document.querySelectorAll('#table-area .cell')[i].scrollIntoView({ block: 'center' }), n.i);
    await settled(page);
    const r = await cellRect(page, n.i);
    await page.mouse.click(r.x + r.width / 2, r.y + r.height / 2);
    await page.waitForSelector('#plot[data-state=drawn]', { timeout: 15000 });
    const got = await page.evaluate(async () => {
      const v = window.vpmView, d = v.state.detail, c = document.getElementById('plot').dataset;
      const others = [];
      for (const s of v.cohort.normals) {
        if (s === d.subject) continue;
        await v.cohort.load([s]);
        others.push(v.cohort.values(s, d.feature)[d.element]);
      }
      return { id: d.subject.id, e: d.element, plotted: { mean: Number(c.mean), std: Number(c.std), z: Number(c.z), value: Number(c.value), n: Number(c.normals) },
        others, cellZ: v.cohort.z(d.subject, d.feature)[d.element] };
    });
    const m = got.others.reduce((a, b) => a + b, 0) / got.others.length;
    const sd = Math.sqrt(got.others.reduce((a, b) => a + (b - m) ** 2, 0) / (got.others.length - 1));
    const p = got.plotted;
    t.check(p.n === got.others.length && Math.abs(p.mean - m) < 1e-4 * Math.abs(m) + 1e-6 && Math.abs(p.std - sd) < 1e-3 * sd + 1e-6,
      `${got.id} at element ${got.e}: the curve is the other ${got.others.length} normals (mean ${p.mean.toFixed(4)}, std ${p.std.toFixed(4)}; ` +
      `theirs ${m.toFixed(4)}, ${sd.toFixed(4)})`);
    const z = (p.value - m) / sd;
    t.check(Math.abs(p.z - z) < 2e-3 && Math.abs(got.cellZ - p.z) < 1e-4, `its z ${p.z.toFixed(3)} is against them (${z.toFixed(3)}), as its cell's`);
    await page.screenshot({ path: path.join(shots, 'normal_detail.png') });
    await page.keyboard.press('Escape');
  });

  await t.step('rows further down load and draw when scrolled to', async () => {
    await page.evaluate(() => { const a = document.getElementById('table-area'); a.scrollTo(0, a.scrollHeight); });
    await settled(page);
    const last = (await cellsOf(page)).at(-1);
    const p = await page.evaluate((i) => window.vpmView.pixels(i), last.i);
    t.check(p.covered > 0.05 * p.total, `the last normal (${last.subject}) draws (${p.covered} px)`);
    const read = await page.evaluate(() => (typeof window.vpmView.bytes === 'function' ? window.vpmView.bytes() : window.vpmView.bytes));
    t.check(read > 0, `${(read / 1e6).toFixed(1)} MB read after scrolling to the end`);
  });
  t.check(errors.length === 0, `no console errors${errors.length ? ': ' + errors.join(' | ') : ''}`);

  await t.step('a missing data file is reported on the page', async () => {
    const dir = fs.mkdtempSync(path.join(os.tmpdir(), 'vpm-view-'));
    const copy = path.join(dir, path.basename(pagePath));
    fs.copyFileSync(pagePath, copy);
    fs.cpSync(path.join(path.dirname(pagePath), manifest.data_dir), path.join(dir, manifest.data_dir), { recursive: true });
    fs.rmSync(path.join(dir, manifest.data_dir, 'rows-000.js'));
    const p2 = await browser.newPage({ viewport: { width: 1280, height: 800 } });
    await p2.goto('file://' + copy);
    await p2.waitForSelector('#loading[role=alert]', { timeout: 20000 });
    const text = await p2.evaluate(() => document.getElementById('loading').textContent);
    t.check(/rows-000\.js could not be read/.test(text), `the page says: "${text}"`);
    await p2.close();
    fs.rmSync(dir, { recursive: true });
  });
} finally {
  await browser.close();
}
t.finish();
