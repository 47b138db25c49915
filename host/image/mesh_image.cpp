// The mesh-image pipeline: mask -> smoothed grid -> topology repair -> marching tetrahedra ->
// remeshing (host/with_cgal) -> TetGen (host/with_tetgen) -> labels. The steps live in
// mask_grid, surface, tets and label_mesh; this file strings them together.
#include "vpm/mesh_image.hpp"
#include "vpm/voxelize.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdint>

#include "image/label_mesh.hpp"
#include "image/mask_grid.hpp"
#include "image/surface.hpp"
#include "image/tets.hpp"
#include "vpm/error.hpp"
#include "vpm/format.hpp"
#include "vpm/io.hpp"
#include "vpm/timing.hpp"
#include "vpm/topology.hpp"

namespace vpm {

MeshImageError::MeshImageError(Problem problem, std::string context, const std::string& message)
    : InputError(message), problem_(problem), context_(std::move(context)) {}

namespace {

using detail::Grid3;
using detail::record;

std::string world_str(const Image& img, int i, int j, int k) {
  const Eigen::Vector3d w = img.to_world(Eigen::Vector3d(i, j, k));
  return "voxel (" + std::to_string(i) + "," + std::to_string(j) + "," + std::to_string(k) +
         ") = (" + format_sig(w.x()) + ", " + format_sig(w.y()) + ", " + format_sig(w.z()) + ") mm";
}

std::string grid_str(const std::array<int, 3>& d) {
  return std::to_string(d[0]) + "x" + std::to_string(d[1]) + "x" + std::to_string(d[2]);
}

// Report input as far as known before masking: path, grid, affine source, mask rule.
void describe_input(const Image& img, const MeshImageOptions& o, const std::string& src, MeshImageReport& report) {
  MeshImageReport::Input& in = report.input;
  in.path = src;
  for (int k = 0; k < 3; ++k) in.dims[k] = img.dims[k], in.spacing_mm[k] = img.spacing[k];
  in.affine_source = img.affine_source;
  in.threshold = o.threshold;
  in.select_labels = o.select_labels;
}

// InputError unless `atlas` has the dims of `img` and its affine within 1e-3 mm.
void check_atlas_grid(const Image& img, const Image& atlas, const std::string& src) {
  const std::string asrc = atlas.path.empty() ? std::string("atlas") : atlas.path;
  if (atlas.dims != img.dims)
    throw InputError(asrc + ": atlas grid " + grid_str(atlas.dims) + " differs from the image grid " +
                     grid_str(img.dims) + " of " + src);
  const double diff = (atlas.affine - img.affine).cwiseAbs().maxCoeff();
  if (diff > 1e-3)
    throw InputError(asrc + ": atlas affine (" + atlas.affine_source + ") differs from the image affine (" +
                     img.affine_source + ") of " + src + " by up to " + format_sig(diff) + " mm: not the same grid");
}

std::string label_list(const MeshImageOptions& o) {
  std::string s;
  for (int l : o.select_labels) s += (s.empty() ? "" : ",") + std::to_string(l);
  return s;
}

// The raw mask (value > threshold, or one of the selected labels); InputError when empty.
std::vector<uint8_t> threshold_mask(const Image& img, const MeshImageOptions& o, const std::string& src) {
  std::vector<uint8_t> mask(img.size());
  size_t count = 0;
  float lo = img.data.empty() ? 0 : img.data[0], hi = lo;
  for (size_t i = 0; i < mask.size(); ++i) {
    const float v = img.data[i];
    lo = std::min(lo, v), hi = std::max(hi, v);
    if (o.select_labels.empty()) {
      mask[i] = v > o.threshold;
    } else {
      const long l = std::lround(v);
      mask[i] = std::find(o.select_labels.begin(), o.select_labels.end(), l) != o.select_labels.end();
    }
    count += mask[i];
  }
  if (count == 0 && !o.select_labels.empty())
    throw InputError(src + ": mask is empty: no voxel has label " + label_list(o) + " (values range " +
                     format_sig(lo) + " .. " + format_sig(hi) + ")");
  if (count == 0)
    throw InputError(src + ": mask is empty: no voxel is above the threshold " + format_sig(o.threshold) +
                     " (values range " + format_sig(lo) + " .. " + format_sig(hi) + ")");
  return mask;
}

// The cleaned mask, its voxel bounding box [lo, hi] and its volume.
struct Mask {
  std::vector<uint8_t> voxels;
  int lo[3] = {0, 0, 0}, hi[3] = {-1, -1, -1};
  double volume_mm3 = 0;
};

// Step "mask": threshold, largest 6-connected component, cavities filled, border check,
// bounding box; report input mask_voxels .. border_voxels.
Mask build_mask(const Image& img, const MeshImageOptions& o, const std::string& src, MeshImageReport& report) {
  if (o.progress)
    o.progress(o.select_labels.empty() ? "mask (value > " + format_sig(o.threshold) + ")" : "mask (labels " + label_list(o) + ")");
  const Grid3 G{img.dims[0], img.dims[1], img.dims[2]};
  Mask m;
  m.voxels = threshold_mask(img, o, src);
  const auto [removed, filled] = detail::keep_largest_fill_cavities(G, m.voxels, detail::kN6);
  m.lo[0] = G.nx, m.lo[1] = G.ny, m.lo[2] = G.nz;
  size_t count = 0, border_voxels = 0;
  for (int z = 0; z < G.nz; ++z)
    for (int y = 0; y < G.ny; ++y)
      for (int x = 0; x < G.nx; ++x) {
        if (!m.voxels[G.idx(x, y, z)]) continue;
        ++count;
        if (x == 0 || y == 0 || z == 0 || x == G.nx - 1 || y == G.ny - 1 || z == G.nz - 1) {
          if (!o.close_at_border) {
            const std::string what = src + ": mask touches the image border at " + world_str(img, x, y, z) +
                                     ": the surface would be cut open";
            throw MeshImageError(MeshImageError::Problem::kMaskTouchesBorder, what,
                                 what + " (pad the image, raise the threshold, or set close_at_border to close "
                                        "it with a flat cap there)");
          }
          ++border_voxels;
        }
        const int p[3] = {x, y, z};
        for (int d = 0; d < 3; ++d) m.lo[d] = std::min(m.lo[d], p[d]), m.hi[d] = std::max(m.hi[d], p[d]);
      }
  const double voxel_volume = std::abs(img.affine.topLeftCorner<3, 3>().determinant());
  MeshImageReport::Input& in = report.input;
  in.mask_voxels = double(count);
  m.volume_mm3 = count * voxel_volume;
  in.mask_volume_mm3 = m.volume_mm3;
  in.components_removed = removed;
  in.cavities_filled = filled;
  in.border_voxels = double(border_voxels);
  return m;
}

// The smoothed mask resampled on the extraction grid E (values in [0, 1]); grid point
// (x, y, z) is voxel c0 + (x, y, z) * step.
struct SmoothGrid {
  Grid3 E;
  std::vector<float> F;
  double step[3] = {0, 0, 0};
  int c0[3] = {0, 0, 0};
  double grid = 0, sigma = 0;
};

// Cropped, padded float copy of the mask, blurred by sigma mm; `c0` receives its first voxel.
std::vector<float> blurred_crop(const Image& img, const Mask& m, double sigma, double grid, Grid3& C, int (&c0)[3]) {
  int cn[3];
  for (int d = 0; d < 3; ++d) {
    const int pad = int(std::ceil((3 * sigma + 2 * grid) / img.spacing[d])) + 2;
    c0[d] = m.lo[d] - pad;
    cn[d] = m.hi[d] - m.lo[d] + 1 + 2 * pad;
  }
  C = Grid3{cn[0], cn[1], cn[2]};
  const Grid3 G{img.dims[0], img.dims[1], img.dims[2]};
  std::vector<float> field(C.size(), 0.f);
  for (int z = m.lo[2]; z <= m.hi[2]; ++z)
    for (int y = m.lo[1]; y <= m.hi[1]; ++y)
      for (int x = m.lo[0]; x <= m.hi[0]; ++x)
        if (m.voxels[G.idx(x, y, z)]) field[C.idx(x - c0[0], y - c0[1], z - c0[2])] = 1.f;
  for (int d = 0; d < 3; ++d) detail::blur_axis(field, C, d, sigma / img.spacing[d]);
  return field;
}

// Step "grid": smoothing and trilinear resampling at 0.7 x the target edge; report parameters.
SmoothGrid smooth_and_resample(const Image& img, Mask m, const detail::Resolution& res,
                               const MeshImageOptions& o, MeshImageReport& report) {
  SmoothGrid s;
  const double min_sp = std::min({img.spacing[0], img.spacing[1], img.spacing[2]});
  s.grid = std::max(0.7 * res.edge, min_sp);
  s.sigma = o.smooth < 0 ? std::max(0.5 * res.edge, 2 * min_sp) : o.smooth;
  MeshImageReport::Parameters& p = report.parameters;
  p.target_edge_mm = res.edge;
  p.grid_mm = s.grid;
  p.smooth_sigma_mm = s.sigma;
  p.max_volume_mm3 = res.max_volume;
  if (o.progress)
    o.progress("smoothing (sigma " + format_sig(s.sigma, 3) + " mm) and resampling (" + format_sig(s.grid, 3) + " mm)");
  Grid3 C;
  const std::vector<float> field = blurred_crop(img, m, s.sigma, s.grid, C, s.c0);
  std::vector<uint8_t>().swap(m.voxels);
  int gn[3];
  for (int d = 0; d < 3; ++d) {
    s.step[d] = s.grid / img.spacing[d];
    const int cn = d == 0 ? C.nx : d == 1 ? C.ny : C.nz;
    gn[d] = int(std::floor((cn - 1) / s.step[d])) + 1;
  }
  s.E = Grid3{gn[0], gn[1], gn[2]};
  s.F.resize(s.E.size());
  auto sample = [&](double x, double y, double z) {
    const int ix = std::min(int(x), C.nx - 2), iy = std::min(int(y), C.ny - 2), iz = std::min(int(z), C.nz - 2);
    const double fx = x - ix, fy = y - iy, fz = z - iz;
    double acc = 0;
    for (int c = 0; c < 8; ++c) {
      const int dx = c & 1, dy = (c >> 1) & 1, dz = (c >> 2) & 1;
      acc += (dx ? fx : 1 - fx) * (dy ? fy : 1 - fy) * (dz ? fz : 1 - fz) * field[C.idx(ix + dx, iy + dy, iz + dz)];
    }
    return float(acc);
  };
  for (int z = 0; z < s.E.nz; ++z)
    for (int y = 0; y < s.E.ny; ++y)
      for (int x = 0; x < s.E.nx; ++x) s.F[s.E.idx(x, y, z)] = sample(x * s.step[0], y * s.step[1], z * s.step[2]);
  return s;
}

constexpr float kIso = 0.5f;

// Marching tetrahedra of the binary grid B, with the smooth values F pushed just to the
// side of the iso level that B says.
TriSurface extract_binary(const SmoothGrid& s, const std::vector<uint8_t>& B) {
  std::vector<float> Fx = s.F;
  for (size_t i = 0; i < s.E.size(); ++i) {
    if (B[i] && !(Fx[i] > kIso + 1e-3f)) Fx[i] = std::max(Fx[i], kIso + 0.05f);
    if (!B[i] && !(Fx[i] < kIso - 1e-3f)) Fx[i] = std::min(Fx[i], kIso - 0.05f);
  }
  return detail::marching_tets(s.E, Fx, kIso);
}

// The grid's inside (F > iso, outer layer outside); InputError when nothing is inside.
std::vector<uint8_t> binary_inside(const SmoothGrid& s, const std::string& src) {
  const Grid3& E = s.E;
  std::vector<uint8_t> B0(E.size());
  for (size_t i = 0; i < E.size(); ++i) B0[i] = s.F[i] > kIso;
  for (int z = 0; z < E.nz; ++z)  // the outer layer is outside by construction of the padding
    for (int y = 0; y < E.ny; ++y)
      for (int x = 0; x < E.nx; ++x)
        if (x == 0 || y == 0 || z == 0 || x == E.nx - 1 || y == E.ny - 1 || z == E.nz - 1) B0[E.idx(x, y, z)] = 0;
  if (std::find(B0.begin(), B0.end(), 1) == B0.end()) {
    const std::string what = src + ": the mask vanishes after smoothing (sigma " + format_sig(s.sigma) +
                             " mm): it is thinner than the mesh resolution";
    throw MeshImageError(MeshImageError::Problem::kMaskVanishes, what,
                         what + "; lower the smoothing or raise target_vertices");
  }
  return B0;
}

// Step "topology": one component, no cavities, genus 0, by morphological closing at growing
// radii; returns the extracted surface (grid coordinates) and fills report.topology.
TriSurface repair_topology(const SmoothGrid& s, const MeshImageOptions& o, const std::string& src,
                           MeshImageReport& report) {
  if (o.progress) o.progress("topology check");
  const std::vector<uint8_t> B0 = binary_inside(s, src);
  MeshImageReport::Topology& topo = report.topology;
  std::vector<uint8_t> B = B0;
  auto [rm0, fill0] = detail::keep_largest_fill_cavities(s.E, B, detail::kN14);
  TriSurface surf = extract_binary(s, B);
  SurfaceTopology st = surface_topology(int(surf.vertices.rows()), surf.triangles);
  topo.euler_before = st.euler;
  topo.genus_before = st.genus();
  topo.grid_components_removed = rm0;
  topo.grid_cavities_filled = fill0;
  int radius = 0;
  while (st.euler != 2 || st.components != 1) {
    ++radius;
    if (radius > o.max_closing_radius)
      throw InputError(src + ": the mask surface has genus " + std::to_string(st.genus()) + " (Euler characteristic " +
                       std::to_string(st.euler) + ") and morphological closing up to radius " +
                       std::to_string(o.max_closing_radius) + " grid cells (" + format_sig(o.max_closing_radius * s.grid) +
                       " mm) did not remove the handles; cannot make a genus-0 boundary");
    if (o.progress) o.progress("genus " + std::to_string(st.genus()) + ": closing with radius " + std::to_string(radius));
    B = B0;
    detail::morph(s.E, B, radius, true);
    detail::morph(s.E, B, radius, false);
    detail::keep_largest_fill_cavities(s.E, B, detail::kN14);
    surf = extract_binary(s, B);
    const int before = st.euler;
    st = surface_topology(int(surf.vertices.rows()), surf.triangles);
    topo.repairs.push_back({radius, radius * s.grid, before, st.euler});
  }
  topo.closing_radius_cells = radius;
  topo.euler = st.euler;
  return surf;
}

// Grid coordinates -> world mm; orientation kept outward under a mirroring affine.
void to_world(TriSurface& surf, const SmoothGrid& s, const Image& img) {
  for (int v = 0; v < surf.vertices.rows(); ++v) {
    Eigen::Vector3d ijk;
    for (int d = 0; d < 3; ++d) ijk[d] = s.c0[d] + surf.vertices(v, d) * s.step[d];
    surf.vertices.row(v) = img.to_world(ijk).transpose();
  }
  if (img.affine.topLeftCorner<3, 3>().determinant() < 0) surf.triangles.col(1).swap(surf.triangles.col(2));
}

}  // namespace

TetMesh mesh_image(const Image& img, const MeshImageOptions& o, MeshImageReport* report_out, const Image* atlas) {
  const Stopwatch t_total;
  MeshImageReport report;
  const std::string src = img.path.empty() ? std::string("image") : img.path;
  describe_input(img, o, src, report);
  if (img.data.size() != img.size() || img.size() == 0) throw InputError(src + ": image has no data");
  if (atlas) check_atlas_grid(img, *atlas, src);

  Stopwatch t0;
  Mask mask = build_mask(img, o, src, report);
  record(report, "mask", t0);

  t0.restart();
  const detail::Resolution res = detail::resolution_for(mask.volume_mm3, o);
  const SmoothGrid grid = smooth_and_resample(img, std::move(mask), res, o, report);
  record(report, "grid", t0);

  t0.restart();
  TriSurface surf = repair_topology(grid, o, src, report);
  record(report, "topology", t0);

  t0.restart();
  to_world(surf, grid, img);
  report.extracted_surface = detail::surface_stats(surf);
  report.extracted_surface_volume_mm3 = detail::enclosed_volume(surf);
  record(report, "extract", t0);

  TetMesh mesh = detail::surface_to_tets(surf, res, o, report, src);

  if (atlas) {
    t0.restart();
    if (o.progress) o.progress("labels");
    report.has_labels = true;
    report.labels = detail::label_report(mesh, *atlas);
    record(report, "labels", t0);
  }
  record(report, "total", t_total);
  if (report_out) *report_out = report;
  return mesh;
}

TetMesh mesh_surface(const TriSurface& surface, const MeshImageOptions& o, MeshImageReport* report_out,
                     const std::string& source) {
  if (o.voxelize_mm > 0) {
    detail::check_closed_genus0(surface, source, "the input surface");
    const Stopwatch t0;
    Image mask = voxelize_surface(surface, o.voxelize_mm);
    mask.path = source + " (voxelized at " + format_sig(o.voxelize_mm) + ")";
    MeshImageOptions mo = o;
    mo.threshold = 0.5;
    mo.select_labels.clear();
    MeshImageReport r;
    TetMesh mesh = mesh_image(mask, mo, &r, nullptr);
    r.parameters.voxelize_mm = o.voxelize_mm;
    r.timings.insert(r.timings.begin(), StageTime{"voxelize", t0.seconds(), t0.cpu_seconds()});
    if (report_out) *report_out = r;
    return mesh;
  }
  const Stopwatch t_total;
  MeshImageReport report;
  report.image_input = false;
  report.input.path = source;
  detail::check_closed_genus0(surface, source, "the input surface");
  double vol = detail::enclosed_volume(surface);
  TriSurface s = surface;
  if (vol < 0) {  // inward normals: flip
    s.triangles.col(1).swap(s.triangles.col(2));
    vol = -vol;
  }
  report.input.volume_mm3 = vol;
  const detail::Resolution res = detail::resolution_for(vol, o);
  report.parameters.target_edge_mm = res.edge;
  report.parameters.max_volume_mm3 = res.max_volume;
  TetMesh mesh = detail::surface_to_tets(s, res, o, report, source);
  record(report, "total", t_total);
  if (report_out) *report_out = report;
  return mesh;
}

TetMesh mesh_image_file(const std::string& path, const MeshImageOptions& o, MeshImageReport* report,
                        const std::string& labels_path) {
  TetMesh m;
  MeshImageReport r;
  if (is_surface_path(path)) {
    if (!labels_path.empty())
      throw MeshImageError(MeshImageError::Problem::kAtlasWithSurface, path,
                           "an atlas needs an image input, not a surface (" + path + ")");
    const Stopwatch t0;
    const TriSurface s = read_surface(path);
    record(r, "read", t0);
    m = mesh_surface(s, o, report, path);
  } else {
    const Stopwatch t0;
    const Image img = read_image(path);
    Image atlas;
    if (!labels_path.empty()) atlas = read_image(labels_path);
    record(r, "read", t0);
    m = mesh_image(img, o, report, labels_path.empty() ? nullptr : &atlas);
  }
  if (report) report->timings.push_back(r.timings.front());
  return m;
}

}  // namespace vpm
