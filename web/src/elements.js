// Element ids of the canonical elements (include/vpm/elements.hpp) as the page draws them: every
// shell is drawn over the outermost level's T triangles; shell k's element over drawn triangle t
// is its ancestor at the shell's level (children of triangle f are 4f..4f+3 at every level), so
// in the graded layout one inner element covers 4^d drawn triangles.

export class ElementIndex {
  constructor(manifest) {
    this.T = manifest.triangles;
    this.K = manifest.shells;
    this.level = manifest.definition.level;
    // pages written before the graded layout carry neither: level L in every shell
    this.levels = manifest.shell_levels ?? Array.from({ length: this.K }, () => this.level);
    this.offsets = manifest.shell_offsets ?? Array.from({ length: this.K + 1 }, (_, k) => k * this.T);
  }

  /** The element of shell k over drawn (outermost-level) triangle t. */
  at(k, t) { return this.offsets[k] + (t >> (2 * (this.level - this.levels[k]))); }

  /** The shell of element e. */
  shellOf(e) {
    let lo = 0, hi = this.K - 1;
    while (lo < hi) {
      const mid = (lo + hi + 1) >> 1;
      if (this.offsets[mid] <= e) lo = mid; else hi = mid - 1;
    }
    return lo;
  }

  /** Element e's triangle at its shell's level. */
  triangleOf(e) { return e - this.offsets[this.shellOf(e)]; }

  /** The drawn triangles [first, end) that element e covers on its shell. */
  drawn(e) {
    const k = this.shellOf(e), d = 2 * (this.level - this.levels[k]), f = e - this.offsets[k];
    return [f << d, (f + 1) << d];
  }
}
