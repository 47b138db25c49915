// vpm demo [--out DIR]: the whole pipeline on the Colin27 brain that Debian's mricron-data
// ships. Two subjects (Colin27 with the AAL atlas, and a smoothly deformed copy of both images
// standing in for a second subject) are meshed, mapped to the unit ball, and the second is
// registered to the first by the centroids of AAL regions; the Dice overlap of held-out regions
// (caudate, thalamus) is measured in the common ball before and after registration.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <set>
#include <sstream>

#include "cli.hpp"
#include "vpm/ball_map.hpp"
#include "vpm/collective.hpp"
#include "vpm/device.hpp"
#include "vpm/error.hpp"
#include "vpm/image.hpp"
#include "vpm/io.hpp"
#include "vpm/json.hpp"
#include "vpm/mesh_image.hpp"
#include "vpm/registration.hpp"
#include "vpm/timing.hpp"
#include "vpm/format.hpp"

namespace {

namespace fs = std::filesystem;
using vpm::Clock;
using vpm::seconds_since;
using vpm::strprintf;


// Regions whose overlap is measured; they are never used as landmarks (held out).
const std::vector<int> kEvaluated = {71, 72, 77, 78};  // Caudate_L/R, Thalamus_L/R

// The second subject: Colin27 resampled through a smooth, invertible deformation (world mm):
// an anisotropic scaling about the brain centre plus four Gaussian displacement bumps (largest
// displacement gradient about 0.2, so the map stays a diffeomorphism).
Eigen::Vector3d deformation(const Eigen::Vector3d& c, const Eigen::Vector3d& x) {
  static const double kScale[3] = {1 / 1.06, 1 / 0.94, 1 / 1.03};
  static const double kBumps[4][6] = {{25, 20, 10, 5, -4, 3},
                                      {-25, -15, 20, -4, 5, -3},
                                      {10, -30, -15, 3, 4, 5},
                                      {-15, 25, -20, -5, -3, -4}};
  const double s2 = 2 * 22.0 * 22.0;
  Eigen::Vector3d y;
  for (int k = 0; k < 3; ++k) y(k) = c(k) + kScale[k] * (x(k) - c(k));
  for (const auto& b : kBumps) {
    const Eigen::Vector3d centre = c + Eigen::Vector3d(b[0], b[1], b[2]);
    y += std::exp(-(x - centre).squaredNorm() / s2) * Eigen::Vector3d(b[3], b[4], b[5]);
  }
  return y;
}

Eigen::Vector3d mask_centroid(const vpm::Image& im) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  double n = 0;
  for (int k = 0; k < im.dims[2]; ++k)
    for (int j = 0; j < im.dims[1]; ++j)
      for (int i = 0; i < im.dims[0]; ++i)
        if (im.at(i, j, k) > 0) {
          sum += Eigen::Vector3d(i, j, k);
          n += 1;
        }
  if (n == 0) throw vpm::InputError(im.path + ": empty mask (no voxel > 0)");
  return im.to_world(sum / n);
}

std::map<int, std::string> aal_names(const std::string& path) {
  std::map<int, std::string> names;
  std::ifstream in(path);
  int id;
  std::string name, code;
  while (in >> id >> name >> code) names[id] = name;
  return names;
}


// Meshes, maps and writes one subject; returns the map and fills `report`.
vpm::BallMap mesh_and_map(vpm::Device& dev, const vpm::Image& image, const vpm::Image& atlas,
                          const vpm::MeshImageOptions& mo, const std::string& name, const fs::path& out,
                          vpm::Json& report) {
  auto t0 = Clock::now();
  vpm::TetMesh mesh = vpm::mesh_image(image, mo, nullptr, &atlas);
  const double t_mesh = seconds_since(t0);
  vpm::write_mesh((out / (name + ".vtu")).string(), mesh);
  const vpm::ValidationReport vr = vpm::validate_mesh(mesh, name);
  vpm::cli::info("demo: " + name + ": " + std::to_string(mesh.num_vertices()) + " vertices, " +
                 std::to_string(mesh.num_tets()) + " tets, smallest dihedral " +
                 strprintf("%.1f", vr.min_dihedral_deg) + " deg (" + strprintf("%.1f", t_mesh) + " s); mapping");
  t0 = Clock::now();
  vpm::BallMapOptions bo;
  bo.volume.progress = [&](const std::string& s) { vpm::cli::progress("demo: " + name + ": " + s); };
  vpm::BallMap bm = vpm::map_to_ball(dev, mesh, vr, name, bo);
  const double t_map = seconds_since(t0);
  vpm::write_mesh((out / (name + "_ball.vtu")).string(), bm.mesh);
  vpm::write_json_file((out / (name + "_map.json")).string(), vpm::to_json(bm));
  report = vpm::Json::object();
  report["vertices"] = mesh.num_vertices();
  report["tets"] = mesh.num_tets();
  report["min_dihedral_deg"] = vr.min_dihedral_deg;
  report["mesh_seconds"] = t_mesh;
  report["map_seconds"] = t_map;
  report["initial"] = vpm::to_json(bm.initial);
  report["final"] = vpm::to_json(bm.final);
  return bm;
}

int run(const vpm::cli::Command& self, const std::vector<std::string>& argv) {
  const std::string kUsage = vpm::cli::synopsis(self);
  using namespace vpm;
  cli::Args args(argv, self);
  args.expect_positional(0, std::string("usage: ") + kUsage);
  const fs::path out = args.get("--out", "out/demo");
  const fs::path data = args.get("--data", "/usr/share/mricron/templates");
  const int grid = args.get_int("--grid", 96);
  if (grid < 8 || grid > 512) throw InputError("--grid: expected 8 to 512 cells a side");
  RegistrationOptions ro;
  ro.width_factor = args.get_double("--width-factor", ro.width_factor);
  if (!(ro.width_factor > 0)) throw InputError("--width-factor: must be positive");
  MeshImageOptions mo;
  mo.target_vertices = args.get_int("--target-vertices", mo.target_vertices);
  if (mo.target_vertices < 100) throw InputError("--target-vertices: expected at least 100");
  mo.progress = [](const std::string& s) { cli::progress("demo: mesh-image: " + s); };
  const fs::path image_path = data / "ch2bet.nii.gz", atlas_path = data / "aal.nii.gz";
  for (const fs::path& p : {image_path, atlas_path})
    if (!fs::exists(p))
      throw InputError(p.string() + ": not found (Debian's mricron-data ships it: run scripts/setup.sh)");
  std::error_code ec;
  fs::create_directories(out, ec);
  if (ec) throw InputError(out.string() + ": cannot create the output folder: " + ec.message());

  const auto t_start = Clock::now();
  Device& dev = Device::current();
  Json timings = Json::object();
  auto t0 = Clock::now();
  const Image image = read_nifti(image_path.string());
  const Image atlas = read_nifti(atlas_path.string());
  const Eigen::Vector3d centre = mask_centroid(image);
  const auto pull = [&](const Eigen::Vector3d& x) { return deformation(centre, x); };
  const Image image_b = resample_image(image, pull, Interpolation::linear);
  const Image atlas_b = resample_image(atlas, pull, Interpolation::nearest);
  timings["read_and_deform"] = seconds_since(t0);

  // 1-3. Mesh and map both subjects.
  Json subjects = Json::object();
  const BallMap tmpl = mesh_and_map(dev, image, atlas, mo, "colin27", out, subjects["colin27"]);
  const BallMap subj = mesh_and_map(dev, image_b, atlas_b, mo, "subject", out, subjects["subject"]);

  // 4. Landmarks: centroids of the AAL regions both maps carry (evaluated regions held out).
  const std::vector<int> lab_t = cell_labels(tmpl.mesh), lab_s = cell_labels(subj.mesh);
  std::set<int> present_t(lab_t.begin(), lab_t.end()), present_s(lab_s.begin(), lab_s.end());
  std::vector<int> landmark_labels;
  for (int l : present_t)
    if (l > 0 && present_s.count(l) && std::find(kEvaluated.begin(), kEvaluated.end(), l) == kEvaluated.end())
      landmark_labels.push_back(l);
  const Points src = label_centroids(subj.mesh.vertices, subj.mesh.tets, lab_s, landmark_labels);
  const Points dst = label_centroids(tmpl.mesh.vertices, tmpl.mesh.tets, lab_t, landmark_labels);
  write_landmarks_csv((out / "landmarks.csv").string(), src);
  write_landmarks_csv((out / "targets.csv").string(), dst);

  // 5. Register the subject's ball to the template's.
  cli::info("demo: registering subject to colin27 by " + std::to_string(landmark_labels.size()) +
            " region centroids");
  t0 = Clock::now();
  Points registered = subj.mesh.vertices;
  const RegistrationResult reg = register_landmarks(dev, registered, subj.mesh.tets, src, dst, ro);
  timings["register"] = seconds_since(t0);
  const MapMetrics rm = map_metrics(dev, subj.mesh.vertices, registered, subj.mesh.tets);
  TetMesh reg_mesh = subj.mesh;
  reg_mesh.vertices = registered;
  reg_mesh.set_point_field("registration_vertex_volume_ratio", rm.vertex_ratio);
  reg_mesh.set_cell_field("registration_tet_volume_ratio", rm.tet_ratio);
  write_mesh((out / "subject_registered.vtu").string(), reg_mesh);

  // 6. Overlap in the common ball, before and after registration.
  t0 = Clock::now();
  const Points samples = ball_grid_points(grid);
  const std::vector<int> s_t = sample_labels(tmpl.mesh.vertices, tmpl.mesh.tets, lab_t, samples);
  const std::vector<int> s_before = sample_labels(subj.mesh.vertices, subj.mesh.tets, lab_s, samples);
  const std::vector<int> s_after = sample_labels(registered, subj.mesh.tets, lab_s, samples);
  const auto d_before = dice_overlap(s_t, s_before, kEvaluated);
  const auto d_after = dice_overlap(s_t, s_after, kEvaluated);
  const auto l_before = dice_overlap(s_t, s_before, landmark_labels);
  const auto l_after = dice_overlap(s_t, s_after, landmark_labels);
  timings["overlap"] = seconds_since(t0);
  timings["total"] = seconds_since(t_start);

  const std::map<int, std::string> names = aal_names((data / "aal.nii.txt").string());
  auto name_of = [&](int l) { return names.count(l) ? names.at(l) : "label " + std::to_string(l); };
  auto mean_dice = [](const std::vector<LabelOverlap>& v) {
    double s = 0;
    for (const auto& o : v) s += o.dice;
    return v.empty() ? 0.0 : s / v.size();
  };

  Json report = Json::object();
  report["device"] = dev.name();
  report["data"] = data.string();
  report["subjects"] = subjects;
  Json jr = to_json(registration_summary(reg, rm));
  jr["landmarks"] = static_cast<long>(landmark_labels.size());
  jr["rotation_deg"] = reg.report.rotation_deg;
  report["registration"] = jr;
  Json jd = Json::array();
  for (size_t i = 0; i < kEvaluated.size(); ++i) {
    Json o = Json::object();
    o["label"] = kEvaluated[i];
    o["name"] = name_of(kEvaluated[i]);
    o["dice_before"] = d_before[i].dice;
    o["dice_after"] = d_after[i].dice;
    jd.push_back(o);
  }
  Json jo = Json::object();
  jo["grid_cells_per_axis"] = grid;
  jo["sample_points"] = static_cast<long>(samples.rows());
  jo["held_out"] = jd;
  jo["landmark_regions_mean_dice_before"] = mean_dice(l_before);
  jo["landmark_regions_mean_dice_after"] = mean_dice(l_after);
  report["overlap"] = jo;
  report["timings_s"] = timings;
  write_json_file((out / "demo.json").string(), report);

  // The summary table (stdout).
  std::ostringstream t;
  auto row = [&](const std::string& what, const std::string& a, const std::string& b) {
    char line[160];
    std::snprintf(line, sizeof line, "  %-34s %14s %14s\n", what.c_str(), a.c_str(), b.c_str());
    t << line;
  };
  const Json& js_t = *subjects.find("colin27");
  const Json& js_s = *subjects.find("subject");
  auto num = [](const Json& j, const char* k) { return j.find(k)->number(); };
  t << "vpm demo on " << dev.name() << " (Colin27 + AAL from " << data.string() << ")\n";
  row("", "colin27", "subject");
  row("mesh vertices / tets", std::to_string(int(num(js_t, "vertices"))) + "/" + std::to_string(int(num(js_t, "tets"))),
      std::to_string(int(num(js_s, "vertices"))) + "/" + std::to_string(int(num(js_s, "tets"))));
  row("smallest dihedral angle (deg)", strprintf("%.1f", num(js_t, "min_dihedral_deg")), strprintf("%.1f", num(js_s, "min_dihedral_deg")));
  row("initial map: vertex / tet |r-1|",
      strprintf("%.1f%%", 100 * tmpl.initial.vertex_volume_ratio.mean_abs_dev) + " / " + strprintf("%.1f%%", 100 * tmpl.initial.tet_volume_ratio.mean_abs_dev),
      strprintf("%.1f%%", 100 * subj.initial.vertex_volume_ratio.mean_abs_dev) + " / " + strprintf("%.1f%%", 100 * subj.initial.tet_volume_ratio.mean_abs_dev));
  row("volume map: vertex / tet |r-1|",
      strprintf("%.2f%%", 100 * tmpl.final.vertex_volume_ratio.mean_abs_dev) + " / " + strprintf("%.2f%%", 100 * tmpl.final.tet_volume_ratio.mean_abs_dev),
      strprintf("%.2f%%", 100 * subj.final.vertex_volume_ratio.mean_abs_dev) + " / " + strprintf("%.2f%%", 100 * subj.final.tet_volume_ratio.mean_abs_dev));
  row("inverted tets", std::to_string(tmpl.final.inverted_tets), std::to_string(subj.final.inverted_tets));
  row("mesh + map seconds", strprintf("%.1f", num(js_t, "mesh_seconds")) + " + " + strprintf("%.1f", num(js_t, "map_seconds")),
      strprintf("%.1f", num(js_s, "mesh_seconds")) + " + " + strprintf("%.1f", num(js_s, "map_seconds")));
  t << "registration of subject to colin27: " << landmark_labels.size() << " region centroids, landmark rms "
    << strprintf("%.1e", reg.landmark_rms_error) << ", max |u.n| " << strprintf("%.1e", reg.max_normal_velocity)
    << ", vertex / tet |r-1| " << strprintf("%.2f%%", 100 * rm.vertex_volume_ratio.mean_abs_dev) << " / "
    << strprintf("%.2f%%", 100 * rm.tet_volume_ratio.mean_abs_dev) << ", " << rm.inverted_tets << " inverted, "
    << strprintf("%.1f", num(timings, "register")) << " s\n";
  t << "Dice with colin27 in the ball (" << samples.rows() << " points; held-out regions):\n";
  row("", "before", "after");
  for (size_t i = 0; i < kEvaluated.size(); ++i)
    row(name_of(kEvaluated[i]), strprintf("%.3f", d_before[i].dice), strprintf("%.3f", d_after[i].dice));
  row("mean of the landmark regions", strprintf("%.3f", mean_dice(l_before)), strprintf("%.3f", mean_dice(l_after)));
  t << "total " << strprintf("%.1f", num(timings, "total")) << " s; wrote " << (out / "demo.json").string()
    << " and the meshes (.vtu, open in ParaView) in " << out.string() << "\n";
  std::cout << t.str();
  return 0;
}

vpm::cli::Registrar reg(
    {"demo", "", "the whole pipeline on Debian's Colin27 brain and a deformed copy",
     {{"--out", "DIR", "output folder (default out/demo)"},
      {"--data", "DIR", "mricron templates folder (default /usr/share/mricron/templates)"},
      {"--target-vertices", "N", "mesh density (default 5200, the paper's size)"},
      {"--grid", "N", "ball grid for the Dice overlap, N^3 points (default 96)"},
      {"--width-factor", "F", "registration kernel width factor (default 0.5)"}},
     run});
}  // namespace
