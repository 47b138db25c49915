// The page's tables (paper Fig. 8): patients and normals, a row per subject (id, group, foci
// counts), a column per feature and kind (value, z) with its colour bar; each cell an empty
// rectangle the one canvas draws into (scene.js).
import { sequentialCss, divergingCss } from './colour.js';
import { fmt } from './plot.js';

/** `text` safe inside HTML. */
export function esc(text) {
  return String(text).replace(/[&<>"']/g, (c) => ({ '&': '&amp;', '<': '&lt;', '>': '&gt;', '"': '&quot;', "'": '&#39;' })[c]);
}

function header(table, columns) {
  const head = table.createTHead().insertRow();
  head.insertCell().textContent = 'subject';
  for (const c of columns) {
    const th = document.createElement('th');
    th.innerHTML = `<div>${esc(c.label)}</div><div class="bar ${c.kind}"></div><div class="bar-labels"></div>` +
      (c.kind === 'z' ? '<div class="bar-note">saturated: in a focus; faded: outside foci</div>' : '<div class="bar-note">&nbsp;</div>');
    th.dataset.kind = c.kind;
    th.dataset.feature = c.feature;
    head.appendChild(th);
  }
}

function row(body, s, columns, features, cells) {
  const tr = body.insertRow();
  tr.dataset.subject = s.id;
  const th = document.createElement('th');
  th.innerHTML = `<div class="sid">${esc(s.id)}</div><div class="group">${esc(s.group)}</div>`;
  if (s.group === 'patient')
    for (const f of features)
      th.innerHTML += `<div class="foci" data-subject="${esc(s.id)}" data-feature="${esc(f.name)}" data-count="${s.foci[f.name]}">` +
        `${s.foci[f.name]} foci (${esc(f.name)})</div>`;
  tr.appendChild(th);
  const list = [];
  columns.forEach((c, ci) => {
    const el = document.createElement('div');
    el.className = 'cell';
    tr.insertCell().appendChild(el);
    list.push({ el, column: ci });
  });
  cells.set(s.index, list);
}

/** Builds the patients' and the normals' tables in `area`; returns subject index -> its cells
 *  ({el, column}). */
export function buildTables(area, { patients, normals, columns, features }) {
  const cells = new Map();
  for (const [title, rows, id] of [['Patients', patients, 'patients'], ['Normals', normals, 'normals']]) {
    const h = document.createElement('h2');
    h.textContent = `${title} (${rows.length})`;
    area.appendChild(h);
    const table = document.createElement('table');
    table.id = id;
    header(table, columns);
    const body = table.createTBody();
    for (const s of rows) row(body, s, columns, features, cells);
    area.appendChild(table);
  }
  return cells;
}

/** Colour bars and their labels in every column header: value ranges per feature, the z scale
 *  around the threshold. */
export function drawBars(ranges, threshold) {
  document.querySelectorAll('th[data-kind]').forEach((th) => {
    const bar = th.querySelector('.bar');
    const labels = th.querySelector('.bar-labels');
    if (th.dataset.kind === 'value') {
      const [lo, hi] = ranges[th.dataset.feature];
      bar.style.background = sequentialCss();
      labels.innerHTML = `<span>${fmt(lo)}</span><span>${fmt(hi)}</span>`;
    } else {
      bar.style.background = divergingCss();
      labels.innerHTML = `<span>\u2264 -${fmt(threshold + 3)}</span><span>|z| < ${fmt(threshold)}</span>` +
        `<span>\u2265 ${fmt(threshold + 3)}</span>`;
      th.title = 'saturated: elements in a focus (a cluster of adjacent elements beyond the threshold vpm compare used); ' +
        'faded: beyond the threshold outside any focus';
    }
  });
}
