// vpm's collective view (paper Figs. 8-10): subjects as rows, features as columns, each cell a
// live 3-D view of the subject's brain (native shape) or of the common ball coloured by the
// feature or its z-score against the normals. One canvas, one shared view for all cells.
// This script runs before the page's data is parsed: it lays out the page at once (title,
// controls, an empty row per subject, a loading indicator), then reads the data it needs for the
// rows on screen and draws them; the other rows follow as they come into view (docs/view.md).
import { readManifest, Store } from './data.js';
import { Cohort } from './cohort.js';
import { SurfaceModel } from './geometry.js';
import { TableScene, BufferAttribute } from './scene.js';
import { CellPainter } from './cells.js';
import { Marks } from './marks.js';
import { Detail } from './detail.js';
import { buildTables, fitCells, drawBars } from './table.js';
import { buildLegend } from './legend.js';
import { Rows } from './rows.js';
import { interact } from './interaction.js';
import { fmt, thousands } from './plot.js';
import { testHooks } from './hooks.js';

performance.mark('vpm:script');
const $ = (sel) => document.querySelector(sel);
const manifest = readManifest();
const K = manifest.shells;
const features = manifest.features;
const store = new Store(manifest);
const cohort = new Cohort(manifest, store);
// read the base data and the first rows (the top of the table) while the page is laid out
const base = store.chunk('base');
if (cohort.subjects.length) store.chunk(cohort.subjects[0].chunk).catch(() => {});
const columns = features.flatMap((f) => [
  { kind: 'value', feature: f.name, label: `${f.name} (${f.normalisation === 'proportional' ? 'proportional: 1 = subject mean' : 'as sampled'})` },
  { kind: 'z', feature: f.name, label: `${f.name} z-score` },
]);
const state = { mode: 'native', shell: K - 1, threshold: features[0]?.threshold ?? 3, hover: -1, detail: null, size: 'auto' };

// ---- the page at once, before any data --------------------------------------------------------
document.title = manifest.title;
$('#title').textContent = manifest.title;
$('#summary').textContent = `${cohort.patients.length} patients, ${cohort.normals.length} normals; ` +
  `${thousands(manifest.elements)} elements (level ${manifest.definition.level}, ${K} shells)` +
  (manifest.compared ? `; compared at level ${manifest.compared.level} (${thousands(manifest.compared.elements)} elements)` : '');
const shellInput = $('#shell');
shellInput.max = String(K);
shellInput.value = String(K);
$('#threshold').value = String(state.threshold);
const loading = $('#loading');
loading.textContent = `Loading ${thousands(cohort.subjects.length)} subjects\u2026`;
buildLegend($('#legend'), manifest);
const area = $('#table-area');
const rows = buildTables(area, { cohort, columns, features });
const fit = () => {
  const got = fitCells(area, rows, columns, state.size);
  for (const r of rows) for (const c of r.cells) c.clipTop = r.group.heads[0];
  return got;
};
fit();
updateLabels();
document.body.classList.add('live');  // the controls show only now, set to the data's values

function updateLabels() {
  drawBars(features, state.threshold);
  $('#threshold-value').textContent = fmt(state.threshold);
  const outer = state.shell === K - 1;
  $('#shell-value').textContent = `${state.shell + 1} of ${K}${outer ? ' (outer)' : ''}`;
  shellInput.setAttribute('aria-valuetext', `shell ${state.shell + 1} of ${K}${outer ? ', the outer one' : ''}`);
  document.querySelectorAll('.spread-max').forEach((el) => {
    el.textContent = features.map((f) => `${fmt(f.spread_range[1])}${features.length > 1 ? ` (${f.name})` : ''}`).join(', ');
  });
}

let app = null;
start().catch(showError);

function showError(e) {
  console.error(e);
  loading.hidden = false;
  loading.classList.add('error');
  loading.setAttribute('role', 'alert');
  loading.textContent = `The page could not show the cohort: ${e.message}`;
}

async function start() {
  await base;
  performance.mark('vpm:decoded');
  const model = new SurfaceModel(manifest, store);
  model.buildCorners();
  const scene = new TableScene($('#gl'));
  scene.drawIndex = new BufferAttribute(model.drawIndex, 1);
  scene.coarseIndex = new BufferAttribute(model.coarseIndex, 1);
  const painter = new CellPainter({ cohort, model, scene, state });
  const marks = new Marks($('#marks'), { scene, model, painter, state });
  for (const r of rows) for (const c of r.cells) Object.assign(c, { clip: area, row: r, subject: r.subject });
  const regionOf = manifest.regions ? store.array(manifest.regions.buffer) : null;
  const regionName = (e) => {
    if (!regionOf) return '';
    const id = regionOf[e];
    return id ? manifest.regions.names[String(id)] || `label ${id}` : 'outside the atlas';
  };
  app = { manifest, store, cohort, model, scene, painter, marks, state, rows, area, columns, regionName, fit, showError };
  app.rowsView = new Rows(app);
  app.requestRender = app.rowsView.requestRender;
  app.setShell = setShell;
  app.detail = new Detail({ ...app, setShell, relayout: relayout, requestRender: app.requestRender });
  app.updateLabels = updateLabels;
  interact(app);
  if ($('#face-foci').checked) app.rowsView.faceAll(true);
  await app.rowsView.firstFrame();
  performance.mark('vpm:first-frame');
  loading.hidden = true;
  area.setAttribute('aria-busy', 'false');
  window.vpmView = testHooks(app);
  document.body.dataset.ready = 'true';
}

/** Shows shell k (0-based); `rows`: rows facing a focus on a shell of their own follow too (the
 *  slider), else they keep theirs (the detail moving to its element's shell). */
function setShell(k, { rows: all = true } = {}) {
  if (all) for (const r of rows) r.shell = null;
  if (k === state.shell) return app.requestRender();
  state.shell = k;
  shellInput.value = String(k + 1);
  app.detail.refresh();
  updateLabels();
  app.requestRender();
}

/** Refits the cells after the table's width changed (the detail panel opened or closed),
 *  keeping `keep` (the row in use) on screen. */
function relayout(keep) {
  fit();
  keep?.scrollIntoView({ block: 'nearest' });
  app.requestRender();
}
