// The cohort page's speed in headless Chromium with software WebGL (SwiftShader), as on a
// machine without a GPU (docs/view.md):
//   node bench/view/bench.mjs PAGE.html [RUNS=3] [OUT.json]
// Per run, a fresh page at 1280 x 800: time from navigation to the first frame of the table
// (performance marks of the page: vpm:decoded, vpm:first-frame), then frame rate while the
// shared camera turns a step every animation frame (120 frames, at the top of the table and
// scrolled to the middle; cells draw their element-level surface while turning, as when a
// person drags; once more at the top with the full surfaces throughout). Prints a table of medians and writes the runs as JSON.
import fs from 'node:fs';
import path from 'node:path';
import { launch, openPage } from '../../tests/browser/browser.mjs';

const [pagePath, runsArg, outJson] = process.argv.slice(2);
if (!pagePath) {
  console.error('usage: bench.mjs PAGE.html [RUNS] [OUT.json]');
  process.exit(2);
}
const runs = Number(runsArg || 3);
const median = (xs) => [...xs].sort((a, b) => a - b)[Math.floor(xs.length / 2)];
const browser = await launch();
const rows = [];
try {
  for (let r = 0; r < runs; ++r) {
    const { page, errors } = await openPage(browser, pagePath);
    const info = await page.evaluate(() => ({
      marks: window.vpmView.marks(), cells: window.vpmView.scene.cells.length, subjects: window.vpmView.manifest.subjects.length,
      features: window.vpmView.manifest.features.length, bytes: window.vpmView.bytes,
    }));
    await page.evaluate(() => window.vpmView.benchRotate(20));  // warm-up
    const top = await page.evaluate(() => window.vpmView.benchRotate(120));
    const full = await page.evaluate(() => window.vpmView.benchRotate(120, false));
    await page.evaluate(() => { const a = document.getElementById('table-area'); a.scrollTo(0, a.scrollHeight / 2); });
    const middle = await page.evaluate(() => window.vpmView.benchRotate(120));
    rows.push({ run: r + 1, ...info, first_frame_ms: info.marks['vpm:first-frame'], decoded_ms: info.marks['vpm:decoded'],
      fps_top: top.fps, fps_middle: middle.fps, fps_top_full_detail: full.fps, cells_drawn: top.cells_drawn,
      console_errors: errors.length });
    await page.close();
  }
} finally {
  await browser.close();
}
const size = fs.statSync(pagePath).size;
const summary = {
  page: path.resolve(pagePath), page_bytes: size, runs: rows.length, viewport: '1280x800',
  subjects: rows[0].subjects, features: rows[0].features, cells: rows[0].cells, cells_drawn: rows[0].cells_drawn,
  median_first_frame_ms: median(rows.map((r) => r.first_frame_ms)), median_decoded_ms: median(rows.map((r) => r.decoded_ms)),
  median_fps_top: median(rows.map((r) => r.fps_top)), median_fps_middle: median(rows.map((r) => r.fps_middle)),
  median_fps_top_full_detail: median(rows.map((r) => r.fps_top_full_detail)), rows,
};
console.log(`| page | subjects | cells (drawn) | first frame (ms) | data decoded (ms) | fps top | fps middle | fps top, full detail | runs |`);
console.log(`|---|---|---|---|---|---|---|---|---|`);
console.log(`| ${(size / 1e6).toFixed(1)} MB | ${summary.subjects} | ${summary.cells} (${summary.cells_drawn}) | ` +
  `${summary.median_first_frame_ms.toFixed(0)} | ${summary.median_decoded_ms.toFixed(0)} | ${summary.median_fps_top.toFixed(1)} | ` +
  `${summary.median_fps_middle.toFixed(1)} | ${summary.median_fps_top_full_detail.toFixed(1)} | ${rows.length} |`);
if (outJson) fs.writeFileSync(outJson, JSON.stringify(summary, null, 2) + '\n');
