// The surface part of `vpm demo` (demo_surface.hpp).
#include "demo_surface.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>

#include "cli.hpp"
#include "vpm/collective.hpp"
#include "vpm/curvature.hpp"
#include "vpm/error.hpp"
#include "vpm/format.hpp"
#include "vpm/io.hpp"
#include "vpm/locate.hpp"
#include "vpm/topology.hpp"

namespace vpm::cli {

namespace fs = std::filesystem;

const std::vector<int> kSurfaceHeldOut = {1, 2, 57, 58};

namespace {

// Regions with fewer boundary faces than this on either surface give no landmark.
constexpr int kMinRegionFaces = 20;
// Sample directions of the Dice on the sphere (each about 2.5e-4 of its area).
constexpr int kDiceSamples = 50000;

// A mesh's boundary with each face's atlas label (its tet's).
struct LabelledSurface {
  TriSurface surface;
  std::vector<int> face_label;
};

LabelledSurface boundary_with_labels(const TetMesh& m) {
  std::vector<int> face_tet;
  boundary_faces(m.tets, &face_tet);  // the faces of boundary_surface, in its order
  LabelledSurface s{boundary_surface(m), {}};
  const std::vector<int> cells = cell_labels(m);
  for (int t : face_tet) s.face_label.push_back(cells[static_cast<size_t>(t)]);
  return s;
}

// The normalised area-weighted mean of the sphere images of each region's faces (area on the
// surface itself), for regions with at least kMinRegionFaces faces.
std::map<int, Eigen::Vector3d> region_centroids(const Points& sphere, const LabelledSurface& s) {
  std::map<int, Eigen::Vector3d> sum;
  std::map<int, int> count;
  const Triangles& f = s.surface.triangles;
  for (Eigen::Index t = 0; t < f.rows(); ++t) {
    const int l = s.face_label[static_cast<size_t>(t)];
    if (l <= 0) continue;
    const Points& x = s.surface.vertices;
    const double area = (x.row(f(t, 1)) - x.row(f(t, 0))).cross(x.row(f(t, 2)) - x.row(f(t, 0))).norm() / 2;
    const Eigen::Vector3d c = (sphere.row(f(t, 0)) + sphere.row(f(t, 1)) + sphere.row(f(t, 2))).transpose().normalized();
    auto [it, fresh] = sum.try_emplace(l, Eigen::Vector3d::Zero());
    it->second += area * c;
    ++count[l];
  }
  std::map<int, Eigen::Vector3d> out;
  for (const auto& [l, v] : sum)
    if (count[l] >= kMinRegionFaces && v.norm() > 0) out[l] = v.normalized();
  return out;
}

// n directions spread evenly on the sphere (the Fibonacci lattice).
Points fibonacci(int n) {
  Points p(n, 3);
  const double golden = M_PI * (3 - std::sqrt(5.0));
  for (int i = 0; i < n; ++i) {
    const double z = 1 - (2 * i + 1.0) / n, r = std::sqrt(1 - z * z);
    p.row(i) << r * std::cos(golden * i), r * std::sin(golden * i), z;
  }
  return p;
}

// The label of the face each sample direction lies on.
std::vector<int> labels_at(const Points& sphere, const LabelledSurface& s, const Points& samples) {
  const std::vector<SphereLocation> loc = SphereLocator(sphere, s.surface.triangles).locate_all(samples);
  std::vector<int> out;
  for (const SphereLocation& l : loc) out.push_back(l.face >= 0 ? s.face_label[static_cast<size_t>(l.face)] : 0);
  return out;
}

std::vector<double> dice(const std::vector<int>& a, const std::vector<int>& b) {
  std::vector<double> out;
  for (int l : kSurfaceHeldOut) {
    double both = 0, na = 0, nb = 0;
    for (size_t i = 0; i < a.size(); ++i) {
      na += a[i] == l;
      nb += b[i] == l;
      both += a[i] == l && b[i] == l;
    }
    out.push_back(na + nb > 0 ? 2 * both / (na + nb) : 0);
  }
  return out;
}

void write_sphere(const fs::path& path, const Points& sphere, const LabelledSurface& s, const Eigen::VectorXd& curvature) {
  TriSurface out{sphere, s.surface.triangles, {}, {}};
  out.point_data.push_back({"original_position", s.surface.vertices, false});
  out.point_data.push_back({"mean_curvature", curvature, false});
  Eigen::VectorXd labels(static_cast<Eigen::Index>(s.face_label.size()));
  for (size_t i = 0; i < s.face_label.size(); ++i) labels(static_cast<Eigen::Index>(i)) = s.face_label[i];
  out.cell_data.push_back({"label", labels, true});
  write_surface(path.string(), out);
}

// The faces of `s` whose sphere images lie above z = 0.3 on average (a cap of the sphere map: a
// disk topologically) to the disk.
void patch_to_disk(const TriSurface& s, const Points& sphere, const fs::path& out, SurfaceDemo& d) {
  std::vector<int> keep, id(static_cast<size_t>(s.vertices.rows()), -1);
  for (Eigen::Index t = 0; t < s.triangles.rows(); ++t)
    if ((sphere.row(s.triangles(t, 0)) + sphere.row(s.triangles(t, 1)) + sphere.row(s.triangles(t, 2))).z() > 0.9)
      keep.push_back(static_cast<int>(t));
  TriSurface patch;
  patch.triangles.resize(static_cast<Eigen::Index>(keep.size()), 3);
  std::vector<Eigen::RowVector3d> points;
  for (size_t k = 0; k < keep.size(); ++k)
    for (int c = 0; c < 3; ++c) {
      int& v = id[static_cast<size_t>(s.triangles(keep[k], c))];
      if (v < 0) v = static_cast<int>(points.size()), points.push_back(s.vertices.row(s.triangles(keep[k], c)));
      patch.triangles(static_cast<Eigen::Index>(k), c) = v;
    }
  patch.vertices.resize(static_cast<Eigen::Index>(points.size()), 3);
  for (size_t i = 0; i < points.size(); ++i) patch.vertices.row(static_cast<Eigen::Index>(i)) = points[i];
  try {
    validate_disk_surface(patch, "the patch");
    const SurfaceMapResult r = map_to_disk(patch);
    d.patch_map = r.report;
    d.patch_mapped = true;
    TriSurface disk{r.sphere, mapped_faces(patch.triangles, r), {}, {}};
    disk.point_data.push_back({"original_position", extend_to_mapped(patch.vertices, r), false});
    disk.cell_data.push_back({"face_area_ratio", r.report.final.face_ratio, false});
    write_surface((out / "colin27_patch_disk.vtp").string(), disk);
  } catch (const InputError& e) {
    d.patch_note = e.what();
  }
}

}  // namespace

SurfaceDemo surface_demo(const TetMesh& tmpl, const TetMesh& subj, const fs::path& out) {
  SurfaceDemo d;
  const LabelledSurface t = boundary_with_labels(tmpl), s = boundary_with_labels(subj);
  validate_closed_surface(t.surface, "colin27's boundary");
  validate_closed_surface(s.surface, "the subject's boundary");
  const SurfaceMapResult tm = map_to_sphere(t.surface), sm = map_to_sphere(s.surface);
  d.template_map = tm.report;
  d.subject_map = sm.report;
  const Eigen::VectorXd tc = mean_curvature(t.surface), sc = mean_curvature(s.surface);
  write_sphere(out / "colin27_sphere.vtp", tm.sphere, t, tc);
  write_sphere(out / "subject_sphere.vtp", sm.sphere, s, sc);
  // landmarks: the centroids on the sphere of the regions both boundaries carry, held-out ones aside
  const std::map<int, Eigen::Vector3d> from = region_centroids(sm.sphere, s), to = region_centroids(tm.sphere, t);
  std::vector<Eigen::Vector3d> p, q;
  for (const auto& [l, c] : from)
    if (to.count(l) && std::find(kSurfaceHeldOut.begin(), kSurfaceHeldOut.end(), l) == kSurfaceHeldOut.end())
      p.push_back(c), q.push_back(to.at(l));
  d.landmarks = static_cast<int>(p.size());
  if (d.landmarks < 3) throw NumericalError("demo: fewer than 3 regions on both boundaries to register the spheres by");
  Points lp(d.landmarks, 3), lq(d.landmarks, 3);
  for (int i = 0; i < d.landmarks; ++i) lp.row(i) = p[static_cast<size_t>(i)].transpose(), lq.row(i) = q[static_cast<size_t>(i)].transpose();
  d.by_landmarks = register_on_sphere(sm.sphere, s.surface.triangles, lp, lq);
  const SphereTemplate templ{tm.sphere, t.surface.triangles, tc};
  d.by_curvature = register_on_sphere(sm.sphere, s.surface.triangles, sc, templ, lp, lq);
  d.by_curvature_alone = register_on_sphere(sm.sphere, s.surface.triangles, sc, templ, Points(0, 3), Points(0, 3));
  write_sphere(out / "subject_sphere_registered.vtp", d.by_curvature.points, s, sc);
  const Points samples = fibonacci(kDiceSamples);
  const std::vector<int> truth = labels_at(tm.sphere, t, samples);
  d.dice_before = dice(labels_at(sm.sphere, s, samples), truth);
  d.dice_landmarks = dice(labels_at(d.by_landmarks.points, s, samples), truth);
  d.dice_curvature = dice(labels_at(d.by_curvature.points, s, samples), truth);
  d.dice_curvature_alone = dice(labels_at(d.by_curvature_alone.points, s, samples), truth);
  patch_to_disk(t.surface, tm.sphere, out, d);
  return d;
}

Json to_json(const SurfaceDemo& d, const RegionNames& names) {
  Json j = Json::object();
  j["colin27_sphere"] = to_json(d.template_map);
  j["subject_sphere"] = to_json(d.subject_map);
  j["landmarks"] = d.landmarks;
  j["registration_landmarks"] = to_json(d.by_landmarks, SurfaceRegistrationOptions{});
  j["registration_curvature"] = to_json(d.by_curvature, SurfaceRegistrationOptions{});
  j["registration_curvature_alone"] = to_json(d.by_curvature_alone, SurfaceRegistrationOptions{});
  Json held = Json::array();
  for (size_t i = 0; i < kSurfaceHeldOut.size(); ++i) {
    Json o = Json::object();
    o["label"] = kSurfaceHeldOut[i];
    o["name"] = name_of(names, kSurfaceHeldOut[i]);
    o["dice_sphere_before"] = d.dice_before[i];
    o["dice_sphere_landmarks"] = d.dice_landmarks[i];
    o["dice_sphere_curvature"] = d.dice_curvature[i];
    o["dice_sphere_curvature_alone"] = d.dice_curvature_alone[i];
    held.push_back(o);
  }
  j["held_out"] = held;
  if (d.patch_mapped) j["patch_disk"] = to_json(d.patch_map);
  else j["patch_disk_skipped"] = d.patch_note;
  return j;
}

std::string surface_summary(const SurfaceDemo& d, const RegionNames& names) {
  std::ostringstream o;
  auto pct = [](const SurfaceMetrics& m) { return strprintf("%.2f%%", 100 * m.face_area_ratio.mean_abs_dev); };
  o << "surfaces: the boundaries to the sphere, face area |r-1| " << pct(d.template_map.final) << " (colin27, "
    << d.template_map.faces << " faces) and " << pct(d.subject_map.final) << " (subject), "
    << d.template_map.final.flipped_faces + d.subject_map.final.flipped_faces << " flipped\n"
    << "registration on the sphere: " << d.landmarks << " region centroids, then the mean curvature (correlation "
    << strprintf("%.2f -> %.2f", d.by_curvature.match.correlation_before, d.by_curvature.match.correlation_after)
    << "), face area |r-1| " << pct(d.by_curvature.metrics) << ", " << d.by_curvature.metrics.flipped_faces << " flipped; "
    << "the curvature alone: a rotation of "
    << strprintf("%.0f deg", Eigen::AngleAxisd(d.by_curvature_alone.match.rotation).angle() * 180 / M_PI)
    << " found first (smoothed correlation "
    << strprintf("%.2f -> %.2f", d.by_curvature_alone.match.search_correlation_identity, d.by_curvature_alone.match.search_correlation_best)
    << "), face area |r-1| " << pct(d.by_curvature_alone.metrics) << ", " << d.by_curvature_alone.metrics.flipped_faces
    << " flipped; Dice of the held-out regions on the sphere:\n"
    << strprintf("  %-34s %10s %10s %10s %10s\n", "", "before", "landmarks", "+curvature", "curvature");
  for (size_t i = 0; i < kSurfaceHeldOut.size(); ++i)
    o << strprintf("  %-34s %10.3f %10.3f %10.3f %10.3f\n", name_of(names, kSurfaceHeldOut[i]).c_str(), d.dice_before[i],
                   d.dice_landmarks[i], d.dice_curvature[i], d.dice_curvature_alone[i]);
  if (d.patch_mapped)
    o << "a cortical patch of colin27 (" << d.patch_map.faces << " faces) to the disk: face area |r-1| " << pct(d.patch_map.final)
      << ", " << d.patch_map.final.flipped_faces << " flipped, " << d.patch_map.ears << " ears ("
      << d.patch_map.split_edges << " split)\n";
  else
    o << "the cortical patch was not a disk: " << d.patch_note << "\n";
  return o.str();
}

}  // namespace vpm::cli
