// The cohort as the page uses it: subjects (patients first, then normals) with their values and
// z-scores per feature, read from the store when their row is needed. Normals' z is leave-one-out
// (each normal against the other normals, as a patient is against all of them) and computed here
// from the normal's value and the reference's mean, spread and count at each element: the same
// numbers the detail's plot draws for a normal, so plot and z agree by construction.
/** Leave-one-out statistics of one normal with value x at an element where the n normals with
 *  data (x among them) have mean m and sample standard deviation s: the other normals' mean, sample
 *  standard deviation and count, and x's z against them (vpm::leave_one_out_z's rule: NaN with
 *  fewer than 3 others or no spread among them). */
export function leaveOneOut(x, m, s, n) {
  const k = n - 1;
  if (!Number.isFinite(x) || !(k >= 3) || !Number.isFinite(m) || !Number.isFinite(s)) return { mean: NaN, std: NaN, n: k, z: NaN };
  const mean = (n * m - x) / k;
  const m2 = s * s * (n - 1) - (x - mean) * (x - m);  // Welford's update, undone
  const v = m2 / (k - 1);
  const std = v > 1e-20 ? Math.sqrt(v) : NaN;
  return { mean, std, n: k, z: std > 0 ? (x - mean) / std : NaN };
}

export class Cohort {
  constructor(manifest, store) {
    this.m = manifest;
    this.store = store;
    this.features = manifest.features;
    this.subjects = manifest.subjects.map((s, index) => ({ ...s, index, kind: 'subject' }));
    this.patients = this.subjects.filter((s) => s.group === 'patient');
    this.normals = this.subjects.filter((s) => s.group !== 'patient');
    this.zCache = new Map();  // normals: `${index}:${feature}` -> Float32Array
    // the normals' summary row: the reference's mean (values) and spread (std) on the mean shape
    this.reference = { id: 'reference', group: 'reference', kind: 'reference', index: -1, chunk: 'base' };
    store.onDrop = (chunk) => {
      for (const s of this.subjects) if (s.chunk === chunk) for (const f of this.features) this.zCache.delete(`${s.index}:${f.name}`);
    };
  }

  /** Whether subject s's data (its row chunk) is in memory. */
  ready(s) { return this.store.loaded(s.chunk); }

  /** Loads the rows of the given subjects. */
  load(list) { return this.store.need(list.map((s) => s.chunk)); }

  /** Normalised values of feature f (Float32Array over elements); the reference row: the mean. */
  values(s, f) {
    if (s.kind === 'reference') return this.store.array(this.m.reference[f].mean);
    return this.store.array(s.values[f]);
  }

  /** The reference's spread (sample standard deviation) of feature f. */
  spread(f) { return this.store.array(this.m.reference[f].std); }

  /** z of feature f per element: patients as vpm compare computed it, normals leave-one-out. */
  z(s, f) {
    if (s.group === 'patient') return this.store.array(s.z[f]);
    const key = `${s.index}:${f}`;
    let z = this.zCache.get(key);
    if (!z) {
      const x = this.values(s, f), r = this.m.reference[f];
      const mean = this.store.array(r.mean), std = this.store.array(r.std), count = this.store.array(r.count);
      z = new Float32Array(x.length);
      for (let e = 0; e < x.length; ++e) z[e] = leaveOneOut(x[e], mean[e], std[e], count[e]).z;
      this.zCache.set(key, z);
    }
    return z;
  }

  /** Focus id per element (0: none), or null (normals, or no foci). */
  cluster(s, f) { return s.cluster?.[f] ? this.store.array(s.cluster[f]) : null; }

  /** The reference at element e of feature f: mean, std and count of every normal. */
  referenceAt(f, e) {
    const r = this.m.reference[f];
    return { mean: this.store.array(r.mean)[e], std: this.store.array(r.std)[e], n: this.store.array(r.count)[e] };
  }

  /** Every normal's value of feature f at element e, in the order of `normals` (loads what it
   *  needs: one chunk of columns in a folder, else the rows). */
  async normalValuesAt(f, e) {
    const cols = this.m.columns?.[f];
    if (cols) {
      const c = Math.floor(e / cols.elements);
      await this.store.chunk(this.m.buffers[cols.buffers[c]].chunk);
      const codes = this.store.codes(cols.buffers[c]);
      const q = this.features.find((x) => x.name === f).value_q;
      const n = cols.normals.length, at = (e - c * cols.elements) * n;
      const order = new Map(cols.normals.map((index, j) => [index, j]));
      return Float32Array.from(this.normals, (s) => {
        const code = codes[at + order.get(s.index)];
        return code === 65535 ? NaN : q.base + q.step * code;
      });
    }
    await this.load(this.normals);
    return Float32Array.from(this.normals, (s) => this.values(s, f)[e]);
  }

  /** Subject s's detail data (element centres, slices) loaded; resolves to whether it has any. */
  async loadDetail(s) {
    if (!s.detail) return false;
    await this.store.chunk(s.detail);
    return true;
  }

  /** Native position (mm) of element e's centre (patients, after loadDetail). */
  centre(s, e) {
    const c = s.centres, q = this.store.array(c.buffer);
    return [0, 1, 2].map((a) => c.offset[a] + q[3 * e + a] * c.scale);
  }

  /** The strongest focus of subject s (focus 1 of the first feature that has one), or null. */
  strongestFocus(s) {
    for (const f of this.features) {
      const row = s.foci_table?.[f.name]?.[0];
      if (row && row.peak_element >= 0) return { feature: f.name, ...row };
    }
    return null;
  }
}
