// The rows near the screen and the frames that draw them: an IntersectionObserver keeps the set of
// rows within half a screen of the table's view; their data is loaded (chunks of rows), their
// cells drawn when on screen, and rows far away give their geometry back, so a cohort of a
// thousand subjects costs what the screen shows. Rows can face their strongest focus.
import { viewFrom } from './scene.js';

const KEEP_ROWS = 120;  // rows holding geometry at most (beyond the near ones)

export class Rows {
  constructor(app) {
    this.app = app;
    this.near = new Set();
    this.built = new Set();  // rows that hold geometry
    this.frameRequested = false;
    this.requestRender = this.requestRender.bind(this);
    this.rowOf = new Map(app.rows.map((r) => [r.el, r]));
    this.observer = new IntersectionObserver((entries) => this.changed(entries), { root: app.area, rootMargin: '50% 0px 50% 0px' });
    for (const r of app.rows) this.observer.observe(r.el);
    // before the observer's first report: the rows on screen now
    const box = app.area.getBoundingClientRect();
    for (const r of app.rows) {
      const b = r.el.getBoundingClientRect();
      if (b.bottom > box.top && b.top < box.bottom + 0.5 * box.height) this.near.add(r);
    }
    app.scene.onRest = this.requestRender;
    // the chunks of rows near the screen and of the detail's subject are never dropped (data.js)
    app.store.pinned = (chunk) => chunk === app.state.detail?.subject.chunk || [...this.near].some((r) => r.subject.chunk === chunk);
  }

  changed(entries) {
    for (const en of entries) {
      const row = this.rowOf.get(en.target);
      if (en.isIntersecting) this.near.add(row);
      else this.near.delete(row);
    }
    this.requestRender();
  }

  requestRender() {
    if (this.frameRequested) return;
    this.frameRequested = true;
    requestAnimationFrame(() => {
      this.frameRequested = false;
      this.render();
    });
  }

  /** The cells that may be on screen: those of the near rows that are in the table's view (a row
   *  off screen is not looked into: its content is not laid out, content-visibility: auto, and
   *  asking where its cells are would lay it out every frame), and the detail's. */
  candidates() {
    const out = [];
    const box = this.app.area.getBoundingClientRect();
    for (const r of this.near) {
      const b = r.el.getBoundingClientRect();
      if (b.bottom > box.top && b.top < box.bottom) out.push(...r.cells);
    }
    const d = this.app.detail?.cell;
    if (d && !d.hidden) out.push(d);
    return out;
  }

  /** Draws every cell on screen whose data is here, asks for the rest; returns {drawn, waiting}. */
  render() {
    const { scene, painter, marks, cohort } = this.app;
    const shown = scene.visible(this.candidates());
    const ready = [], missing = new Set();
    for (const v of shown) {
      const ok = painter.prepare(v.cell);
      v.cell.el.classList.toggle('waiting', !ok);
      if (ok) {
        ready.push(v);
        this.built.add(v.cell.row);
        this.faceNow(v.cell.row);
        this.showShell(v.cell.row);
      } else {
        missing.add(v.cell.row.subject);
      }
    }
    const onScreen = [...missing];
    // load the near rows too (a chunk holds several), so that scrolling finds them here
    for (const r of this.near) if (r.subject.kind !== 'reference' && !cohort.ready(r.subject)) missing.add(r.subject);
    if (missing.size) cohort.load([...missing]).then(this.requestRender, this.app.showError);
    const drawn = scene.draw(ready);
    marks.draw(ready);
    this.trim();
    return { drawn, waiting: shown.length - ready.length, missing: onScreen };
  }

  /** Rows far from the screen give their geometry back above KEEP_ROWS. */
  trim() {
    if (this.built.size <= KEEP_ROWS + this.near.size) return;
    for (const r of this.built) {
      if (this.near.has(r)) continue;
      this.app.painter.release(r);
      this.built.delete(r);
      if (this.built.size <= KEEP_ROWS) break;
    }
  }

  /** Resolves after a frame with every cell on screen drawn (data loaded). */
  async firstFrame() {
    for (let i = 0; i < 600; ++i) {
      const { waiting, missing } = this.render();
      if (!waiting) return;
      await this.app.cohort.load(missing);  // the rows on screen; the near ones follow
    }
    throw new Error('the rows on screen did not load');
  }

  /** Row `row` faces its strongest focus (on the focus's outermost shell), or follows the
   *  shared view again. */
  face(row, on) {
    const focus = on ? this.app.cohort.strongestFocus(row.subject) : null;
    const { scene } = this.app;
    if (row.view) scene.own.delete(row.view);
    row.view = null;
    row.shell = null;
    if (focus && focus.face_element >= 0) {
      row.view = { yaw: scene.shared.yaw, pitch: scene.shared.pitch, pending: focus.face_element };
      row.shell = this.app.model.ids.shellOf(focus.face_element);
      scene.own.add(row.view);
    }
    row.el.querySelector('.face')?.setAttribute('aria-pressed', String(!!row.view));
    this.showShell(row);
    this.requestRender();
  }

  /** The row header names the shell a row shows when it is its own. */
  showShell(row) {
    if (row.shownShell === row.shell) return;
    row.shownShell = row.shell;
    const el = row.el.querySelector('.row-shell');
    if (!el) return;
    el.textContent = row.shell === null ? '' : `shows shell ${row.shell + 1} of ${this.app.model.K} (its focus)`;
  }

  /** Points a row's pending view at its focus once its surface is here. */
  faceNow(row) {
    const v = row.view;
    if (!v || v.pending === undefined || !row.surf) return;
    Object.assign(v, viewFrom(this.app.model.elementPoint(row.surf, v.pending).p));
    delete v.pending;
  }

  /** Every patient with foci faces its strongest focus (or none does). */
  faceAll(on) {
    for (const r of this.app.rows) if (r.subject.group === 'patient') this.face(r, on);
  }
}
