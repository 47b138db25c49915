// The marker of the lit element: a ring of a fixed screen size around it in every cell where it is
// on the shown shell and faces the viewer, drawn on a 2-D canvas over the WebGL one. The element
// itself is only a few pixels wide in a cell (8-11 px at 150 px cells), too small to find at a glance.
import { rgb, HIGHLIGHT } from './colour.js';

export class Marks {
  constructor(canvas, { scene, model, painter, state }) {
    Object.assign(this, { canvas, scene, model, painter, state });
    this.ctx = canvas.getContext('2d');
    this.rings = [];   // what was drawn last: {cell, x, y, r}
  }

  elementAt(cell, at) {
    const f = this.scene.pick(cell, at.x, at.y);
    return f < 0 ? -1 : this.model.element(this.painter.shellOf(cell.row), f);
  }

  /** Rings for the cells drawn this frame (`shown`: from TableScene.visible, prepared). */
  draw(shown) {
    const rings = [];
    for (const v of shown) {
      const cell = v.cell;
      const e = cell.detail ? (this.state.detail?.element ?? -1) : this.painter.lit();
      if (e < 0 || !cell.row.surf || this.model.ids.shellOf(e) !== this.painter.shellOf(cell.row)) continue;
      const { p, n } = this.model.elementPoint(cell.row.surf, e);
      const at = this.scene.project(cell, v.rect, p, n);
      if (!at.facing || at.x < v.left || at.x > v.right || at.y < v.top || at.y > v.bottom) continue;
      // seen at an angle it may be behind a fold: at rest, only where the surface there is its own
      if (at.cos < 0.7 && (this.scene.moving || this.elementAt(cell, at) !== e)) continue;
      rings.push({ cell, x: at.x, y: at.y, r: Math.max(10, Math.min(22, 0.06 * v.rect.width)), clip: v });
    }
    if (!rings.length && !this.rings.length) return;
    const c = this.canvas, ctx = this.ctx;
    if (c.width !== innerWidth || c.height !== innerHeight) {
      c.width = innerWidth;
      c.height = innerHeight;
    }
    ctx.clearRect(0, 0, c.width, c.height);
    for (const { x, y, r, clip } of rings) {
      ctx.save();
      ctx.beginPath();
      ctx.rect(clip.left, clip.top, clip.right - clip.left, clip.bottom - clip.top);
      ctx.clip();
      ctx.beginPath();
      ctx.arc(x, y, r, 0, 2 * Math.PI);
      ctx.lineWidth = 5;
      ctx.strokeStyle = 'rgba(0, 0, 0, 0.75)';
      ctx.stroke();
      ctx.lineWidth = 2.5;
      ctx.strokeStyle = rgb(HIGHLIGHT);
      ctx.stroke();
      ctx.restore();
    }
    this.rings = rings;
  }
}
