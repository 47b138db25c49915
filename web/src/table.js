// The page's tables (paper Fig. 8): patients, then normals, a row per subject (id, group, foci
// counts) and a column per feature and kind (value, z) with its colour bar in a sticky header.
// Rows flow into as many lanes side by side as the window holds (sized by fitCells), so a wide
// window shows more subjects instead of empty space. Each cell is an empty, focusable rectangle
// that the one canvas draws into (scene.js). The patients' section starts with the normals'
// reference (mean and spread) as a row: the normals in one line, whatever their number.
import { sequentialCss, divergingCss, spreadCss } from './colour.js';
import { fmt } from './plot.js';

/** `text` safe inside HTML. */
export function esc(text) {
  return String(text).replace(/[&<>"']/g, (c) => ({ '&': '&amp;', '<': '&lt;', '>': '&gt;', '"': '&quot;', "'": '&#39;' })[c]);
}

const HEAD = 124;   // row header width (px), as in style.css
const GAP = 4;      // between cells
const LANE_GAP = 22;

function header(columns) {
  const head = document.createElement('div');
  head.className = 'colhead';
  head.innerHTML = '<div class="rowhead">subject</div>' + columns.map((c) =>
    `<div class="colbox" data-kind="${c.kind}" data-feature="${esc(c.feature)}">` +
    `<div class="collabel">${esc(c.label)}</div><div class="bar" aria-hidden="true"></div><div class="bar-labels"></div></div>`).join('');
  return head;
}

function cellElement(label) {
  const el = document.createElement('div');
  el.className = 'cell';
  el.tabIndex = 0;
  el.setAttribute('role', 'application');  // takes the arrow keys (they turn the brains)
  el.setAttribute('aria-roledescription', '3-D brain view');
  el.setAttribute('aria-label', label);
  return el;
}

const HINT = 'drag or arrow keys turn every brain, Ctrl+wheel or + and - zoom, Enter opens the detail';

function subjectRow(s, columns, features) {
  const row = document.createElement('div');
  row.className = `row ${s.group}`;
  row.setAttribute('role', 'group');
  row.dataset.subject = s.id;
  const count = (n) => `${n} ${n === 1 ? 'focus' : 'foci'}`;
  const foci = s.group === 'patient' ? features.map((f) => `${count(s.foci[f.name])} (${f.name})`).join(', ') : '';
  row.setAttribute('aria-label', `${s.id}, ${s.group}${foci ? ', ' + foci : ''}`);
  let head = `<div class="rowhead"><div class="sid">${esc(s.id)}</div><div class="group">${esc(s.group)}</div>`;
  if (s.group === 'patient') {
    for (const f of features)
      head += `<div class="foci" data-subject="${esc(s.id)}" data-feature="${esc(f.name)}" data-count="${s.foci[f.name]}">` +
        `${count(s.foci[f.name])} (${esc(f.name)})</div>`;
    if (features.some((f) => s.foci_table?.[f.name]?.length))
      head += `<button class="face" type="button" aria-pressed="false" aria-label="${esc(s.id)}: turn this row to face its strongest focus">face focus</button>` +
        '<div class="row-shell"></div>';
  }
  row.innerHTML = head + '</div>';
  const cells = columns.map((c) => {
    const el = cellElement(`${s.id} (${s.group}), ${c.label}: ${HINT}`);
    row.appendChild(el);
    return { el, column: c };
  });
  return { el: row, subject: s, cells, view: null, shell: null };
}

function referenceRow(cohort, columns) {
  const n = cohort.normals.length;
  const row = document.createElement('div');
  row.className = 'row reference';
  row.setAttribute('role', 'group');
  row.setAttribute('aria-label', `the normals' reference: mean and spread of ${n} normals`);
  row.innerHTML = `<div class="rowhead" title="the normals in one row: their mean on their mean shape (value columns) and their ` +
    `spread, the standard deviation (z columns); every normal is listed under Normals"><div class="sid">reference</div>` +
    `<div class="group">${n} normals: mean; spread (sd)</div><div class="ref-scale"><span class="spread-bar" style="background:${spreadCss()}"></span> ` +
    `0 to <span class="spread-max"></span></div></div>`;
  const cells = columns.map((c) => {
    const what = c.kind === 'value' ? `mean of the ${n} normals` : `spread (standard deviation) of the ${n} normals`;
    const el = cellElement(`reference, ${c.feature} ${what} on their mean shape: ${HINT}`);
    row.appendChild(el);
    return { el, column: c, spread: c.kind === 'z' };
  });
  return { el: row, subject: cohort.reference, cells, view: null, shell: null };
}

/** Builds both sections in `area`; returns every row ({el, subject, cells, group}) in order. */
export function buildTables(area, { cohort, columns, features }) {
  const rows = [];
  const sections = [['Patients', cohort.patients, 'patients'], ['Normals', cohort.normals, 'normals']];
  for (const [title, list, id] of sections) {
    const section = document.createElement('section');
    section.className = 'cohort-group';
    section.id = id;
    section.setAttribute('aria-label', `${title}: ${list.length}`);
    const h = document.createElement('h2');
    h.textContent = `${title} (${list.length})`;
    const grid = document.createElement('div');
    grid.className = 'grid';
    section.append(h, grid);
    area.appendChild(section);
    const group = { id, grid, heads: [] };
    if (id === 'patients') {
      const r = referenceRow(cohort, columns);
      grid.appendChild(r.el);
      rows.push({ ...r, group });
    }
    for (const s of list) {
      const r = subjectRow(s, columns, features);
      grid.appendChild(r.el);
      rows.push({ ...r, group });
    }
    group.columns = columns;
  }
  return rows;
}

/** Sizes the cells to the window: `size` 'auto' (about 3.4 rows in the table's height, lanes to
 *  fill its width) or a width in px; repeats the sticky header once per lane. Returns the size. */
export function fitCells(area, rows, columns, size) {
  const style = getComputedStyle(area);
  const width = area.clientWidth - parseFloat(style.paddingLeft) - parseFloat(style.paddingRight);
  const height = area.clientHeight;
  const n = columns.length;
  let cell, lanes;
  if (size === 'auto') {
    const target = Math.max(120, Math.min(480, (height - 90) / 3.4));
    const fitting = (l) => Math.floor(((width + LANE_GAP) / l - LANE_GAP - HEAD) / n - GAP);  // cells filling l lanes
    lanes = Math.max(1, Math.floor((width + LANE_GAP) / (HEAD + n * (target + GAP) + LANE_GAP)));
    if (fitting(lanes + 1) >= 0.8 * target) ++lanes;  // one lane more of cells a little smaller
    cell = Math.max(90, Math.min(Math.round(1.35 * target), fitting(lanes)));
  } else {
    cell = Number(size);
    lanes = Math.max(1, Math.floor((width + LANE_GAP) / (HEAD + n * (cell + GAP) + LANE_GAP)));
  }
  area.style.setProperty('--cell', `${cell}px`);
  area.style.setProperty('--lanes', String(lanes));
  const groups = new Set(rows.map((r) => r.group));
  for (const g of groups) {
    while (g.heads.length < lanes) {
      const h = header(g.columns);
      g.grid.insertBefore(h, g.grid.children[g.heads.length] || null);
      g.heads.push(h);
    }
    while (g.heads.length > lanes) g.heads.pop().remove();
  }
  return { cell, lanes };
}

/** Colour bars and their labels in every column header: value ranges per feature, the z scale
 *  around the threshold. */
export function drawBars(features, threshold) {
  const range = Object.fromEntries(features.map((f) => [f.name, f.range]));
  document.querySelectorAll('.colbox[data-kind]').forEach((box) => {
    const bar = box.querySelector('.bar');
    const labels = box.querySelector('.bar-labels');
    if (box.dataset.kind === 'value') {
      const [lo, hi] = range[box.dataset.feature];
      bar.style.background = sequentialCss();
      labels.innerHTML = `<span>${fmt(lo)}</span><span>${fmt(hi)}</span>`;
      box.title = `normalised ${box.dataset.feature} from ${fmt(lo)} to ${fmt(hi)} (2nd to 98th percentile of the normals)`;
    } else {
      bar.style.background = divergingCss();
      labels.innerHTML = `<span>\u2264 -${fmt(threshold + 3)}</span><span>|z| < ${fmt(threshold)}</span>` +
        `<span>\u2265 ${fmt(threshold + 3)}</span>`;
      box.title = 'saturated: elements in a focus (a cluster of adjacent elements beyond the threshold vpm compare used); ' +
        'faded: beyond the threshold outside any focus';
    }
  });
}
