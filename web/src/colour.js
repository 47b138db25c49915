// Colour scales for element values: a sequential scale for features, a diverging one for
// z-scores with the elements below the threshold in neutral grey.

// viridis-like anchor colours (sequential), blue-white-red (diverging)
const SEQ = [[0.267, 0.005, 0.329], [0.230, 0.322, 0.546], [0.128, 0.567, 0.551],
  [0.369, 0.789, 0.383], [0.993, 0.906, 0.144]];
const NEG = [[0.85, 0.9, 1.0], [0.2, 0.45, 0.95], [0.05, 0.1, 0.55]];
const POS = [[1.0, 0.88, 0.8], [0.95, 0.3, 0.15], [0.55, 0.0, 0.05]];
const SPREAD = [[0.16, 0.12, 0.24], [0.55, 0.22, 0.45], [0.96, 0.55, 0.3], [1.0, 0.93, 0.72]];
export const NO_DATA = [0.25, 0.25, 0.25];
export const BELOW = [0.78, 0.78, 0.76];
export const HIGHLIGHT = [0.1, 1.0, 0.35];

function ramp(stops, t, out) {
  t = Math.min(1, Math.max(0, t)) * (stops.length - 1);
  const i = Math.min(stops.length - 2, Math.floor(t));
  const f = t - i;
  for (let c = 0; c < 3; ++c) out[c] = stops[i][c] * (1 - f) + stops[i + 1][c] * f;
  return out;
}

/** Sequential colour of `v` on [lo, hi]. */
export function sequential(v, lo, hi, out = [0, 0, 0]) {
  if (!Number.isFinite(v)) return Object.assign(out, NO_DATA);
  return ramp(SEQ, (v - lo) / (hi - lo || 1), out);
}

/** Colour of a spread (standard deviation) `v` on [0, hi]: the normals' reference row. */
export function spread(v, hi, out = [0, 0, 0]) {
  if (!Number.isFinite(v)) return Object.assign(out, NO_DATA);
  return ramp(SPREAD, v / (hi || 1), out);
}

/** Diverging colour of z: grey when |z| < threshold, else blue (below) or red (above),
 *  saturating at `zmax`. */
export function diverging(z, threshold, zmax, out = [0, 0, 0]) {
  if (!Number.isFinite(z)) return Object.assign(out, NO_DATA);
  if (Math.abs(z) < threshold) return Object.assign(out, BELOW);
  const t = (Math.abs(z) - threshold) / Math.max(1e-9, zmax - threshold);
  return ramp(z < 0 ? NEG : POS, t, out);
}

/** `c` faded three fifths of the way to the neutral grey: |z| beyond the threshold outside any
 *  focus (foci are clusters of at least min_cluster adjacent elements). */
export function faded(c) {
  for (let i = 0; i < 3; ++i) c[i] = 0.4 * c[i] + 0.6 * BELOW[i];
  return c;
}

/** CSS gradient strings for the colour bars. */
export function sequentialCss() {
  return `linear-gradient(to right, ${SEQ.map((c) => rgb(c)).join(', ')})`;
}
export function spreadCss() {
  return `linear-gradient(to right, ${SPREAD.map((c) => rgb(c)).join(', ')})`;
}
export function divergingCss() {
  const stops = [...NEG].reverse().map(rgb).concat([rgb(BELOW), rgb(BELOW)], POS.map(rgb));
  return `linear-gradient(to right, ${stops.join(', ')})`;
}
export function rgb(c) {
  return `rgb(${Math.round(c[0] * 255)}, ${Math.round(c[1] * 255)}, ${Math.round(c[2] * 255)})`;
}
