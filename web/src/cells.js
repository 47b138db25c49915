// What each cell draws: its row's surface (the subject's shell in native space or the ball; shared
// by the row's cells) and its own per-corner colours (the feature's value, its z, or for the
// reference row the normals' mean and spread), made when the cell comes on screen and brought up to
// date lazily: a cell off screen costs nothing when the shell or threshold changes, and rows far
// from the screen give their geometry back.
import { BufferAttribute, BufferGeometry } from './scene.js';
import { sequential, diverging, faded, spread, HIGHLIGHT } from './colour.js';

export class CellPainter {
  constructor({ cohort, model, scene, state }) {
    Object.assign(this, { cohort, model, scene, state });
    this.ids = model.ids;
    this.tmp = [0, 0, 0];
  }

  /** The shell row r shows: its own (facing a focus) or the page's. */
  shellOf(row) { return row?.shell ?? this.state.shell; }

  /** The element lit in every cell: the one under the pointer, else the detail's. */
  lit() {
    if (this.state.hover >= 0) return this.state.hover;
    return this.state.detail ? this.state.detail.element : -1;
  }

  /** The spread scale's top for feature f (the reference row's z columns). */
  spreadMax(f) { return this.cohort.features.find((x) => x.name === f).spread_range[1]; }

  /** Colour of element e in `cell` (no highlight). */
  colourOf(cell, e, out) {
    const s = cell.subject, f = cell.column.feature;
    if (cell.spread) return spread(this.cohort.spread(f)[e], this.spreadMax(f), out);
    if (cell.column.kind === 'value') {
      const [lo, hi] = this.cohort.features.find((x) => x.name === f).range;
      return sequential(this.cohort.values(s, f)[e], lo, hi, out);
    }
    return this.zColour(s, f, e, this.state.threshold, out);
  }

  /** z colour of element e: saturated in a patient's foci, faded elsewhere beyond the threshold. */
  zColour(s, f, e, threshold, out) {
    const z = this.cohort.z(s, f)[e];
    diverging(z, threshold, threshold + 3, out);
    const cl = this.cohort.cluster(s, f);
    return !(cl && cl[e] > 0) && Math.abs(z) >= threshold ? faded(out) : out;
  }

  /** Colours drawn triangle t of shell k in `cell` (all its corners); `lit` in the highlight. */
  paint(cell, k, t, lit) {
    const e = this.ids.at(k, t);
    const c = e === lit ? HIGHLIGHT : this.colourOf(cell, e, this.tmp);
    const a = cell.colours, m = this.model;
    const r = Math.round(c[0] * 255), g = Math.round(c[1] * 255), b = Math.round(c[2] * 255);
    for (let j = m.cornerStart[t]; j < m.cornerStart[t + 1]; ++j) {
      a[3 * j] = r;
      a[3 * j + 1] = g;
      a[3 * j + 2] = b;
    }
  }

  /** The row's surface for the page's mode and its shell, made or remade when they changed. */
  surface(row) {
    const k = this.shellOf(row), key = `${this.state.mode}:${k}`;
    if (row.surfaceKey === key) return row.surf;
    const surf = this.model.surface(row.subject, k, this.state.mode);
    if (!row.attrs) {
      row.attrs = { position: new BufferAttribute(surf.pos, 3), normal: new BufferAttribute(surf.nor, 3) };
    } else {
      row.attrs.position.array.set(surf.pos);
      row.attrs.normal.array.set(surf.nor);
      row.attrs.position.needsUpdate = row.attrs.normal.needsUpdate = true;
    }
    row.surf = surf;
    row.surfaceKey = key;
    for (const c of row.cells) if (c.geometry) c.geometry.boundingSphere = null;
    return surf;
  }

  /** Brings `cell` up to date; false while its subject's data is not loaded yet. */
  prepare(cell) {
    const row = cell.row;
    if (row.subject.kind !== 'reference' && !this.cohort.ready(row.subject)) return false;
    this.surface(row);
    if (!cell.geometry) {
      cell.colours = new Uint8Array(this.model.corners.length * 3);
      const g = new BufferGeometry();
      g.setIndex(this.scene.drawIndex);
      g.setAttribute('position', row.attrs.position);
      g.setAttribute('normal', row.attrs.normal);
      g.setAttribute('color', new BufferAttribute(cell.colours, 3, true));
      cell.geometry = g;
      cell.coarse = this.scene.coarseOf(g);
      cell.colourKey = null;
    } else if (cell.geometry.attributes.position !== row.attrs.position) {  // the detail's cell, moved to another row
      cell.geometry.setAttribute('position', row.attrs.position);
      cell.geometry.setAttribute('normal', row.attrs.normal);
      cell.geometry.boundingSphere = null;
      cell.coarse = this.scene.coarseOf(cell.geometry);
      cell.colourKey = null;
    }
    this.colour(cell, this.shellOf(row));
    return true;
  }

  /** Recolours `cell` in full when its shell or the threshold changed, else only the elements
   *  whose highlight changed. */
  colour(cell, k) {
    // the detail's own view keeps its picked element lit whatever the pointer does
    const lit = cell.detail ? (this.state.detail?.element ?? -1) : this.lit();
    const key = `${k}|${this.state.threshold}|${cell.subject.index}`;
    if (cell.colourKey !== key) {
      for (let t = 0; t < this.model.T; ++t) this.paint(cell, k, t, lit);
      cell.colourKey = key;
    } else if (cell.lit !== lit) {
      for (const e of [cell.lit, lit]) {
        if (e < 0 || this.ids.shellOf(e) !== k) continue;
        const [first, end] = this.ids.drawn(e);
        for (let t = first; t < end; ++t) this.paint(cell, k, t, lit);
      }
    } else {
      return;
    }
    cell.lit = lit;
    cell.geometry.attributes.color.needsUpdate = true;
  }

  /** Gives back a row's geometry (far from the screen); remade when it comes back. */
  release(row) {
    if (row === this.state.detail?.row) return;
    for (const c of row.cells) {
      if (!c.geometry) continue;
      c.geometry.dispose();
      c.coarse.dispose();
      c.geometry = c.coarse = c.colours = null;
    }
    row.attrs = row.surf = row.surfaceKey = null;
  }
}
