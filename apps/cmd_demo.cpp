// vpm demo [--out DIR]: the whole pipeline on the Colin27 brain that Debian's mricron-data
// ships. Two subjects (Colin27 with the AAL atlas, and a smoothly deformed copy of both images
// standing in for a second subject) are meshed, mapped to the unit ball, and the second is
// registered to the first by the centroids of AAL regions and dense iterations; the Dice overlap
// of held-out regions (caudate, thalamus) is measured in the subject's image space before and
// after registration. Then the same two brains' boundary surfaces: mapped to the sphere, the
// subject's registered there by region centroids and its mean curvature, and a cortical patch
// mapped to the disk (demo_surface.hpp). The benchmark of registered pairs (bench/pairs.cpp) runs the same pipeline
// with seeded deformations and more measures.
#include <filesystem>
#include <iostream>
#include <sstream>

#include "cli.hpp"
#include "demo_deformation.hpp"
#include "demo_overlap.hpp"
#include "demo_pipeline.hpp"
#include "demo_surface.hpp"
#include "dense_options.hpp"
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
using vpm::seconds_since;
using vpm::strprintf;
using vpm::cli::kDemoHeldOut;

struct Settings {
  fs::path out, data;
  vpm::DenseRegistrationOptions dense;
  vpm::MeshImageOptions meshing;
};

// The demo's dense registration: a preset (standard: 12 iterations) pulled by the region
// boundaries and the T1 intensities together, as the workflow registers.
constexpr vpm::DenseForce kDenseForce = vpm::DenseForce::both;

Settings parse_settings(const vpm::cli::Command& self, const std::vector<std::string>& argv) {
  vpm::cli::Args args(argv, self);
  args.expect_positional(0, vpm::cli::synopsis(self));
  Settings s;
  s.out = args.get("--out", "out/demo");
  s.data = args.get("--data", "/usr/share/mricron/templates");
  vpm::DenseRegistrationOptions base;
  base.force = kDenseForce;
  s.dense = vpm::cli::preset_option(args, vpm::with_preset(vpm::RegistrationPreset::standard, base));
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

struct HeldOutDice {
  std::vector<vpm::LabelOverlap> before, after;
  long voxels = 0;
};

vpm::Json overlap_json(const HeldOutDice& d, const vpm::cli::RegionNames& names) {
  vpm::Json held = vpm::Json::array();
  for (size_t i = 0; i < kDemoHeldOut.size(); ++i) {
    vpm::Json o = vpm::Json::object();
    o["label"] = kDemoHeldOut[i];
    o["name"] = vpm::cli::name_of(names, kDemoHeldOut[i]);
    o["dice_subject_before"] = d.before[i].dice;
    o["dice_subject_after"] = d.after[i].dice;
    held.push_back(o);
  }
  vpm::Json j = vpm::Json::object();
  j["subject_voxels"] = d.voxels;
  j["held_out"] = held;
  return j;
}

std::string dice_summary(const HeldOutDice& d, const vpm::cli::RegionNames& names) {
  std::ostringstream out;
  out << "Dice of the held-out regions in the subject's image space (" << d.voxels
      << " voxels; Colin27's atlas carried\nonto the subject's voxels through the maps, as an image registration's "
         "transformix carries it):\n"
      << strprintf("  %-34s %14s %14s\n", "", "before", "after");
  for (size_t i = 0; i < kDemoHeldOut.size(); ++i)
    out << strprintf("  %-34s %14.3f %14.3f\n", vpm::cli::name_of(names, kDemoHeldOut[i]).c_str(), d.before[i].dice,
                     d.after[i].dice);
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
  const auto pull = vpm::cli::demo_deformation(vpm::cli::mask_centroid(image), 0, 0);
  const vpm::cli::DeformedSubject subject = vpm::cli::deformed_subject(image, atlas, pull);
  timings["read_and_deform"] = seconds_since(t0);

  const vpm::cli::DemoSubject tmpl = vpm::cli::mesh_and_map(dev, image, atlas, st.meshing, "colin27", st.out);
  vpm::write_nifti((st.out / "subject_t1.nii.gz").string(), subject.t1);  // the subject's own images
  vpm::write_nifti((st.out / "subject_atlas.nii.gz").string(), subject.atlas);
  const vpm::cli::DemoSubject subj =
      vpm::cli::mesh_and_map(dev, subject.t1, subject.atlas, st.meshing, "subject", st.out);
  const vpm::cli::DemoRegistration reg = vpm::cli::register_demo_subject(
      dev, tmpl, subj, vpm::RegistrationOptions{}, st.dense, image, subject.t1, st.out);
  timings["register"] = reg.seconds;
  t0 = Clock::now();
  HeldOutDice dice;
  const vpm::TetMesh& tm = tmpl.map.mesh;
  const vpm::TetMesh& sm = subj.map.mesh;
  dice.before = vpm::cli::subject_space_dice(tm, sm, sm.vertices, atlas, subject.atlas, kDemoHeldOut, dice.voxels);
  dice.after = vpm::cli::subject_space_dice(tm, sm, reg.registered, atlas, subject.atlas, kDemoHeldOut, dice.voxels);
  timings["overlap"] = seconds_since(t0);
  vpm::cli::write_registered((st.out / "subject_registered.vtu").string(), sm, reg);
  t0 = Clock::now();
  const vpm::cli::SurfaceDemo surfaces = vpm::cli::surface_demo(vpm::read_mesh((st.out / "colin27.vtu").string()),
                                                                vpm::read_mesh((st.out / "subject.vtu").string()), st.out);
  timings["surfaces"] = seconds_since(t0);
  const double total = seconds_since(t_start);
  timings["total"] = total;

  const vpm::cli::RegionNames names = vpm::cli::aal_names((st.data / "aal.nii.txt").string());
  vpm::Json report = vpm::Json::object();
  report["device"] = dev.name();
  report["data"] = st.data.string();
  report["subjects"]["colin27"] = vpm::cli::to_json(tmpl);
  report["subjects"]["subject"] = vpm::cli::to_json(subj);
  report["registration"] = vpm::cli::to_json(reg);
  report["overlap"] = overlap_json(dice, names);
  report["surfaces"] = vpm::cli::to_json(surfaces, names);
  report["timings_s"] = timings;
  vpm::write_json_file((st.out / "demo.json").string(), report);
  std::cout << vpm::cli::subjects_summary("vpm demo on " + dev.name() + " (Colin27 + AAL from " + st.data.string() + ")",
                                          tmpl, subj, reg)
            << dice_summary(dice, names) << vpm::cli::surface_summary(surfaces, names) << "total " << strprintf("%.1f", total) << " s; wrote "
            << (st.out / "demo.json").string() << " and the meshes (.vtu, open in ParaView) in " << st.out.string()
            << "\n";
  return 0;
}

vpm::cli::Registrar reg({"demo", "", "the whole pipeline on Debian's Colin27 brain and a deformed copy",
                         {{"--out", "DIR", "output folder (default out/demo)"},
                          {"--data", "DIR", "mricron templates folder (default /usr/share/mricron/templates)"},
                          {"--target-vertices", "N", "mesh density (default 5200, the paper's size)"},
                          {"--preset", "landmarks|standard|accurate",
                           "the registration's dense settings by name (default standard: 12 iterations; "
                           "docs/register.md \"Presets\")"}},
                         run});
}  // namespace
