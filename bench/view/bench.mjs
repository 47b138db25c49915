// The cohort page's speed and memory in headless Chromium with software WebGL (SwiftShader), as
// on a machine without a GPU (docs/view.md):
//   node bench/view/bench.mjs PAGE.html[,PAGE2.html...] [RUNS=3] [OUT.json] [WIDTHxHEIGHT=1280x800] [CELL_PX]
// Per run, a fresh browser and page: time from navigation to the first frame with every cell on
// screen drawn (the page's performance marks vpm:decoded, vpm:first-frame), the data read by then,
// the frame rate while the shared view turns a step every animation frame (120 frames at the top
// of the table and scrolled to the middle, cells at their element-level surface as while a person
// drags; once more at the top with the full surfaces throughout), and the browser's memory: the
// proportional set size (PSS) of all its processes after the first frame and the most seen while
// scrolling through the whole table in 12 steps. CELL_PX: the frame rates with cells of that size
// (the page's size control; pages before issue 37 have 150 px cells). Prints a table of medians;
// writes the runs as JSON. Several pages (comma-separated) are run in turn, run by run, so that
// they meet the same load on a shared machine; OUT.json then holds a list.
import fs from 'node:fs';
import path from 'node:path';
import { launch, openPage } from '../../tests/browser/browser.mjs';

const [pagesArg, runsArg, outJson, sizeArg, cellArg] = process.argv.slice(2);
if (!pagesArg) {
  console.error('usage: bench.mjs PAGE.html[,PAGE2.html...] [RUNS] [OUT.json] [WIDTHxHEIGHT] [CELL_PX]');
  process.exit(2);
}
const runs = Number(runsArg || 3);
const [width, height] = (sizeArg || '1280x800').split('x').map(Number);
const median = (xs) => [...xs].sort((a, b) => a - b)[Math.floor(xs.length / 2)];

/** PSS (bytes) of every process below this one (the browser and its helpers). */
function browserPss() {
  const parent = new Map();
  for (const pid of fs.readdirSync('/proc').filter((d) => /^\d+$/.test(d))) {
    try {
      const stat = fs.readFileSync(`/proc/${pid}/stat`, 'utf8');
      parent.set(Number(pid), Number(stat.slice(stat.lastIndexOf(')') + 2).split(' ')[1]));
    } catch { /* gone */ }
  }
  const below = (pid) => { for (let p = parent.get(pid); p; p = parent.get(p)) if (p === process.pid) return true; return false; };
  let total = 0;
  for (const pid of parent.keys()) {
    if (!below(pid)) continue;
    try {
      const m = /^Pss:\s+(\d+) kB/m.exec(fs.readFileSync(`/proc/${pid}/smaps_rollup`, 'utf8'));
      if (m) total += Number(m[1]) * 1024;
    } catch { /* gone */ }
  }
  return total;
}

function dataBytes(page) {
  const html = fs.readFileSync(page, 'utf8');
  const m = /<script id="vpm-manifest" type="application\/json">(.*?)<\/script>/s.exec(html);
  const manifest = JSON.parse(m[1]);
  let folder = 0;
  if (manifest.layout === 'folder') {
    const dir = path.join(path.dirname(page), manifest.data_dir);
    for (const f of fs.readdirSync(dir)) folder += fs.statSync(path.join(dir, f)).size;
  }
  return { html: html.length, folder, layout: manifest.layout || 'file' };
}

const loadAverage = () => fs.readFileSync('/proc/loadavg', 'utf8').split(' ').slice(0, 3).map(Number);

async function run(pagePath, r) {
  const load = loadAverage();
  const browser = await launch();
  try {
    const { page, errors } = await openPage(browser, pagePath, { width, height });
    const info = await page.evaluate(() => {
      const v = window.vpmView;
      return { marks: v.marks(), cells: v.cells().length, subjects: v.manifest.subjects.length, features: v.manifest.features.length,
        read: typeof v.bytes === 'function' ? v.bytes() : v.bytes };
    });
    const pssFirst = browserPss();
    if (cellArg) await page.selectOption('#cell-size', cellArg).catch(() => {});  // pages without the control: 150 px
    await page.evaluate(() => window.vpmView.settled?.());
    await page.evaluate(() => window.vpmView.benchRotate(20));  // warm-up
    const top = await page.evaluate(() => window.vpmView.benchRotate(120));
    const full = await page.evaluate(() => window.vpmView.benchRotate(120, false));
    await page.evaluate(() => { const a = document.getElementById('table-area'); a.scrollTo(0, a.scrollHeight / 2); });
    await page.evaluate(() => window.vpmView.settled?.());
    const middle = await page.evaluate(() => window.vpmView.benchRotate(120));
    let pssMax = browserPss();
    for (let k = 0; k <= 12; ++k) {
      await page.evaluate((f) => { const a = document.getElementById('table-area'); a.scrollTo(0, f * (a.scrollHeight - a.clientHeight)); }, k / 12);
      await page.evaluate(() => window.vpmView.settled?.());
      pssMax = Math.max(pssMax, browserPss());
    }
    const heap = await page.evaluate(() => performance.memory?.usedJSHeapSize ?? null);
    return { run: r + 1, load_average: load, ...info, first_frame_ms: info.marks['vpm:first-frame'], decoded_ms: info.marks['vpm:decoded'],
      read_at_first_frame: info.read, fps_top: top.fps, fps_middle: middle.fps, fps_top_full_detail: full.fps,
      cells_drawn: top.cells_drawn, pss_first_frame: pssFirst, pss_max_scrolling: pssMax, js_heap_end: heap, console_errors: errors.length };
  } finally {
    await browser.close();
  }
}

const pages = pagesArg.split(',');
const runsOf = pages.map(() => []);
for (let r = 0; r < runs; ++r)
  for (let p = 0; p < pages.length; ++p) runsOf[p].push(await run(pages[p], r));

function summarise(pagePath, rows) {
  const size = dataBytes(pagePath);
  const med = (k) => median(rows.map((r) => r[k]));
  return {
    page: path.resolve(pagePath), page_bytes: size.html, data_folder_bytes: size.folder, layout: size.layout, runs: rows.length,
    viewport: `${width}x${height}`, cell_px: cellArg ? Number(cellArg) : 'fit window', load_average_end: loadAverage(),
    subjects: rows[0].subjects, features: rows[0].features, cells: rows[0].cells, cells_drawn: rows[0].cells_drawn,
    median_first_frame_ms: med('first_frame_ms'), median_decoded_ms: med('decoded_ms'), median_read_at_first_frame: med('read_at_first_frame'),
    median_fps_top: med('fps_top'), median_fps_middle: med('fps_middle'), median_fps_top_full_detail: med('fps_top_full_detail'),
    median_pss_first_frame: med('pss_first_frame'), median_pss_max_scrolling: med('pss_max_scrolling'), rows,
  };
}
const summaries = pages.map((p, i) => summarise(p, runsOf[i]));
const mb = (b) => (b / 1e6).toFixed(1);
console.log('| page (+ folder) | subjects | cells (drawn) | first frame (ms) | read by then | fps top | fps middle | fps full detail | memory first / max (MB) | runs | load |');
console.log('|---|---|---|---|---|---|---|---|---|---|---|');
for (const s of summaries)
  console.log(`| ${mb(s.page_bytes)}${s.data_folder_bytes ? ` + ${mb(s.data_folder_bytes)}` : ''} MB | ${s.subjects} | ${s.cells} (${s.cells_drawn}) | ` +
    `${s.median_first_frame_ms.toFixed(0)} | ${mb(s.median_read_at_first_frame)} MB | ${s.median_fps_top.toFixed(1)} | ` +
    `${s.median_fps_middle.toFixed(1)} | ${s.median_fps_top_full_detail.toFixed(1)} | ` +
    `${mb(s.median_pss_first_frame)} / ${mb(s.median_pss_max_scrolling)} | ${s.runs} | ` +
    `${s.rows.map((r) => r.load_average[0].toFixed(1)).join(', ')} |`);
if (outJson) fs.writeFileSync(outJson, JSON.stringify(pages.length > 1 ? summaries : summaries[0], null, 2) + '\n');
