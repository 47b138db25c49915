// Surfaces of the table's cells. Every subject shares one triangulation: the icosphere one level
// finer than the elements' (each element triangle split into four display triangles; from level 4
// on the elements' own), at the middle radius of a shell. In the ball it is that sphere; in native space the same vertices
// pulled back through the subject's map (vpm view computes them), so every display triangle
// belongs to the same canonical element in every cell and picking one element picks it everywhere.

import { ElementIndex } from './elements.js';

export class SurfaceModel {
  /** `store`: the page's data with the base chunk loaded (display sphere, mean shape). */
  constructor(manifest, store) {
    const d = manifest.display;
    this.V = d.vertices;
    this.D = d.triangles;
    this.K = manifest.shells;
    this.T = manifest.triangles;
    this.finer = d.finer ?? true;
    this.ids = new ElementIndex(manifest);
    this.radii = manifest.radii;
    this.shellRadius = manifest.shell_radius;  // per shell: the largest subject's, from its centre (mm)
    this.store = store;
    this.index = store.array('display_index');
    this.sphere = store.array('display_sphere');
    this.faceTriangle = store.array('display_element_triangle');
    this.meanShape = store.array(manifest.mean_shape);  // shells x V x 3, mm from the centre
    this.facesOf = Array.from({ length: this.T }, () => []);
    for (let f = 0; f < this.D; ++f) this.facesOf[this.faceTriangle[f]].push(f);
  }

  /** Native positions (mm, from the subject's centre) of shell k's surface: the normals' mean
   *  shape plus the subject's own difference from it (8-bit codes times its scale), or the
   *  mean shape itself for the reference row. */
  vertices(s, k) {
    const out = new Float32Array(this.V * 3);
    const base = k * this.V * 3, mean = this.meanShape;
    if (s.kind === 'reference') {
      out.set(mean.subarray(base, base + this.V * 3));
      return out;
    }
    const q = this.store.array(s.native.buffer), scale = s.native.scale;
    for (let j = 0; j < this.V * 3; ++j) out[j] = mean[base + j] + q[base + j] * scale;
    return out;
  }

  /** Corners: each element triangle's display vertices, its own copies (6 for 4 display
   *  triangles), so one element has one colour; `drawIndex` the display triangles over them,
   *  element by element (triangle j belongs to element triangle elementOfDrawn[j]). */
  buildCorners() {
    const corners = [], draw = [], start = [0], owner = [];
    for (let t = 0; t < this.T; ++t) {
      const local = new Map();
      for (const f of this.facesOf[t])
        for (let c = 0; c < 3; ++c) {
          const v = this.index[3 * f + c];
          if (!local.has(v)) { local.set(v, corners.length); corners.push(v); }
          draw.push(local.get(v));
        }
      for (let j = 0; j < this.facesOf[t].length; ++j) owner.push(t);
      start.push(corners.length);
    }
    this.corners = Uint32Array.from(corners);
    this.coarseIndex = this.coarse(corners, start);
    this.cornerStart = Uint32Array.from(start);
    this.drawIndex = Uint32Array.from(draw);
    this.elementOfDrawn = Uint32Array.from(owner);
  }

  /** The surface drawn while the view turns, over the same corners, a quarter of the display
   *  triangles: per element triangle its three corners that are vertices of the coarser
   *  icosphere (the first 10 * 4^L + 2 display vertices); when the display is not finer than
   *  the elements (level >= 4), per group of 4 sibling element triangles the parent triangle
   *  over the corner copies of the 3 corner children (its colours blend 3 elements while the
   *  view moves). Oriented outwards. */
  coarse(corners, start) {
    const VL = (this.V - 2) / 4 + 2;
    const group = this.finer ? 1 : 4;
    const out = new Uint32Array((this.T / group) * 3);
    const P = (j) => [0, 1, 2].map((c) => this.sphere[3 * corners[j] + c]);
    for (let g = 0; g < this.T / group; ++g) {
      const own = [];
      for (let t = g * group; t < (g + 1) * group; ++t)
        for (let j = start[t]; j < start[t + 1]; ++j) if (corners[j] < VL) own.push(j);
      if (own.length !== 3) throw new Error(`element triangle ${g * group}: ${own.length} coarse corners`);
      const [a, b, c] = own.map(P);
      const u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]], w = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
      const n = [u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]];
      const outward = n[0] * (a[0] + b[0] + c[0]) + n[1] * (a[1] + b[1] + c[1]) + n[2] * (a[2] + b[2] + c[2]) > 0;
      out.set(outward ? own : [own[0], own[2], own[1]], 3 * g);
    }
    return out;
  }

  /** Positions and smooth normals at the corners of subject s's shell k in native space
   *  (scaled so that the largest subject's shell k fills the unit ball) or in the ball (the
   *  unit sphere: every shell is a sphere there). */
  surface(s, k, mode) {
    if (!this.corners) this.buildCorners();
    let p;
    if (mode === 'ball') {
      p = Float32Array.from(this.sphere);
    } else {
      p = this.vertices(s, k);
      const scale = 1 / (this.shellRadius[k] || 1);
      for (let j = 0; j < p.length; ++j) p[j] *= scale;
    }
    const vn = new Float32Array(this.V * 3);
    const idx = this.index;
    for (let f = 0; f < this.D; ++f) {
      const a = 3 * idx[3 * f], b = 3 * idx[3 * f + 1], c = 3 * idx[3 * f + 2];
      const ux = p[b] - p[a], uy = p[b + 1] - p[a + 1], uz = p[b + 2] - p[a + 2];
      const wx = p[c] - p[a], wy = p[c + 1] - p[a + 1], wz = p[c + 2] - p[a + 2];
      const nx = uy * wz - uz * wy, ny = uz * wx - ux * wz, nz = ux * wy - uy * wx;
      for (const v of [a, b, c]) { vn[v] += nx; vn[v + 1] += ny; vn[v + 2] += nz; }
    }
    const n = this.corners.length;
    const pos = new Float32Array(n * 3);
    const nor = new Float32Array(n * 3);
    for (let j = 0; j < n; ++j) {
      const v = 3 * this.corners[j];
      const l = Math.hypot(vn[v], vn[v + 1], vn[v + 2]) || 1;
      for (let c = 0; c < 3; ++c) {
        pos[3 * j + c] = p[v + c];
        nor[3 * j + c] = vn[v + c] / l;
      }
    }
    return { pos, nor };
  }

  /** Element id of drawn triangle j (a raycast's faceIndex) on shell k. */
  element(k, j) { return this.ids.at(k, this.elementOfDrawn[j]); }

  /** Centroid and mean normal of element e's corners in a surface {pos, nor} of its shell. */
  elementPoint(surf, e) {
    const [first, end] = this.ids.drawn(e);
    const p = [0, 0, 0], n = [0, 0, 0];
    let count = 0;
    for (let t = first; t < end; ++t)
      for (let j = this.cornerStart[t]; j < this.cornerStart[t + 1]; ++j, ++count)
        for (let c = 0; c < 3; ++c) { p[c] += surf.pos[3 * j + c]; n[c] += surf.nor[3 * j + c]; }
    return { p: p.map((v) => v / (count || 1)), n };
  }
}
