// vpm demo [--out DIR]: the whole pipeline on the Colin27 brain that Debian's mricron-data
// ships. Two subjects (Colin27 with the AAL atlas, and a smoothly deformed copy of both images
// standing in for a second subject) are meshed, mapped to the unit ball, and the second is
// registered to the first by the centroids of AAL regions; the Dice overlap of held-out regions
// (caudate, thalamus) is measured in the common ball before and after registration.
#include <algorithm>
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
#include "demo_deformation.hpp"
#include "demo_ideal.hpp"
#include "demo_overlap.hpp"
#include "dense_options.hpp"
#include "vpm/ball_map.hpp"
#include "vpm/collective.hpp"
#include "vpm/dense_registration.hpp"
#include "vpm/device.hpp"
#include "vpm/error.hpp"
#include "vpm/image.hpp"
#include "vpm/io.hpp"
#include "vpm/json.hpp"
#include "vpm/mesh_image.hpp"
#include "vpm/registration.hpp"
#include "vpm/sampling.hpp"
#include "vpm/template_registration.hpp"
#include "vpm/timing.hpp"
#include "vpm/format.hpp"

namespace {

namespace fs = std::filesystem;
using vpm::Clock;
using vpm::seconds_since;
using vpm::strprintf;
using vpm::Points;
using vpm::cli::Overlap;
using vpm::cli::volume_bound;


// Regions whose overlap is measured; they are never used as landmarks (held out).
const std::vector<int> kEvaluated = {71, 72, 77, 78};  // Caudate_L/R, Thalamus_L/R

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


// One subject meshed and mapped.
struct Subject {
  vpm::BallMap map;
  int vertices = 0, tets = 0;
  double min_dihedral_deg = 0, mesh_seconds = 0, map_seconds = 0;
};

vpm::Json to_json(const Subject& s) {
  vpm::Json j = vpm::Json::object();
  j["vertices"] = s.vertices;
  j["tets"] = s.tets;
  j["min_dihedral_deg"] = s.min_dihedral_deg;
  j["mesh_seconds"] = s.mesh_seconds;
  j["map_seconds"] = s.map_seconds;
  j["initial"] = vpm::to_json(s.map.initial);
  j["final"] = vpm::to_json(s.map.final);
  return j;
}

// Meshes, maps and writes one subject (NAME.vtu, NAME_ball.vtu, NAME_map.json).
Subject mesh_and_map(vpm::Device& dev, const vpm::Image& image, const vpm::Image& atlas,
                     const vpm::MeshImageOptions& mo, const std::string& name, const fs::path& out) {
  Subject s;
  auto t0 = Clock::now();
  vpm::TetMesh mesh = vpm::mesh_image(image, mo, nullptr, &atlas);
  s.mesh_seconds = seconds_since(t0);
  vpm::write_mesh((out / (name + ".vtu")).string(), mesh);
  const vpm::ValidationReport vr = vpm::validate_mesh(mesh, name);
  vpm::cli::info("demo: " + name + ": " + std::to_string(mesh.num_vertices()) + " vertices, " +
                 std::to_string(mesh.num_tets()) + " tets, smallest dihedral " +
                 strprintf("%.1f", vr.min_dihedral_deg) + " deg (" + strprintf("%.1f", s.mesh_seconds) + " s); mapping");
  t0 = Clock::now();
  vpm::BallMapOptions bo;
  bo.volume.progress = [&](const std::string& line) { vpm::cli::progress("demo: " + name + ": " + line); };
  s.map = vpm::map_to_ball(dev, mesh, vr, name, bo);
  s.map_seconds = seconds_since(t0);
  if (!s.map.convergence.converged)
    vpm::cli::convergence_status("demo: " + name, s.map.convergence, true);  // a warning line, no exit
  vpm::write_mesh((out / (name + "_ball.vtu")).string(), s.map.mesh);
  vpm::write_json_file((out / (name + "_map.json")).string(), vpm::to_json(s.map));
  s.vertices = mesh.num_vertices();
  s.tets = mesh.num_tets();
  s.min_dihedral_deg = vr.min_dihedral_deg;
  return s;
}

// The demo's dense registration: the standard preset (12 iterations) pulled by the region
// boundaries and the T1 intensities together (bench/results/register_dense/: held-out Dice up by 0.05-0.16
// over the landmarks).
constexpr vpm::DenseForce kDenseForce = vpm::DenseForce::both;
vpm::DenseRegistrationOptions demo_dense() {
  vpm::DenseRegistrationOptions d;
  d.force = kDenseForce;
  return vpm::with_preset(vpm::RegistrationPreset::standard, d);
}
const int kDenseIterations = demo_dense().iterations;

struct Settings {
  fs::path out, data;
  int grid = 96;
  unsigned seed = 0;          // --seed: 0 is the demo's fixed deformation (demo_deformation.hpp)
  double max_rotation = 0;    // --max-rotation DEG
  bool ceiling = false;  // --ceiling: the subject is Colin27 meshed at another size
  bool incompressible = false;  // --incompressible: the deformation keeps local volumes
  vpm::RegistrationOptions registration;
  vpm::DenseRegistrationOptions dense = demo_dense();
  vpm::MeshImageOptions meshing;
};

Settings parse_settings(const vpm::cli::Command& self, const std::vector<std::string>& argv) {
  vpm::cli::Args args(argv, self);
  args.expect_positional(0, "usage: " + vpm::cli::synopsis(self));
  Settings s;
  s.out = args.get("--out", "out/demo");
  s.data = args.get("--data", "/usr/share/mricron/templates");
  s.grid = args.get_int("--grid", 96);
  if (s.grid < 8 || s.grid > 512) throw vpm::InputError("--grid: expected 8 to 512 cells a side");
  s.registration.width_factor = args.get_double("--width-factor", s.registration.width_factor);
  if (!(s.registration.width_factor > 0)) throw vpm::InputError("--width-factor: must be positive");
  s.registration.restore_iterations = args.get_int("--restore-iterations", s.registration.restore_iterations);
  if (s.registration.restore_iterations < 1 || s.registration.restore_iterations > 10000)
    throw vpm::InputError("--restore-iterations: expected 1 to 10000");
  s.registration.restore_volumes = !args.has("--no-restore");
  vpm::cli::restore_step_options(args, s.registration);
  s.ceiling = args.has("--ceiling");
  s.incompressible = args.has("--incompressible");
  const int seed = args.get_int("--seed", 0);
  if (seed < 0) throw vpm::InputError("--seed: expected 0 or a positive integer");
  s.seed = static_cast<unsigned>(seed);
  s.max_rotation = args.get_double("--max-rotation", 0);
  if (!(s.max_rotation >= 0 && s.max_rotation <= 90)) throw vpm::InputError("--max-rotation: expected 0 to 90 degrees");
  s.dense = vpm::cli::dense_options(args, vpm::cli::preset_option(args, s.dense));
  s.meshing.target_vertices = args.get_int("--target-vertices", s.meshing.target_vertices);
  if (s.meshing.target_vertices < 100) throw vpm::InputError("--target-vertices: expected at least 100");
  s.meshing.progress = [](const std::string& line) { vpm::cli::progress("demo: mesh-image: " + line); };
  for (const fs::path& p : {s.data / "ch2bet.nii.gz", s.data / "aal.nii.gz"})
    if (!fs::exists(p))
      throw vpm::InputError(p.string() + ": not found (Debian's mricron-data ships it: run scripts/setup.sh)");
  std::error_code ec;
  fs::create_directories(s.out, ec);
  if (ec) throw vpm::InputError(s.out.string() + ": cannot create the output folder: " + ec.message());
  return s;
}

struct Registration {
  vpm::RegistrationResult result;   // the landmark stage, with the final landmark errors
  vpm::DenseRegistrationResult dense;
  vpm::MapMetrics metrics;  // against the subject's map before registration
  Points registered;
  std::vector<int> tmpl_labels, subj_labels;  // AAL label of each tet of the two maps
  std::vector<int> landmark_labels;           // the regions whose centroids were matched
  double seconds = 0;
};

// Registers the subject's ball to the template's by region centroids (register_to_template, the
// held-out regions excluded); writes the landmark files.
Registration register_subject(vpm::Device& dev, const Subject& tmpl, const Subject& subj, const Settings& st,
                              const vpm::Image& tmpl_image, const vpm::Image& subj_image) {
  Registration r;
  r.tmpl_labels = vpm::cell_labels(tmpl.map.mesh);
  r.subj_labels = vpm::cell_labels(subj.map.mesh);
  const vpm::TetMesh& sm = subj.map.mesh;
  vpm::TemplateRegistrationOptions opt;
  opt.exclude_labels = kEvaluated;  // held out: neither landmarks nor the dense force see them
  opt.flow = st.registration;
  opt.dense = st.dense;
  const auto t0 = Clock::now();
  vpm::TemplateRegistration out = vpm::register_to_template(dev, sm, tmpl.map.mesh, opt, {&subj_image, &tmpl_image});
  r.seconds = seconds_since(t0);
  r.landmark_labels = std::move(out.landmark_labels);
  vpm::write_landmarks_csv((st.out / "landmarks.csv").string(), out.landmarks);
  vpm::write_landmarks_csv((st.out / "targets.csv").string(), out.targets);
  vpm::cli::info("demo: registered subject to colin27 by " + std::to_string(r.landmark_labels.size()) +
                 " region centroids");
  r.registered = std::move(out.ball);
  r.result = out.result;
  if (out.dense) r.dense = std::move(*out.dense);
  r.metrics = vpm::map_metrics(dev, sm.vertices, r.registered, sm.tets);
  return r;  // subject_registered.vtu is written with the ideal registration's error (run)
}

using Names = std::map<int, std::string>;
std::string name_of(const Names& names, int l) { return names.count(l) ? names.at(l) : "label " + std::to_string(l); }

vpm::Json demo_json(const std::string& device, const Settings& st, const Subject& tmpl, const Subject& subj,
                    const Registration& reg, const Overlap& ov, const Names& names, vpm::Json timings) {
  vpm::Json report = vpm::Json::object();
  report["device"] = device;
  report["data"] = st.data.string();
  report["deformation"]["seed"] = static_cast<long>(st.seed);
  report["deformation"]["max_rotation_deg"] = st.max_rotation;
  report["deformation"]["incompressible"] = st.incompressible;
  report["deformation"]["rotation_deg"] = vpm::cli::demo_rotation_deg(st.seed, st.max_rotation);
  report["subjects"]["colin27"] = to_json(tmpl);
  report["subjects"]["subject"] = to_json(subj);
  vpm::Json jr = vpm::to_json(vpm::registration_summary(reg.result, reg.metrics));
  jr["landmarks"] = static_cast<long>(reg.landmark_labels.size());
  jr["rotation_deg"] = reg.result.report.rotation_deg;
  jr["dense"] = vpm::to_json(reg.dense);
  report["registration"] = jr;
  vpm::Json jd = vpm::Json::array();
  for (size_t i = 0; i < kEvaluated.size(); ++i) {
    vpm::Json o = vpm::Json::object();
    o["label"] = kEvaluated[i];
    o["name"] = name_of(names, kEvaluated[i]);
    o["dice_before"] = ov.before[i].dice;
    o["dice_after"] = ov.after[i].dice;
    o["dice_image_before"] = ov.image_before[i].dice;
    o["dice_image_after"] = ov.image_after[i].dice;
    o["dice_volume_bound"] = volume_bound(ov.image_before[i]);
    o["dice_subject_before"] = ov.subject_before[i].dice;
    o["dice_subject_after"] = ov.subject_after[i].dice;
    jd.push_back(o);
  }
  vpm::Json jo = vpm::Json::object();
  jo["grid_cells_per_axis"] = st.grid;
  jo["sample_points"] = ov.points;
  jo["subject_voxels"] = ov.subject_voxels;
  jo["held_out"] = jd;
  jo["landmark_regions_mean_dice_before"] = ov.landmark_before;
  jo["landmark_regions_mean_dice_after"] = ov.landmark_after;
  jo["landmark_regions_mean_dice_image_before"] = ov.image_landmark_before;
  jo["landmark_regions_mean_dice_image_after"] = ov.image_landmark_after;
  report["overlap"] = jo;
  report["timings_s"] = timings;
  return report;
}

std::string two_pcts(const char* f, const vpm::MapMetrics& m) {
  return strprintf(f, 100 * m.vertex_volume_ratio.mean_abs_dev) + " / " + strprintf(f, 100 * m.tet_volume_ratio.mean_abs_dev);
}

// The summary table (stdout).
void print_summary(const std::string& device, const Settings& st, const Subject& t, const Subject& s,
                   const Registration& reg, const Overlap& ov, const Names& names, double total,
                   const std::string& ideal) {
  std::ostringstream out;
  auto row = [&](const std::string& what, const std::string& a, const std::string& b, const std::string& c = "") {
    std::string line = strprintf("  %-34s %14s %14s %8s", what.c_str(), a.c_str(), b.c_str(), c.c_str());
    line.erase(line.find_last_not_of(' ') + 1);
    out << line << "\n";
  };
  out << "vpm demo on " << device << " (Colin27 + AAL from " << st.data.string() << ")\n";
  row("", "colin27", "subject");
  row("mesh vertices / tets", std::to_string(t.vertices) + "/" + std::to_string(t.tets),
      std::to_string(s.vertices) + "/" + std::to_string(s.tets));
  row("smallest dihedral angle (deg)", strprintf("%.1f", t.min_dihedral_deg), strprintf("%.1f", s.min_dihedral_deg));
  row("initial map: vertex / tet |r-1|", two_pcts("%.1f%%", t.map.initial), two_pcts("%.1f%%", s.map.initial));
  row("volume map: vertex / tet |r-1|", two_pcts("%.2f%%", t.map.final), two_pcts("%.2f%%", s.map.final));
  row("inverted tets", std::to_string(t.map.final.inverted_tets), std::to_string(s.map.final.inverted_tets));
  row("mesh + map seconds", strprintf("%.1f", t.mesh_seconds) + " + " + strprintf("%.1f", t.map_seconds),
      strprintf("%.1f", s.mesh_seconds) + " + " + strprintf("%.1f", s.map_seconds));
  out << "registration of subject to colin27: " << reg.landmark_labels.size() << " region centroids, landmark rms "
      << strprintf("%.1e", reg.result.landmark_rms_error) << ", max |u.n| " << strprintf("%.1e", reg.result.max_normal_velocity)
      << ", vertex / tet |r-1| " << two_pcts("%.2f%%", reg.metrics) << ", " << reg.metrics.inverted_tets << " inverted, "
      << std::count_if(reg.dense.iterations.begin(), reg.dense.iterations.end(), [](const auto& i) { return i.accepted; })
      << " of " << reg.dense.iterations.size() << " dense iterations kept, " << strprintf("%.1f", reg.seconds) << " s\n";
  out << "Dice with colin27 in the ball (" << ov.points << " points; held-out regions), labels read from each\n"
      << "subject's atlas image through its map (tet labels, capped by the mesh resolution, in brackets);\n"
      << "bound: the most a volume-preserving registration can reach, from the two region volumes:\n";
  auto pair = [](const vpm::LabelOverlap& image, const vpm::LabelOverlap& tet) {
    return strprintf("%.3f", image.dice) + " (" + strprintf("%.3f", tet.dice) + ")";
  };
  row("", "before", "after", "bound");
  for (size_t i = 0; i < kEvaluated.size(); ++i)
    row(name_of(names, kEvaluated[i]), pair(ov.image_before[i], ov.before[i]), pair(ov.image_after[i], ov.after[i]),
        strprintf("%.3f", volume_bound(ov.image_before[i])));
  row("mean of the landmark regions",
      strprintf("%.3f", ov.image_landmark_before) + " (" + strprintf("%.3f", ov.landmark_before) + ")",
      strprintf("%.3f", ov.image_landmark_after) + " (" + strprintf("%.3f", ov.landmark_after) + ")");
  out << "Dice in the subject's image space (" << ov.subject_voxels
      << " voxels): colin27's atlas carried onto the subject's\nvoxels through the maps, as an image registration's "
         "transformix carries it:\n";
  for (size_t i = 0; i < kEvaluated.size(); ++i)
    row(name_of(names, kEvaluated[i]), strprintf("%.3f", ov.subject_before[i].dice), strprintf("%.3f", ov.subject_after[i].dice));
  out << ideal;
  out << "total " << strprintf("%.1f", total) << " s; wrote " << (st.out / "demo.json").string()
      << " and the meshes (.vtu, open in ParaView) in " << st.out.string() << "\n";
  std::cout << out.str();
}

int run(const vpm::cli::Command& self, const std::vector<std::string>& argv) {
  const Settings st = parse_settings(self, argv);
  const auto t_start = Clock::now();
  vpm::Device& dev = vpm::Device::current();
  vpm::Json timings = vpm::Json::object();
  auto t0 = Clock::now();
  const vpm::Image image = vpm::read_nifti((st.data / "ch2bet.nii.gz").string());
  const vpm::Image atlas = vpm::read_nifti((st.data / "aal.nii.gz").string());
  const Eigen::Vector3d centre = mask_centroid(image);
  const auto pull = vpm::cli::demo_deformation(centre, st.seed, st.max_rotation, st.incompressible);
  // --ceiling: the subject is Colin27 itself, meshed at 1.3x the vertices, so the overlap after
  // registration is what independent meshing and mapping leave (the best any subject can reach)
  const vpm::cli::DeformedSubject deformed =
      st.ceiling ? vpm::cli::DeformedSubject{image, atlas} : vpm::cli::deformed_subject(image, atlas, pull);
  const vpm::Image& image_b = deformed.t1;
  const vpm::Image& atlas_b = deformed.atlas;
  vpm::MeshImageOptions subject_meshing = st.meshing;
  if (st.ceiling) subject_meshing.target_vertices = static_cast<int>(1.3 * st.meshing.target_vertices);
  // a rotated brain can leave the image grid (the brainstem, at the bottom): cap it flat there
  if (st.max_rotation > 0) subject_meshing.close_at_border = true;
  timings["read_and_deform"] = seconds_since(t0);

  const Subject tmpl = mesh_and_map(dev, image, atlas, st.meshing, "colin27", st.out);
  t0 = Clock::now();
  // the subject's own images, for viewers and bench/paper/fig7.py (its slices through the maps)
  vpm::write_nifti((st.out / "subject_t1.nii.gz").string(), image_b);
  vpm::write_nifti((st.out / "subject_atlas.nii.gz").string(), atlas_b);
  timings["write_subject_images"] = seconds_since(t0);
  const Subject subj = mesh_and_map(dev, image_b, atlas_b, subject_meshing, "subject", st.out);
  const Registration reg = register_subject(dev, tmpl, subj, st, image, image_b);
  timings["register"] = reg.seconds;
  const Overlap ov = vpm::cli::measure_overlap(tmpl.map.mesh, subj.map.mesh, reg.registered, reg.tmpl_labels,
                                               reg.subj_labels, reg.landmark_labels, kEvaluated, st.grid, atlas, atlas_b);
  timings["overlap"] = ov.seconds;
  t0 = Clock::now();
  const vpm::cli::IdealReport ideal = vpm::cli::measure_ideal(
      dev, subj.map.mesh, tmpl.map.mesh, reg.registered,
      st.ceiling ? [](const Eigen::Vector3d& y) { return y; } : pull, [&](const Points& ball) {
        return vpm::cli::measure_overlap(tmpl.map.mesh, subj.map.mesh, ball, reg.tmpl_labels, reg.subj_labels,
                                         reg.landmark_labels, kEvaluated, st.grid, atlas, atlas_b);
      });
  timings["ideal"] = seconds_since(t0);
  vpm::cli::write_registered((st.out / "subject_registered.vtu").string(), subj.map.mesh, reg.registered, reg.metrics,
                             ideal);
  const double total = seconds_since(t_start);
  timings["total"] = total;

  const Names names = aal_names((st.data / "aal.nii.txt").string());
  vpm::Json report = demo_json(dev.name(), st, tmpl, subj, reg, ov, names, timings);
  report["ideal"] = vpm::cli::to_json(ideal, kEvaluated);
  vpm::write_json_file((st.out / "demo.json").string(), report);
  print_summary(dev.name(), st, tmpl, subj, reg, ov, names, total, vpm::cli::ideal_summary(ideal));
  return 0;
}

vpm::cli::Registrar reg(vpm::cli::with_expert(vpm::cli::with_dense_options(
    {"demo", "", "the whole pipeline on Debian's Colin27 brain and a deformed copy",
     {{"--out", "DIR", "output folder (default out/demo)"},
      {"--data", "DIR", "mricron templates folder (default /usr/share/mricron/templates)"},
      {"--target-vertices", "N", "mesh density (default 5200, the paper's size)"},
      {"--grid", "N", "ball grid for the Dice overlap, N^3 points (default 96)"},
      {"--preset", "landmarks|standard|accurate", "the registration's dense settings by name (default standard: 12 "
       "iterations; docs/register.md \"Presets\"); --dense-* flags override it"},
      {"--width-factor", "F", "registration kernel width factor (default 0.5)"},
      {"--restore-iterations", "N",
       "CGLS iterations per step of the registration's volume restoration (default 10; more: lower volume "
       "distortion, the regions drift more)", false, 0, true},
      {"--restore-rounds", "N", "steps of the registration's volume restoration at most (default 12)", false, 0, true},
      {"--restore-min-gain", "G", "the restoration's steps end once one gains less than this fraction (default 0.01)",
       false, 0, true},
      {"--no-restore", "", "skip the registration's volume restoration (to see what it costs in overlap)", false, 0, true},
      {"--seed", "S", "the subject's deformation: 0 (default) the fixed one, S > 0 drawn from seed S"},
      {"--max-rotation", "DEG", "rotate the subject by up to DEG degrees about the brain centre (default 0)"},
      {"--incompressible", "", "the subject's deformation keeps local volumes (the default one changes them by up to 20 %)"},
      {"--ceiling", "", "the subject is Colin27 itself meshed at 1.3x the vertices: the best overlap reachable"}},
     run}, "--preset", kDenseIterations, kDenseForce),
    {"--grid", "--width-factor", "--restore-iterations", "--restore-rounds", "--restore-min-gain", "--no-restore",
     "--max-rotation", "--incompressible", "--ceiling"}));
}  // namespace
