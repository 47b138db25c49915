// The detail panel of one subject (opened by clicking a cell, or Enter on it): the picked element's
// value against the normals' distribution (for a normal: the other normals, as its leave-one-out z
// is), the subject's z-map on its own brain (a 3-D view that turns with the table; its picked
// element stays marked whatever the pointer does) and, for patients, voxel slices of its image
// with the z-map over them and its foci table (paper Figs. 8 and 10). Closing it puts back the
// shell it changed and the keyboard focus where it was.
import { drawDistribution, drawSlice, worldToVoxel, fmt } from './plot.js';
import { leaveOneOut } from './cohort.js';
import { esc } from './table.js';
import { viewFrom } from './scene.js';

const byId = (id) => document.getElementById(id);

export class Detail {
  constructor(ctx) {
    Object.assign(this, ctx);  // cohort, model, scene, state, painter, setShell, regionName, requestRender, relayout, showError
    this.panel = byId('detail');
    this.cell = { el: byId('detail-view'), clip: this.panel, detail: true, column: { kind: 'z', feature: '' }, hidden: true };
    this.token = 0;
    byId('detail-close').addEventListener('click', () => this.close());
  }

  /** Opens the detail of row's subject for `feature` at element `e` (-1: the subject's strongest
   *  focus, or no element); `turn`: every brain turns to face the element. */
  open(row, feature, e, { turn = false, opener = null } = {}) {
    const subject = row.subject;
    const foci = subject.foci_table?.[feature];
    if (e < 0 && foci?.length) {
      e = foci[0].peak_element;
      turn = true;
    }
    if (!this.state.detail) this.before = { shell: this.state.shell, opener: opener || document.activeElement };
    this.state.detail = { subject, feature, element: e, row };
    const wasHidden = this.panel.hidden;
    this.panel.hidden = false;
    document.body.classList.add('with-detail');
    Object.assign(this.cell, { row, subject, hidden: false, column: { kind: 'z', feature, label: 'detail' } });
    const k = e >= 0 ? this.model.ids.shellOf(e) : -1;
    if (e >= 0 && row.shell !== null && row.shell !== k) row.shell = null;  // the row shows the element's shell
    if (e >= 0 && k !== this.state.shell) {
      this.setShell(k, { rows: false });
      this.before.setShell = k;
    }
    if (turn && e >= 0) this.face(row, e);
    if (wasHidden) this.relayout(row.el);
    this.refresh();
  }

  /** Turns the shared view (and the row, which then follows it) to face element e. */
  face(row, e) {
    if (row.view) {
      this.scene.own.delete(row.view);
      row.view = null;
      row.shell = null;
      row.el.querySelector('.face')?.setAttribute('aria-pressed', 'false');
    }
    if (!this.cohort.ready(row.subject) && row.subject.kind !== 'reference') return;
    const surf = this.model.surface(row.subject, this.model.ids.shellOf(e), this.state.mode);
    Object.assign(this.scene.shared, viewFrom(this.model.elementPoint(surf, e).p));
  }

  close() {
    if (!this.state.detail) return;
    this.state.detail = null;
    this.panel.hidden = true;
    this.cell.hidden = true;
    document.body.classList.remove('with-detail');
    // the shell the detail moved to goes back, unless the shell was changed since
    if (this.before?.setShell !== undefined && this.state.shell === this.before.setShell) this.setShell(this.before.shell, { rows: false });
    const opener = this.before?.opener;
    this.before = null;
    this.relayout(opener?.closest?.('.row'));
    this.requestRender();
    if (opener?.isConnected && opener.focus) opener.focus();
  }

  /** Redraws everything in the panel for the current state (shell, threshold, element). */
  refresh() {
    const d = this.state.detail;
    if (!d) return;
    const { subject, feature, element: e } = d;
    const ids = this.model.ids;
    byId('detail-title').textContent = `${subject.id} (${subject.group})`;
    const info = byId('detail-info');
    if (e >= 0 && this.cohort.ready(subject)) {
      const value = this.cohort.values(subject, feature)[e], z = this.cohort.z(subject, feature)[e];
      info.textContent = `element ${e}: shell ${ids.shellOf(e) + 1}, triangle ${ids.triangleOf(e)}; ${this.regionName(e)}; ` +
        `${feature} ${fmt(value)}, z ${fmt(z)}` + (this.state.shell !== ids.shellOf(e) ? ' (on another shell than shown)' : '');
    } else {
      info.textContent = e >= 0 ? 'loading\u2026' : 'click on a brain to pick an element';
    }
    const token = ++this.token;
    const later = (p) => p.then(() => token === this.token && this.requestRender()).catch(this.showError);
    later(this.drawPlot(d, token));
    later(this.drawSlices(d, token));
    this.drawFoci(d);
    this.requestRender();
  }

  async drawPlot({ subject, feature, element: e }, token) {
    const canvas = byId('plot');
    canvas.dataset.state = 'pending';
    if (e < 0) {
      canvas.getContext('2d').clearRect(0, 0, canvas.width, canvas.height);
      canvas.setAttribute('aria-label', 'no element picked');
      return;
    }
    const all = await this.cohort.normalValuesAt(feature, e);
    await this.cohort.load([subject]);
    if (token !== this.token) return;
    const ref = this.cohort.referenceAt(feature, e);
    const value = this.cohort.values(subject, feature)[e];
    let mean = ref.mean, std = ref.std, z = this.cohort.z(subject, feature)[e], normals = all, curve;
    if (subject.group === 'patient') {
      curve = `curve: the reference, all ${ref.n} normals (mean ${fmt(mean)} \u00b1 ${fmt(std)})`;
    } else {
      const loo = leaveOneOut(value, ref.mean, ref.std, ref.n);
      ({ mean, std } = loo);
      normals = all.filter((_, i) => this.cohort.normals[i] !== subject);
      curve = `curve: the other ${loo.n} normals, without ${subject.id} (leave-one-out; mean ${fmt(mean)} \u00b1 ${fmt(std)})`;
    }
    const title = `${subject.id} ${feature} ${fmt(value)}, z = ${fmt(z)} (element ${e})`;
    drawDistribution(canvas, { normals, mean, std, value, z, title, curve });
    Object.assign(canvas.dataset, { state: 'drawn', mean: String(mean), std: String(std), z: String(z), value: String(value), normals: String(normals.length) });
    canvas.setAttribute('aria-label', `${title}; ${curve}; histogram of ${normals.length} normals`);
  }

  async drawSlices({ subject, feature, element: e }, token) {
    const box = byId('slices');
    const sl = subject.slices?.[feature];
    box.hidden = !sl;
    if (!sl) return;
    await this.cohort.loadDetail(subject);
    if (token !== this.token) return;
    const image = this.cohort.store.array(sl.image), zmap = this.cohort.store.array(sl.z);
    const at = e >= 0 ? worldToVoxel(sl.affine, this.cohort.centre(subject, e)) : sl.dims.map((n) => (n - 1) / 2);
    for (const axis of [2, 1, 0]) {
      const canvas = byId(`slice-${axis}`);
      const edges = drawSlice(canvas, sl, image, zmap, axis, at, this.state.threshold);
      canvas.dataset.edges = `${edges.left}${edges.right}${edges.top}${edges.bottom}`;
      canvas.setAttribute('aria-label', `${['sagittal', 'coronal', 'axial'][axis]} slice of ${sl.image_source}: ` +
        `${edges.left} on the left, ${edges.right} on the right, ${edges.top} at the top`);
    }
    byId('slices-note').textContent = `${sl.image_source} with the z-map (|z| \u2265 ${fmt(this.state.threshold)}) on the ` +
      `patient's own grid` + (sl.step > 1 ? ` (voxels subsampled by ${sl.step})` : '') + '; letters: left/right, anterior/posterior, superior/inferior';
  }

  drawFoci({ subject, feature, element: e, row }) {
    const table = byId('foci-table');
    const rows = subject.foci_table?.[feature];
    table.hidden = !rows;
    if (!rows) return;
    const cl = e >= 0 && this.cohort.ready(subject) ? this.cohort.cluster(subject, feature) : null;
    const chosen = cl ? cl[e] : 0;
    table.innerHTML = '<caption>foci (Enter or a click shows one)</caption>' +
      '<tr><th>focus</th><th>mm\u00b3</th><th>peak z</th><th>centroid (mm)</th><th>region</th></tr>' +
      rows.map((r) => `<tr data-focus="${r.id}" tabindex="0" aria-selected="${r.id === chosen}"` +
        ` class="${r.id === chosen ? 'chosen' : ''}" aria-label="focus ${r.id}: ${fmt(r.volume_mm3)} mm\u00b3, peak z ${fmt(r.peak_z)}` +
        `${r.region ? ', ' + esc(r.region) : ''}"><td>${r.id}</td><td>${fmt(r.volume_mm3)}</td><td>${fmt(r.peak_z)}</td>` +
        `<td>${r.centroid.map((v) => fmt(v)).join(', ')}</td><td>${esc(r.region)}</td></tr>`).join('');
    table.querySelectorAll('tr[data-focus]').forEach((tr, i) => {
      const go = () => {
        const peak = rows[i].peak_element;
        if (peak >= 0) this.open(row, feature, peak, { turn: true });
        table.querySelector(`tr[data-focus="${rows[i].id}"]`)?.focus();
      };
      tr.addEventListener('click', go);
      tr.addEventListener('keydown', (ev) => {
        if (ev.key === 'Enter' || ev.key === ' ') {
          ev.preventDefault();
          go();
        }
      });
    });
  }
}
