// vpm's collective view (paper Figs. 8-10): subjects as rows, features as columns, each cell a
// live 3-D view of the subject's brain (native shape) or of the common ball coloured by the
// feature or its z-score against the normals. One canvas, one camera for all cells.
import { loadPageData } from './data.js';
import { SurfaceModel } from './geometry.js';
import { ElementIndex } from './elements.js';
import { TableScene, BufferAttribute } from './scene.js';
import { Detail } from './detail.js';
import { sequential, diverging, faded, robustRange, HIGHLIGHT } from './colour.js';
import { buildTables, drawBars } from './table.js';
import { fmt } from './plot.js';

performance.mark('vpm:script');
const { manifest, array, bytes } = loadPageData();
performance.mark('vpm:decoded');

const model = new SurfaceModel(manifest, array);
const ids = new ElementIndex(manifest);
const T = manifest.triangles;
const K = manifest.shells;
const features = manifest.features;
const subjects = manifest.subjects.map((s, i) => ({ ...s, index: i }));
const columns = features.flatMap((f) => [
  { kind: 'value', feature: f.name, label: `${f.name} (${f.normalisation})` },
  { kind: 'z', feature: f.name, label: `${f.name} z-score` },
]);
const regionOf = manifest.regions ? array(manifest.regions.buffer) : null;
const ranges = Object.fromEntries(features.map((f) => [f.name,
  robustRange(subjects.filter((s) => s.group !== 'patient').map((s) => array(s.values[f.name])))]));

const state = {
  mode: 'native', shell: K - 1, threshold: features[0]?.threshold ?? 3,
  highlight: -1, detail: null, dirty: true,
};

// ---- page structure -------------------------------------------------------------------------
const $ = (sel) => document.querySelector(sel);
document.title = manifest.title;
$('#title').textContent = manifest.title;
const patients = subjects.filter((s) => s.group === 'patient');
const normals = subjects.filter((s) => s.group !== 'patient');
$('#summary').textContent = `${patients.length} patients, ${normals.length} normals; ` +
  `${manifest.elements.toLocaleString()} canonical elements (level ${manifest.definition.level}, ` +
  `${K} shells); reference from ${features.map((f) => `${f.reference_subjects} normals (${f.name})`).join(', ')}`;
const shellInput = $('#shell');
shellInput.max = String(K);
shellInput.value = String(K);
$('#threshold').value = String(state.threshold);

const area = $('#table-area');
const scene = new TableScene($('#gl'));

const pending = buildTables(area, { patients, normals, columns, features });

// ---- geometry and colours -------------------------------------------------------------------
const attrs = subjects.map(() => ({ position: null, normal: null }));
let drawIndex = null;
function setSurfaces() {
  let ball = null;
  subjects.forEach((s, i) => {
    const surf = state.mode === 'ball' ? (ball ||= model.surface(0, state.shell, 'ball')) : model.surface(i, state.shell, 'native');
    const a = attrs[i];
    if (!a.position) {
      a.position = new BufferAttribute(surf.pos, 3);
      a.normal = new BufferAttribute(surf.nor, 3);
    } else {
      a.position.array.set(surf.pos);
      a.normal.array.set(surf.nor);
      a.position.needsUpdate = a.normal.needsUpdate = true;
    }
  });
  for (const c of scene.cells) c.geometry.boundingSphere = null;
}
setSurfaces();
drawIndex = new BufferAttribute(model.drawIndex, 1);
scene.coarseIndex = new BufferAttribute(model.coarseIndex, 1);
const cornerCount = model.corners.length;
for (const [i, list] of pending)
  for (const { el, column } of list)
    scene.addCell(el, area, drawIndex, attrs[i].position, attrs[i].normal, new Uint8Array(cornerCount * 3),
      { subject: subjects[i], column: columns[column] });

const tmp = [0, 0, 0];
function colourOf(cell, e) {
  if (e === state.highlight) return HIGHLIGHT;
  const s = cell.subject, c = cell.column;
  if (c.kind === 'value') {
    const [lo, hi] = ranges[c.feature];
    return sequential(array(s.values[c.feature])[e], lo, hi, tmp);
  }
  return zColour(s, c.feature, e, state.threshold, tmp);
}
/** z colour of element e: saturated in a patient's foci, faded elsewhere beyond the threshold. */
function zColour(s, feature, e, threshold, out) {
  const z = array(s.z[feature])[e];
  diverging(z, threshold, threshold + 3, out);
  const inFocus = s.cluster?.[feature] && array(s.cluster[feature])[e] > 0;
  return !inFocus && Math.abs(z) >= threshold ? faded(out) : out;
}
/** Colours element triangle t of the shown shell in `cell` (all its corners). */
function paintElement(cell, t) {
  const col = colourOf(cell, ids.at(state.shell, t));
  const a = cell.geometry.attributes.color.array;
  const r = Math.round(col[0] * 255), g = Math.round(col[1] * 255), b = Math.round(col[2] * 255);
  for (let j = model.cornerStart[t]; j < model.cornerStart[t + 1]; ++j) {
    a[3 * j] = r;
    a[3 * j + 1] = g;
    a[3 * j + 2] = b;
  }
}
function recolour(cell) {
  for (let t = 0; t < T; ++t) paintElement(cell, t);
  cell.geometry.attributes.color.needsUpdate = true;
}
function recolourAll() { scene.cells.forEach(recolour); }
recolourAll();

function setHighlight(e) {
  if (e === state.highlight) return;
  const old = state.highlight;
  state.highlight = e;
  for (const id of [old, e]) {
    if (id < 0 || ids.shellOf(id) !== state.shell) continue;
    const [first, end] = ids.drawn(id);
    for (const cell of scene.cells) {
      for (let t = first; t < end; ++t) paintElement(cell, t);
      cell.geometry.attributes.color.needsUpdate = true;
    }
  }
  requestRender();
}

// ---- colour bars ----------------------------------------------------------------------------
function updateBars() {
  drawBars(ranges, state.threshold);
  $('#threshold-value').textContent = fmt(state.threshold);
  $('#shell-value').textContent = `${state.shell + 1} of ${K}` + (state.shell === K - 1 ? ' (outer)' : '');
}
updateBars();

// ---- rendering ------------------------------------------------------------------------------
let frameRequested = false;
function requestRender() {
  if (frameRequested) return;
  frameRequested = true;
  requestAnimationFrame(() => {
    frameRequested = false;
    scene.render();
  });
}
window.addEventListener('resize', requestRender);
scene.onRest = requestRender;
area.addEventListener('scroll', requestRender, { passive: true });

// ---- interaction ----------------------------------------------------------------------------
const tooltip = $('#tooltip');
const detail = new Detail({ manifest, array, model, scene, state, features, subjects, regionName, requestRender, area, drawIndex, zColour, setShell: (k) => setShell(k) });
function regionName(e) {
  if (!regionOf) return '';
  const id = regionOf[e];
  if (!id) return 'outside the atlas';
  return manifest.regions.names[String(id)] || `label ${id}`;
}
function cellAt(target) {
  const el = target.closest && target.closest('.cell');
  return el ? scene.cells.find((c) => c.el === el) : null;
}
function pickElement(cell, x, y) {
  const f = scene.pick(cell, x, y);
  return f < 0 ? -1 : model.element(state.shell, f);
}
let drag = null;
document.addEventListener('pointerdown', (ev) => {
  const cell = cellAt(ev.target);
  if (!cell) return;
  drag = { x: ev.clientX, y: ev.clientY, moved: 0, cell };
  ev.preventDefault();
});
document.addEventListener('pointermove', (ev) => {
  if (drag && ev.buttons) {
    const dx = ev.clientX - drag.x, dy = ev.clientY - drag.y;
    drag.moved += Math.abs(dx) + Math.abs(dy);
    drag.x = ev.clientX;
    drag.y = ev.clientY;
    scene.rotate(dx, dy);
    tooltip.hidden = true;
    requestRender();
    return;
  }
  const cell = cellAt(ev.target);
  if (!cell) {
    tooltip.hidden = true;
    return setHighlight(-1);
  }
  const e = pickElement(cell, ev.clientX, ev.clientY);
  setHighlight(e);
  if (e < 0) {
    tooltip.hidden = true;
    return;
  }
  const s = cell.subject, fe = cell.column.feature;
  tooltip.hidden = false;
  tooltip.style.left = `${ev.clientX + 14}px`;
  tooltip.style.top = `${ev.clientY + 10}px`;
  const focus = s.cluster?.[fe] ? array(s.cluster[fe])[e] : 0;
  tooltip.textContent = `${s.id} \u00b7 element ${e} (shell ${ids.shellOf(e) + 1}, triangle ${ids.triangleOf(e)})\n` +
    `${fe} ${fmt(array(s.values[fe])[e])}, z ${fmt(array(s.z[fe])[e])}${focus ? `, focus ${focus}` : ''}\n${regionName(e)}`;
});
document.addEventListener('pointerup', (ev) => {
  if (drag && drag.moved < 4) {
    const e = pickElement(drag.cell, ev.clientX, ev.clientY);
    detail.open(drag.cell.subject, drag.cell.column.feature, e);
  }
  drag = null;
});

$('#mode-native').addEventListener('change', () => setMode('native'));
$('#mode-ball').addEventListener('change', () => setMode('ball'));
function setMode(mode) {
  state.mode = mode;
  scene.distance = mode === 'ball' ? 4.0 : 4.2;
  scene.placeCamera();
  setSurfaces();
  requestRender();
}
shellInput.addEventListener('input', () => setShell(Number(shellInput.value) - 1));
/** Shows shell k (0-based) in every cell. */
function setShell(k) {
  if (k === state.shell) return;
  state.shell = k;
  shellInput.value = String(k + 1);
  setSurfaces();
  recolourAll();
  detail.refresh();
  updateBars();
  requestRender();
}
$('#threshold').addEventListener('input', (ev) => {
  state.threshold = Number(ev.target.value);
  recolourAll();
  detail.refresh();
  updateBars();
  requestRender();
});

// ---- first frame, measurements and test hooks -----------------------------------------------
scene.render();
performance.mark('vpm:first-frame');
const marks = () => Object.fromEntries(performance.getEntriesByType('mark').map((m) => [m.name, m.startTime]));
/** Rotates the camera by a small step each animation frame for `frames` frames; resolves to
 *  the frame rate measured between the first and the last frame. `lod` false: full surfaces
 *  while turning too. */
function benchRotate(frames = 60, lod = true) {
  scene.lod = lod;
  return new Promise((resolve) => {
    let n = 0, t0 = 0, drawn = 0;
    function step(t) {
      if (n === 1) t0 = t;
      scene.rotate(3, 0);
      drawn = scene.render();
      if (++n <= frames) return requestAnimationFrame(step);
      scene.lod = true;
      resolve({ frames: frames - 1, seconds: (t - t0) / 1000, fps: ((frames - 1) * 1000) / (t - t0), cells_drawn: drawn });
    }
    requestAnimationFrame(step);
  });
}
window.vpmView = {
  manifest, state, scene, model, detail, bytes, marks, benchRotate, array,
  cells: () => scene.cells.map((c, i) => ({ i, subject: c.subject.id, column: c.column.label, rect: c.el.getBoundingClientRect().toJSON() })),
  pixels: (i) => scene.cellPixels(scene.cells[i]),
  camera: () => scene.cameraState(),
  pick: (i, x, y) => pickElement(scene.cells[i], x, y),
};
document.body.dataset.ready = 'true';
