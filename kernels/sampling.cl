// Per-element sampling of a subject's images (vpm/element_sampler.hpp): a work item per element
// of a block makes the element's samples, locates them in the registered ball mesh, carries them
// to native space and reads the images there; the arithmetic is the host's
// (kernels/element_sampling.clh and the headers before it), this kernel only loads and stores.
//
// Built with -DSP_FEATURES=<feature images> -DSP_LABELS=<label images>.
// Elements: shells, samples, offset (shells + 1), level (shells), first (per level), corners (9
//   per triangle of every level), u (samples x 3), radius (shells x samples), dir (per
//   triangle of every level, samples x 3): kernels/element_samples.clh.
// Mesh: inv m x 12, nbr m x 4, tets m x 4, native n x 3, the grid (lo, inv_h, dims; cell_start,
//   cell_tets): kernels/tet_locate.clh.
// Images (the feature images, then the label images): affine 12 each (the rows of the inverse
//   3 x 3, then the translation), dims 3 each, offset (first voxel in `voxels`) 1 each.
// Out, for element first + i (i < count): mean, stdev, in_grid [f * count + i] per feature f;
//   labels [(i * SP_LABELS + l) * samples + s] per label image l and sample s.

#include "tet_locate.clh"
#include "element_samples.clh"
#include "image_read.clh"
#include "element_sampling.clh"

#define SP_IMAGES (SP_FEATURES + SP_LABELS)
#define SP_ACC (SP_FEATURES > 0 ? 3 * SP_FEATURES : 1)

__kernel void sample_elements(const int first_element, const int count, const int shells,
                              const int samples, __global const int* offset,
                              __global const int* level, __global const int* first,
                              __global const real* corners, __global const real* u,
                              __global const real* radius, __global const real* dir,
                              __global const real* inv, __global const int* nbr,
                              __global const int* tets, __global const real* native,
                              const real lox, const real loy, const real loz, const real inv_h,
                              const int gx, const int gy, const int gz,
                              __global const int* cell_start, __global const int* cell_tets,
                              __global const real* affine, __global const int* dims,
                              __global const long* voxel_offset, __global const float* voxels,
                              __global real* mean, __global real* stdev, __global int* in_grid,
                              __global int* labels) {
  const int i = get_global_id(0);
  if (i >= count) return;
  const EsLayout L = {shells, samples, offset, level, first, corners, u, radius, dir};
  SpMesh M;
  M.inv = inv;
  M.nbr = nbr;
  M.tets = tets;
  M.native = native;
  M.grid.lo[0] = lox;
  M.grid.lo[1] = loy;
  M.grid.lo[2] = loz;
  M.grid.inv_h = inv_h;
  M.grid.dims[0] = gx;
  M.grid.dims[1] = gy;
  M.grid.dims[2] = gz;
  M.grid.cell_start = cell_start;
  M.grid.cell_tets = cell_tets;
  IrImage im[SP_IMAGES];
  for (int f = 0; f < SP_IMAGES; ++f) {
    for (int c = 0; c < 9; ++c) im[f].inv[c] = affine[12 * f + c];
    for (int c = 0; c < 3; ++c) {
      im[f].t[c] = affine[12 * f + 9 + c];
      im[f].dims[c] = dims[3 * f + c];
    }
    im[f].data = voxels + voxel_offset[f];
  }
  real acc[SP_ACC];
  int st[3] = {0, 0, 0};
  sp_element(&L, &M, im, SP_FEATURES, SP_LABELS, first_element + i, acc,
             labels + (long)i * SP_LABELS * samples, st);
  for (int f = 0; f < SP_FEATURES; ++f) {
    real m, s;
    sp_moments(acc + 3 * f, &m, &s);
    mean[f * count + i] = m;
    stdev[f * count + i] = s;
    in_grid[f * count + i] = (int)acc[3 * f + 2];
  }
}
