// Mouse, wheel and keyboard on the page: dragging (or the arrow keys on a focused cell) turns
// every brain, hovering picks an element (lit in every cell, named in a tooltip kept inside the
// table), a click (or Enter) opens the detail, Escape closes it, Ctrl + wheel (or + and -) zooms;
// the controls in the bar (mode, shell, threshold, cell size, facing foci, zoom).
import { fmt } from './plot.js';

const $ = (sel) => document.querySelector(sel);
const ARROWS = { ArrowLeft: [-1, 0], ArrowRight: [1, 0], ArrowUp: [0, -1], ArrowDown: [0, 1] };

export function interact(app) {
  const { scene, state, area, cohort, model, rowsView, detail } = app;
  const render = app.requestRender;
  const tooltip = $('#tooltip');
  const cellOf = new Map();
  for (const r of app.rows) for (const c of r.cells) cellOf.set(c.el, c);
  cellOf.set(detail.cell.el, detail.cell);
  const cellAt = (target) => cellOf.get(target?.closest?.('.cell')) || null;
  const pick = (cell, x, y) => {
    const f = scene.pick(cell, x, y);
    return f < 0 ? -1 : model.element(app.painter.shellOf(cell.row), f);
  };
  const hideTip = () => { tooltip.hidden = true; };
  const setHover = (e) => {
    if (e === state.hover) return;
    state.hover = e;
    render();
  };

  function showTip(cell, e, x, y) {
    const s = cell.subject, f = cell.column.feature, ids = model.ids;
    const where = `element ${e} (shell ${ids.shellOf(e) + 1}, triangle ${ids.triangleOf(e)})`;
    let text;
    if (s.kind === 'reference') {
      const r = cohort.referenceAt(f, e);
      text = `normals' reference \u00b7 ${where}\n${f} mean ${fmt(r.mean)} \u00b1 ${fmt(r.std)} (${r.n} normals)`;
    } else {
      const cl = cohort.cluster(s, f), focus = cl ? cl[e] : 0;
      text = `${s.id} \u00b7 ${where}\n${f} ${fmt(cohort.values(s, f)[e])}, z ${fmt(cohort.z(s, f)[e])}` +
        `${s.group === 'patient' ? '' : ' (leave-one-out)'}${focus ? `, focus ${focus}` : ''}`;
    }
    tooltip.textContent = `${text}\n${app.regionName(e)}`;
    tooltip.hidden = false;
    // inside the cell's table (or panel) and the window: flipped left or up near an edge
    const box = cell.clip.getBoundingClientRect();
    const w = tooltip.offsetWidth, h = tooltip.offsetHeight;
    const right = Math.min(innerWidth, box.right) - 4, bottom = Math.min(innerHeight, box.bottom) - 4;
    let left = x + 14, top = y + 12;
    if (left + w > right) left = x - 14 - w;
    if (top + h > bottom) top = y - 12 - h;
    tooltip.style.left = `${Math.max(4, left)}px`;
    tooltip.style.top = `${Math.max(4, top)}px`;
  }

  function openAt(cell, e, opener) {
    if (cell.detail || cell.subject.kind === 'reference') return;
    detail.open(cell.row, cell.column.feature, e, { opener });
  }

  // ---- pointer ----------------------------------------------------------------------------
  let drag = null;
  document.addEventListener('pointerdown', (ev) => {
    hideTip();
    const cell = cellAt(ev.target);
    if (!cell) return;
    drag = { x: ev.clientX, y: ev.clientY, moved: 0, cell };
    ev.preventDefault();
    cell.el.focus({ preventScroll: true });
  });
  document.addEventListener('pointermove', (ev) => {
    if (drag && ev.buttons) {
      const dx = ev.clientX - drag.x, dy = ev.clientY - drag.y;
      drag.moved += Math.abs(dx) + Math.abs(dy);
      drag.x = ev.clientX;
      drag.y = ev.clientY;
      scene.rotate(dx, dy);
      hideTip();
      render();
      return;
    }
    const cell = cellAt(ev.target);
    const e = cell && (cell.subject.kind === 'reference' || cohort.ready(cell.subject)) ? pick(cell, ev.clientX, ev.clientY) : -1;
    setHover(e);
    if (e < 0) return hideTip();
    showTip(cell, e, ev.clientX, ev.clientY);
  });
  document.addEventListener('pointerup', (ev) => {
    if (drag && drag.moved < 4) openAt(drag.cell, pick(drag.cell, ev.clientX, ev.clientY), drag.cell.el);
    drag = null;
    hideTip();
  });
  document.documentElement.addEventListener('pointerleave', () => { hideTip(); setHover(-1); });
  document.addEventListener('wheel', (ev) => {
    const cell = cellAt(ev.target);
    if (!cell || !(cell.detail || ev.ctrlKey || ev.metaKey)) return;  // the wheel scrolls the table
    ev.preventDefault();
    scene.zoomBy(Math.exp(-ev.deltaY * 0.0015));
    render();
  }, { passive: false });
  area.addEventListener('scroll', () => { hideTip(); render(); }, { passive: true });
  window.addEventListener('resize', () => { app.fit(); render(); });

  // ---- keyboard ---------------------------------------------------------------------------
  document.addEventListener('keydown', (ev) => {
    if (ev.key === 'Escape') {
      hideTip();
      setHover(-1);
      detail.close();
      return;
    }
    const cell = cellAt(document.activeElement);
    if (!cell || ev.target !== cell.el) return;
    const step = ev.shiftKey ? 40 : 12;
    if (ARROWS[ev.key]) {
      ev.preventDefault();
      scene.rotate(ARROWS[ev.key][0] * step, ARROWS[ev.key][1] * step);
    } else if (ev.key === '+' || ev.key === '=') {
      scene.zoomBy(1.15);
    } else if (ev.key === '-' || ev.key === '_') {
      scene.zoomBy(1 / 1.15);
    } else if (ev.key === 'Enter' || ev.key === ' ') {
      ev.preventDefault();
      const r = cell.el.getBoundingClientRect();
      const e = cell.subject.group === 'patient' ? -1 : pick(cell, r.left + r.width / 2, r.top + r.height / 2);
      openAt(cell, e, cell.el);
      return;
    } else {
      return;
    }
    render();
  });
  area.addEventListener('focusin', render);

  // ---- controls ---------------------------------------------------------------------------
  $('#mode-native').addEventListener('change', () => setMode('native'));
  $('#mode-ball').addEventListener('change', () => setMode('ball'));
  function setMode(mode) {
    state.mode = mode;
    scene.distance = mode === 'ball' ? 4.0 : 4.2;
    for (const r of app.rows) if (r.view) rowsView.face(r, true);  // directions differ in the ball
    render();
  }
  $('#shell').addEventListener('input', (ev) => app.setShell(Number(ev.target.value) - 1));
  $('#threshold').addEventListener('input', (ev) => {
    state.threshold = Number(ev.target.value);
    detail.refresh();
    app.updateLabels();
    render();
  });
  $('#cell-size').addEventListener('change', (ev) => {
    state.size = ev.target.value;
    app.fit();
    render();
  });
  $('#face-foci').addEventListener('change', (ev) => rowsView.faceAll(ev.target.checked));
  for (const r of app.rows) r.el.querySelector('.face')?.addEventListener('click', () => rowsView.face(r, !r.view));
  $('#zoom-in').addEventListener('click', () => { scene.zoomBy(1.25); render(); });
  $('#zoom-out').addEventListener('click', () => { scene.zoomBy(0.8); render(); });
}
