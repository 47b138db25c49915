// The detail's 2-D plots on plain canvases: an element's value against the normals'
// distribution, and slices of the patient's image with the z-map over it (paper Figs. 8, 10).
import { diverging, rgb } from './colour.js';

/** Histogram of the normals' values, the normal density of the reference (mean, std), each
 *  normal as a dot and the subject's value as a line with its z. The title has its own band above
 *  the plot, which the value line does not enter. Returns what it drew. */
export function drawDistribution(canvas, { normals, mean, std, value, z, title, curve }) {
  const ctx = canvas.getContext('2d');
  const W = canvas.width, H = canvas.height;
  ctx.fillStyle = '#fff';
  ctx.fillRect(0, 0, W, H);
  ctx.font = '12px sans-serif';
  ctx.fillStyle = '#222';
  ctx.fillText(title, 8, 14, W - 16);
  ctx.fillStyle = '#555';
  ctx.fillText(curve, 8, 30, W - 16);
  const finite = normals.filter(Number.isFinite);
  const span = [mean - 4 * std, mean + 4 * std, ...finite, value].filter(Number.isFinite);
  if (!span.length || !(std > 0)) {
    ctx.fillStyle = '#333';
    ctx.fillText('no reference at this element', 10, 56);
    return { drawn: false };
  }
  const lo = Math.min(...span), hi = Math.max(...span);
  const L = 36, R = W - 10, T = 44, B = H - 30;
  const X = (v) => L + ((v - lo) / (hi - lo || 1)) * (R - L);
  const bins = 16, counts = new Array(bins).fill(0);
  for (const v of finite) counts[Math.min(bins - 1, Math.floor(((v - lo) / (hi - lo || 1)) * bins))]++;
  const pdfPeak = 1 / (std * Math.sqrt(2 * Math.PI));
  const binWidth = (hi - lo) / bins;
  const yMax = Math.max(...counts.map((c) => c / (finite.length * binWidth || 1)), pdfPeak) * 1.1;
  const Y = (d) => B - (d / yMax) * (B - T);
  ctx.fillStyle = '#c9d3e0';
  counts.forEach((c, i) => {
    const d = c / (finite.length * binWidth || 1);
    ctx.fillRect(X(lo + i * binWidth) + 1, Y(d), (R - L) / bins - 2, B - Y(d));
  });
  ctx.strokeStyle = '#2c5aa0';
  ctx.lineWidth = 2;
  ctx.beginPath();
  for (let i = 0; i <= 200; ++i) {
    const v = lo + ((hi - lo) * i) / 200;
    const d = pdfPeak * Math.exp(-0.5 * ((v - mean) / std) ** 2);
    i ? ctx.lineTo(X(v), Y(d)) : ctx.moveTo(X(v), Y(d));
  }
  ctx.stroke();
  ctx.fillStyle = '#2c5aa0';
  finite.forEach((v, i) => {
    ctx.beginPath();
    ctx.arc(X(v), B - 5 - (i % 4) * 3, 2.2, 0, 2 * Math.PI);
    ctx.fill();
  });
  if (Number.isFinite(value)) {
    ctx.strokeStyle = '#c0392b';
    ctx.lineWidth = 2.5;
    ctx.beginPath();
    ctx.moveTo(X(value), T);
    ctx.lineTo(X(value), B);
    ctx.stroke();
  }
  ctx.fillStyle = '#222';
  ctx.strokeStyle = '#888';
  ctx.lineWidth = 1;
  ctx.beginPath();
  ctx.moveTo(L, B);
  ctx.lineTo(R, B);
  ctx.stroke();
  for (let i = 0; i <= 4; ++i) {
    const v = lo + ((hi - lo) * i) / 4;
    ctx.fillText(fmt(v), X(v) - 12, B + 14);
  }
  return { drawn: true, top: T };
}

/** An integer with thousands separators (12,345): Number.toLocaleString took 245 ms on its first
 *  call in headless Chromium (loading the locale data), a tenth of the page's start. */
export function thousands(n) {
  return String(Math.round(n)).replace(/\B(?=(\d{3})+(?!\d))/g, ',');
}

export function fmt(v) {
  if (!Number.isFinite(v)) return 'n/a';
  return Math.abs(v) >= 100 ? v.toFixed(0) : Math.abs(v) >= 10 ? v.toFixed(1) : v.toFixed(2);
}

/** Voxel (i, j, k) of world point w through the inverse of a 4x4 row-major affine. */
export function worldToVoxel(affine, w) {
  const a = affine;
  const m = [[a[0], a[1], a[2]], [a[4], a[5], a[6]], [a[8], a[9], a[10]]];
  const t = [w[0] - a[3], w[1] - a[7], w[2] - a[11]];
  const det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
    m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
  const inv = [
    [m[1][1] * m[2][2] - m[1][2] * m[2][1], m[0][2] * m[2][1] - m[0][1] * m[2][2], m[0][1] * m[1][2] - m[0][2] * m[1][1]],
    [m[1][2] * m[2][0] - m[1][0] * m[2][2], m[0][0] * m[2][2] - m[0][2] * m[2][0], m[0][2] * m[1][0] - m[0][0] * m[1][2]],
    [m[1][0] * m[2][1] - m[1][1] * m[2][0], m[0][1] * m[2][0] - m[0][0] * m[2][1], m[0][0] * m[1][1] - m[0][1] * m[1][0]],
  ];
  return inv.map((row) => (row[0] * t[0] + row[1] * t[1] + row[2] * t[2]) / det);
}

const LETTERS = [['L', 'R'], ['P', 'A'], ['I', 'S']];

/** The anatomical letter at the positive end of voxel axis a of a 4x4 row-major affine (RAS
 *  world: R, A, S) and at its negative end. */
export function axisLetters(affine, a) {
  const d = [affine[a], affine[4 + a], affine[8 + a]];
  const w = [0, 1, 2].reduce((best, c) => (Math.abs(d[c]) > Math.abs(d[best]) ? c : best), 0);
  return d[w] >= 0 ? { pos: LETTERS[w][1], neg: LETTERS[w][0] } : { pos: LETTERS[w][0], neg: LETTERS[w][1] };
}

/** One voxel plane of the image through voxel `at`, the z-map over it where |z| >= threshold,
 *  with the anatomical direction (L/R, A/P, S/I) at each edge. axis 2: axial (i right, j up),
 *  1: coronal (i right, k up), 0: sagittal (j right, k up). Returns the edge letters. */
export function drawSlice(canvas, slices, image, zmap, axis, at, threshold) {
  const [nx, ny, nz] = slices.dims;
  const dims = [nx, ny, nz];
  const [ua, va] = axis === 2 ? [0, 1] : axis === 1 ? [0, 2] : [1, 2];
  const w = dims[ua], h = dims[va];
  const fixed = Math.max(0, Math.min(dims[axis] - 1, Math.round(at[axis])));
  const off = document.createElement('canvas');
  off.width = w;
  off.height = h;
  const octx = off.getContext('2d');
  const img = octx.createImageData(w, h);
  const c = [0, 0, 0];
  const ijk = [0, 0, 0];
  for (let v = 0; v < h; ++v)
    for (let u = 0; u < w; ++u) {
      ijk[axis] = fixed;
      ijk[ua] = u;
      ijk[va] = v;
      const idx = ijk[0] + nx * (ijk[1] + ny * ijk[2]);
      const g = image[idx];
      const p = 4 * ((h - 1 - v) * w + u);
      const z = zmap[idx] / slices.z_scale;
      if (zmap[idx] !== 0 && Math.abs(z) >= threshold) {
        diverging(z, threshold, threshold + 3, c);
        img.data[p] = c[0] * 255 * 0.7 + g * 0.3;
        img.data[p + 1] = c[1] * 255 * 0.7 + g * 0.3;
        img.data[p + 2] = c[2] * 255 * 0.7 + g * 0.3;
      } else {
        img.data[p] = img.data[p + 1] = img.data[p + 2] = g;
      }
      img.data[p + 3] = 255;
    }
  octx.putImageData(img, 0, 0);
  const ctx = canvas.getContext('2d');
  ctx.imageSmoothingEnabled = false;
  ctx.fillStyle = '#000';
  ctx.fillRect(0, 0, canvas.width, canvas.height);
  const s = Math.min(canvas.width / w, canvas.height / h);
  const ox = (canvas.width - w * s) / 2, oy = (canvas.height - h * s) / 2;
  ctx.drawImage(off, ox, oy, w * s, h * s);
  ctx.strokeStyle = 'rgba(80, 255, 120, 0.8)';
  ctx.lineWidth = 1;
  const cx = ox + (at[ua] + 0.5) * s, cy = oy + (h - at[va] - 0.5) * s;
  ctx.beginPath();
  ctx.moveTo(cx, oy);
  ctx.lineTo(cx, oy + h * s);
  ctx.moveTo(ox, cy);
  ctx.lineTo(ox + w * s, cy);
  ctx.stroke();
  ctx.fillStyle = rgb([1, 1, 1]);
  ctx.font = '11px sans-serif';
  ctx.fillText(['sagittal', 'coronal', 'axial'][axis] + ` ${fixed}`, 4, 12);
  const hor = axisLetters(slices.affine, ua), ver = axisLetters(slices.affine, va);
  const edges = { left: hor.neg, right: hor.pos, top: ver.pos, bottom: ver.neg };
  ctx.font = 'bold 12px sans-serif';
  ctx.fillStyle = '#ffd84a';
  ctx.textBaseline = 'middle';
  ctx.fillText(edges.left, 3, canvas.height / 2);
  ctx.fillText(edges.right, canvas.width - 11, canvas.height / 2);
  ctx.textBaseline = 'alphabetic';
  ctx.fillText(edges.top, canvas.width / 2 - 4, 26);
  ctx.fillText(edges.bottom, canvas.width / 2 - 4, canvas.height - 4);
  return edges;
}
