// The detail panel of one subject (opened by clicking a cell): the picked element's value
// against the normals' distribution, the subject's z-map on its own brain (a 3-D view that turns
// with the table) and, for patients, voxel slices of its image with the z-map over them and the
// table of its foci in native space (paper Figs. 8 and 10).
import { HIGHLIGHT } from './colour.js';
import { drawDistribution, drawSlice, worldToVoxel, fmt } from './plot.js';
import { esc } from './table.js';

export class Detail {
  constructor(ctx) {
    Object.assign(this, ctx);
    this.panel = document.getElementById('detail');
    this.view = document.getElementById('detail-view');
    this.cell = null;
    document.getElementById('detail-close').addEventListener('click', () => this.close());
  }

  /** Opens the detail of `subject` for `feature` at element `e` (-1: the subject's strongest
   *  focus, or no element). */
  open(subject, feature, e, { turn = false } = {}) {
    const foci = subject.foci_table?.[feature];
    if (e < 0 && foci?.length) {
      e = foci[0].peak_element;
      turn = true;
    }
    this.keepCamera = !turn;
    this.state.detail = { subject, feature, element: e };
    this.panel.hidden = false;
    document.body.classList.add('with-detail');
    this.attach(subject);
    // turn every brain to face the element (patients: from its native centre)
    if (e >= 0 && subject.centres) {
      const c = this.array(subject.centres), m = this.model.centres[subject.index];
      if (!this.keepCamera) this.scene.lookFrom([c[3 * e] - m[0], c[3 * e + 1] - m[1], c[3 * e + 2] - m[2]]);
    }
    // show the picked element's shell, so that a focus deep inside is seen on the brains
    const k = e >= 0 ? this.model.ids.shellOf(e) : -1;
    if (e >= 0 && k !== this.state.shell) this.setShell(k);
    else this.refresh();
    this.requestRender();
  }

  close() {
    this.state.detail = null;
    this.panel.hidden = true;
    document.body.classList.remove('with-detail');
    if (this.cell) this.cell.hidden = true;
    this.requestRender();
  }

  attach(subject) {
    const a = this.scene.cells.find((c) => c.subject === subject && c.column.kind === 'z');
    if (!this.cell) {
      this.cell = this.scene.addCell(this.view, this.panel, this.drawIndex, a.geometry.attributes.position,
        a.geometry.attributes.normal, new Uint8Array(this.model.corners.length * 3), { subject, column: { kind: 'z', feature: a.column.feature, label: 'detail' } });
    } else {
      this.cell.geometry.setAttribute('position', a.geometry.attributes.position);
      this.cell.geometry.setAttribute('normal', a.geometry.attributes.normal);
      this.cell.coarse = this.scene.coarseOf(this.cell.geometry);
      this.cell.subject = subject;
    }
    this.cell.hidden = false;
  }

  /** Redraws everything in the panel for the current state (shell, threshold, element). */
  refresh() {
    const d = this.state.detail;
    if (!d) return;
    const { subject, feature } = d;
    const e = d.element;
    const T = this.manifest.triangles;  // drawn triangles per shell
    const z = this.array(subject.z[feature]);
    const value = this.array(subject.values[feature]);
    // the 3-D view: z on the subject's own brain, the picked element highlighted
    const col = this.cell.geometry.attributes.color.array;
    const tmp = [0, 0, 0];
    const m = this.model;
    for (let t = 0; t < T; ++t) {
      const el = this.model.ids.at(this.state.shell, t);
      const c = el === e ? HIGHLIGHT : this.zColour(subject, feature, el, this.state.threshold, tmp);
      for (let j = m.cornerStart[t]; j < m.cornerStart[t + 1]; ++j)
        for (let ch = 0; ch < 3; ++ch) col[3 * j + ch] = Math.round(c[ch] * 255);
    }
    this.cell.geometry.attributes.color.needsUpdate = true;
    document.getElementById('detail-title').textContent = `${subject.id} (${subject.group})`;
    const info = document.getElementById('detail-info');
    if (e >= 0) {
      info.textContent = `element ${e}: shell ${this.model.ids.shellOf(e) + 1}, triangle ${this.model.ids.triangleOf(e)}; ${this.regionName(e)}; ` +
        `${feature} ${fmt(value[e])}, z ${fmt(z[e])}` + (this.state.shell !== this.model.ids.shellOf(e) ? ' (on another shell than shown)' : '');
    } else {
      info.textContent = 'click on a brain to pick an element';
    }
    this.drawPlot(d);
    this.drawSlices(d);
    this.drawFoci(d);
  }

  drawPlot({ subject, feature, element: e }) {
    const canvas = document.getElementById('plot');
    if (e < 0) {
      canvas.getContext('2d').clearRect(0, 0, canvas.width, canvas.height);
      return;
    }
    const ref = this.manifest.reference[feature];
    const normals = this.subjects.filter((s) => s.group !== 'patient').map((s) => this.array(s.values[feature])[e]);
    drawDistribution(canvas, {
      normals, mean: this.array(ref.mean)[e], std: this.array(ref.std)[e],
      value: this.array(subject.values[feature])[e], z: this.array(subject.z[feature])[e], label: `${subject.id} ${feature}`,
    });
  }

  drawSlices({ subject, feature, element: e }) {
    const box = document.getElementById('slices');
    const sl = subject.slices?.[feature];
    box.hidden = !sl;
    if (!sl) return;
    const image = this.array(sl.image);
    const zmap = this.array(sl.z);
    let at;
    if (e >= 0) {
      const c = this.array(subject.centres);
      at = worldToVoxel(sl.affine, [c[3 * e], c[3 * e + 1], c[3 * e + 2]]);
    } else {
      at = sl.dims.map((n) => (n - 1) / 2);
    }
    for (const axis of [2, 1, 0])
      drawSlice(document.getElementById(`slice-${axis}`), sl, image, zmap, axis, at, this.state.threshold);
    document.getElementById('slices-note').textContent =
      `${sl.image_source} with the z-map (|z| \u2265 ${fmt(this.state.threshold)}) on the patient's own grid` +
      (sl.step > 1 ? ` (voxels subsampled by ${sl.step})` : '');
  }

  drawFoci({ subject, feature }) {
    const table = document.getElementById('foci-table');
    const rows = subject.foci_table?.[feature];
    table.hidden = !rows;
    if (!rows) return;
    table.innerHTML = '<tr><th>focus</th><th>mm\u00b3</th><th>peak z</th><th>centroid (mm)</th><th>region</th></tr>' +
      rows.map((r) => `<tr data-focus="${r.id}"><td>${r.id}</td><td>${fmt(r.volume_mm3)}</td><td>${fmt(r.peak_z)}</td>` +
        `<td>${r.centroid.map((v) => fmt(v)).join(', ')}</td><td>${esc(r.region)}</td></tr>`).join('');
    table.querySelectorAll('tr[data-focus]').forEach((tr, i) => tr.addEventListener('click', () => {
      const peak = rows[i].peak_element;
      if (peak >= 0) this.open(subject, feature, peak, { turn: true });
    }));
  }
}
