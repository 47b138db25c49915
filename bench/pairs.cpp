// The benchmark of registered pairs: `vpm demo`'s pipeline (apps/demo_pipeline.hpp) on Colin27 and
// a copy of it through a seeded deformation (--seed, --max-rotation, --incompressible; --ceiling:
// Colin27 itself meshed at another size), with every registration setting open, measured by the
// Dice of the held-out regions in the common ball (labels read from the tets and from each
// subject's atlas through its map), in the subject's image space, against the bound volumes
// allow, and against the ideal registration known from the deformation. bench/paper/run.sh
// (the paper's Table 2), bench/forces/run.sh and scripts/gpu/run.sh run it.
//
//   vpm_bench_pairs [--out DIR] [--seed S] [--max-rotation DEG] [--incompressible] ... (--help)
//
// Writes DIR/demo.json (the demo's keys plus "deformation", the ball measures and "ideal") and the
// meshes; subject_registered.vtu carries each vertex's distance to the ideal registration
// (error_to_ideal) and its ideal position (ideal_x, ideal_y, ideal_z; read by
// bench/register_peers/landmark_truth.py).
#include <exception>
#include <filesystem>
#include <iostream>
#include <sstream>

#include "apps/cli.hpp"
#include "apps/demo_deformation.hpp"
#include "apps/demo_pipeline.hpp"
#include "apps/dense_options.hpp"
#include "pairs/ideal.hpp"
#include "pairs/overlap.hpp"
#include "vpm/device.hpp"
#include "vpm/error.hpp"
#include "vpm/format.hpp"
#include "vpm/io.hpp"
#include "vpm/json.hpp"
#include "vpm/registration_preset.hpp"
#include "vpm/timing.hpp"

namespace {

namespace fs = std::filesystem;
using vpm::Clock;
using vpm::Points;
using vpm::seconds_since;
using vpm::strprintf;
using vpm::bench::Overlap;
using vpm::bench::volume_bound;
using vpm::cli::kDemoHeldOut;

constexpr vpm::DenseForce kDenseForce = vpm::DenseForce::both;  // as `vpm demo` and the workflow

vpm::DenseRegistrationOptions standard_dense() {
  vpm::DenseRegistrationOptions d;
  d.force = kDenseForce;
  return vpm::with_preset(vpm::RegistrationPreset::standard, d);
}

struct Settings {
  fs::path out, data;
  int grid = 96;
  unsigned seed = 0;          // 0: the demo's fixed deformation (apps/demo_deformation.hpp)
  double max_rotation = 0;    // degrees
  bool ceiling = false;       // the subject is Colin27 meshed at 1.3x the vertices
  bool incompressible = false;
  vpm::RegistrationOptions registration;
  vpm::DenseRegistrationOptions dense = standard_dense();
  vpm::MeshImageOptions meshing;
};

Settings parse_settings(const vpm::cli::Command& self, const std::vector<std::string>& argv) {
  vpm::cli::Args args(argv, self);
  args.expect_positional(0, "usage: " + vpm::cli::synopsis(self));
  Settings s;
  s.out = args.get("--out", VPM_BENCH_OUT "/pairs");
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
  s.meshing.progress = [](const std::string& line) { vpm::cli::progress("pairs: mesh-image: " + line); };
  for (const fs::path& p : {s.data / "ch2bet.nii.gz", s.data / "aal.nii.gz"})
    if (!fs::exists(p)) throw vpm::InputError(p.string() + ": not found (Debian's mricron-data ships it)");
  std::error_code ec;
  fs::create_directories(s.out, ec);
  if (ec) throw vpm::InputError(s.out.string() + ": cannot create the output folder: " + ec.message());
  return s;
}

using Names = vpm::cli::RegionNames;

vpm::Json overlap_json(const Settings& st, const Overlap& ov, const Names& names) {
  vpm::Json jd = vpm::Json::array();
  for (size_t i = 0; i < kDemoHeldOut.size(); ++i) {
    vpm::Json o = vpm::Json::object();
    o["label"] = kDemoHeldOut[i];
    o["name"] = vpm::cli::name_of(names, kDemoHeldOut[i]);
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
  return jo;
}

// The Dice tables below the demo's subject table.
std::string overlap_summary(const Overlap& ov, const Names& names) {
  std::ostringstream out;
  auto row = [&](const std::string& what, const std::string& a, const std::string& b, const std::string& c = "") {
    std::string line = strprintf("  %-34s %14s %14s %8s", what.c_str(), a.c_str(), b.c_str(), c.c_str());
    line.erase(line.find_last_not_of(' ') + 1);
    out << line << "\n";
  };
  auto pair = [](const vpm::LabelOverlap& image, const vpm::LabelOverlap& tet) {
    return strprintf("%.3f", image.dice) + " (" + strprintf("%.3f", tet.dice) + ")";
  };
  out << "Dice with colin27 in the ball (" << ov.points << " points; held-out regions), labels read from each\n"
      << "subject's atlas image through its map (tet labels, capped by the mesh resolution, in brackets);\n"
      << "bound: the most a volume-preserving registration can reach, from the two region volumes:\n";
  row("", "before", "after", "bound");
  for (size_t i = 0; i < kDemoHeldOut.size(); ++i)
    row(vpm::cli::name_of(names, kDemoHeldOut[i]), pair(ov.image_before[i], ov.before[i]),
        pair(ov.image_after[i], ov.after[i]), strprintf("%.3f", volume_bound(ov.image_before[i])));
  row("mean of the landmark regions",
      strprintf("%.3f", ov.image_landmark_before) + " (" + strprintf("%.3f", ov.landmark_before) + ")",
      strprintf("%.3f", ov.image_landmark_after) + " (" + strprintf("%.3f", ov.landmark_after) + ")");
  out << "Dice in the subject's image space (" << ov.subject_voxels
      << " voxels): colin27's atlas carried onto the subject's\nvoxels through the maps, as an image registration's "
         "transformix carries it:\n";
  for (size_t i = 0; i < kDemoHeldOut.size(); ++i)
    row(vpm::cli::name_of(names, kDemoHeldOut[i]), strprintf("%.3f", ov.subject_before[i].dice),
        strprintf("%.3f", ov.subject_after[i].dice));
  return out.str();
}

int run(const vpm::cli::Command& self, const std::vector<std::string>& argv) {
  const Settings st = parse_settings(self, argv);
  const auto t_start = Clock::now();
  vpm::Device& dev = vpm::Device::current();
  vpm::Json timings = vpm::Json::object();
  auto t0 = Clock::now();
  const vpm::Image image = vpm::read_nifti((st.data / "ch2bet.nii.gz").string());
  const vpm::Image atlas = vpm::read_nifti((st.data / "aal.nii.gz").string());
  const auto pull =
      vpm::cli::demo_deformation(vpm::cli::mask_centroid(image), st.seed, st.max_rotation, st.incompressible);
  const vpm::cli::DeformedSubject subject =
      st.ceiling ? vpm::cli::DeformedSubject{image, atlas} : vpm::cli::deformed_subject(image, atlas, pull);
  vpm::MeshImageOptions subject_meshing = st.meshing;
  if (st.ceiling) subject_meshing.target_vertices = static_cast<int>(1.3 * st.meshing.target_vertices);
  // a rotated brain can leave the image grid (the brainstem, at the bottom): cap it flat there
  if (st.max_rotation > 0) subject_meshing.close_at_border = true;
  timings["read_and_deform"] = seconds_since(t0);

  const auto tmpl = vpm::cli::mesh_and_map(dev, image, atlas, st.meshing, "colin27", st.out);
  vpm::write_nifti((st.out / "subject_t1.nii.gz").string(), subject.t1);  // for bench/paper/fig7.py
  vpm::write_nifti((st.out / "subject_atlas.nii.gz").string(), subject.atlas);
  const auto subj = vpm::cli::mesh_and_map(dev, subject.t1, subject.atlas, subject_meshing, "subject", st.out);
  const auto reg =
      vpm::cli::register_demo_subject(dev, tmpl, subj, st.registration, st.dense, image, subject.t1, st.out);
  timings["register"] = reg.seconds;
  const vpm::TetMesh& tm = tmpl.map.mesh;
  const vpm::TetMesh& sm = subj.map.mesh;
  auto overlap_of = [&](const Points& ball) {
    return vpm::bench::measure_overlap(tm, sm, ball, reg.tmpl_labels, reg.subj_labels, reg.landmark_labels,
                                       kDemoHeldOut, st.grid, atlas, subject.atlas);
  };
  const Overlap ov = overlap_of(reg.registered);
  timings["overlap"] = ov.seconds;
  t0 = Clock::now();
  const vpm::bench::IdealReport ideal = vpm::bench::measure_ideal(
      dev, sm, tm, reg.registered, st.ceiling ? [](const Eigen::Vector3d& y) { return y; } : pull, overlap_of);
  timings["ideal"] = seconds_since(t0);
  const Points& at = ideal.ideal.ball;
  vpm::cli::write_registered((st.out / "subject_registered.vtu").string(), sm, reg,
                             {{"error_to_ideal", ideal.error},
                              {"ideal_x", at.col(0)},
                              {"ideal_y", at.col(1)},
                              {"ideal_z", at.col(2)}});
  const double total = seconds_since(t_start);
  timings["total"] = total;

  const Names names = vpm::cli::aal_names((st.data / "aal.nii.txt").string());
  vpm::Json report = vpm::Json::object();
  report["device"] = dev.name();
  report["data"] = st.data.string();
  report["deformation"]["seed"] = static_cast<long>(st.seed);
  report["deformation"]["max_rotation_deg"] = st.max_rotation;
  report["deformation"]["incompressible"] = st.incompressible;
  report["deformation"]["rotation_deg"] = vpm::cli::demo_rotation_deg(st.seed, st.max_rotation);
  report["subjects"]["colin27"] = vpm::cli::to_json(tmpl);
  report["subjects"]["subject"] = vpm::cli::to_json(subj);
  report["registration"] = vpm::cli::to_json(reg);
  report["overlap"] = overlap_json(st, ov, names);
  report["ideal"] = vpm::bench::to_json(ideal, kDemoHeldOut);
  report["timings_s"] = timings;
  vpm::write_json_file((st.out / "demo.json").string(), report);
  std::cout << vpm::cli::subjects_summary("vpm_bench_pairs on " + dev.name() + " (Colin27 + AAL from " +
                                              st.data.string() + ")",
                                          tmpl, subj, reg)
            << overlap_summary(ov, names) << vpm::bench::ideal_summary(ideal) << "total " << strprintf("%.1f", total)
            << " s; wrote " << (st.out / "demo.json").string() << " and the meshes in " << st.out.string() << "\n";
  return 0;
}

vpm::cli::Command command() {
  vpm::cli::Command c{
      "", "", "the demo's pipeline on a seeded pair, measured against the ideal registration",
      {{"--out", "DIR", "output folder (default <build>/bench-results/pairs)"},
       {"--data", "DIR", "mricron templates folder (default /usr/share/mricron/templates)"},
       {"--target-vertices", "N", "mesh density (default 5200, the paper's size)"},
       {"--grid", "N", "ball grid for the Dice overlap, N^3 points (default 96)"},
       {"--preset", "landmarks|standard|accurate", "the dense settings by name (default standard); --dense-* override it"},
       {"--width-factor", "F", "registration kernel width factor (default 0.5)"},
       {"--restore-iterations", "N", "CGLS iterations per step of the volume restoration (default 10)"},
       {"--restore-rounds", "N", "steps of the volume restoration at most (default 12)"},
       {"--restore-min-gain", "G", "the restoration's steps end once one gains less than this fraction (default 0.01)"},
       {"--no-restore", "", "skip the volume restoration (to see what it costs in overlap)"},
       {"--seed", "S", "the subject's deformation: 0 (default) the demo's, S > 0 drawn from seed S"},
       {"--max-rotation", "DEG", "rotate the subject by up to DEG degrees about the brain centre (default 0)"},
       {"--incompressible", "", "the deformation keeps local volumes (the default one changes them by up to 20 %)"},
       {"--ceiling", "", "the subject is Colin27 itself meshed at 1.3x the vertices: the best overlap reachable"}},
      run};
  c.program = "vpm_bench_pairs";
  return vpm::cli::with_dense_options(c, "--preset", standard_dense().iterations, kDenseForce);
}

}  // namespace

int main(int argc, char** argv) {
  const vpm::cli::Command c = command();
  const std::vector<std::string> args(argv + 1, argv + argc);
  if (!args.empty() && (args[0] == "--help" || args[0] == "-h")) {
    std::cout << vpm::cli::help_text(c, true);
    return vpm::kExitOk;
  }
  try {
    return c.run(c, args);
  } catch (const vpm::InputError& e) {
    std::cerr << "vpm_bench_pairs: error: " << e.what() << '\n';
    return vpm::kExitInput;
  } catch (const vpm::NumericalError& e) {
    std::cerr << "vpm_bench_pairs: numerical failure: " << e.what() << '\n';
    return vpm::kExitNumerical;
  } catch (const std::exception& e) {
    std::cerr << "vpm_bench_pairs: error: " << e.what() << '\n';
    return vpm::kExitInternal;
  }
}
