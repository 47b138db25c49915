// vpm register MAPPED -o OUT --landmarks SRC.csv --targets DST.csv: volume-preserving
// landmark registration of a mesh already mapped to the unit ball (paper section 5).
#include <chrono>
#include <sstream>

#include "cli.hpp"
#include "vpm/device.hpp"
#include "vpm/error.hpp"
#include "vpm/io.hpp"
#include "vpm/json.hpp"
#include "vpm/metrics.hpp"
#include "vpm/registration.hpp"
#include "vpm/timing.hpp"

namespace {



int run(const vpm::cli::Command& self, const std::vector<std::string>& argv) {
  const std::string kUsage = vpm::cli::synopsis(self);
  using namespace vpm;
  const auto t_start = Clock::now();
  cli::Args args(argv, self);
  args.expect_positional(1, kUsage);
  const std::string in = args.positional()[0];
  const auto out = args.get("-o");
  const auto src = args.get("--landmarks");
  const auto dst = args.get("--targets");
  if (!out || !src || !dst)
    throw InputError(std::string("missing ") + (!out ? "-o OUT" : !src ? "--landmarks SRC.csv" : "--targets DST.csv") +
                     "; usage: " + kUsage);
  if (!is_mesh_path(*out)) throw InputError(*out + ": unknown file extension for a tet mesh");

  RegistrationOptions opt;
  opt.steps = args.get_int("--steps", opt.steps);
  if (opt.steps < 1 || opt.steps > 100000) throw InputError("--steps: expected 1 to 100000");
  if (args.has("--width") && args.has("--lambda"))
    throw InputError("--width and --lambda both given; use one");
  if (args.has("--width")) {
    const double w = args.get_double("--width", 0);
    if (!(w > 0)) throw InputError("--width: must be positive (ball units)");
    opt.lambda = 1 / (w * w);
  }
  if (args.has("--lambda")) {
    opt.lambda = args.get_double("--lambda", 0);
    if (!(opt.lambda > 0)) throw InputError("--lambda: must be positive");
  }
  opt.width_factor = args.get_double("--width-factor", opt.width_factor);
  if (!(opt.width_factor > 0)) throw InputError("--width-factor: must be positive");
  opt.width_loo = args.has("--width-loo");
  try {
    opt.boundary = parse_registration_boundary(args.get("--boundary", "tangent"));
    opt.field = parse_registration_field(args.get("--field", "per-step"));
  } catch (const RegistrationInputError& e) {
    throw InputError("--" + e.option + ": " + e.problem);
  }
  opt.boundary_samples = args.get_int("--boundary-samples", opt.boundary_samples);
  if (opt.boundary_samples < 1) throw InputError("--boundary-samples: must be positive");
  opt.rigid = !args.has("--no-rigid");
  opt.untangle = !args.has("--no-untangle");
  opt.restore_volumes = !args.has("--no-restore");

  auto t0 = Clock::now();
  TetMesh mesh = read_mesh(in);
  for (int t = 0; t < mesh.num_tets(); ++t)
    for (int c = 0; c < 4; ++c)
      if (mesh.tets(t, c) < 0 || mesh.tets(t, c) >= mesh.num_vertices())
        throw InputError(in + ": tet " + std::to_string(t) + ": vertex index " +
                         std::to_string(mesh.tets(t, c)) + " out of range");
  const LandmarkFile lm = read_landmarks_csv(*src, mesh.vertices);
  const LandmarkFile tg = read_landmarks_csv(*dst, mesh.vertices);
  if (lm.points.rows() != tg.points.rows())
    throw InputError(*src + " has " + std::to_string(lm.points.rows()) + " landmarks but " + *dst +
                     " has " + std::to_string(tg.points.rows()) + " targets");
  const double t_read = seconds_since(t0);
  cli::info("register: " + std::to_string(mesh.num_vertices()) + " vertices, " +
            std::to_string(mesh.num_tets()) + " tets, " + std::to_string(lm.points.rows()) +
            " landmarks, " + std::to_string(opt.steps) + " steps");

  Device& dev = Device::current();
  const Points before = mesh.vertices;
  Points ball = mesh.vertices;
  RegistrationResult res;
  t0 = Clock::now();
  try {
    res = register_landmarks(dev, ball, mesh.tets, lm.points, tg.points, opt);
  } catch (const RegistrationInputError& e) {
    using Subject = RegistrationInputError::Subject;
    const size_t i = static_cast<size_t>(e.landmark);
    if (e.subject == Subject::Mesh) throw InputError(in + ": " + e.what() + " (run `vpm map` first)");
    if (e.subject == Subject::Landmark && e.landmark >= 0 && i < lm.lines.size())
      throw InputError(*src + ":" + std::to_string(lm.lines[i]) + " / " + *dst + ":" + std::to_string(tg.lines[i]) +
                       ": " + e.what());
    if (e.subject == Subject::Option) throw InputError("--" + e.option + ": " + e.problem);
    throw InputError(*src + ", " + *dst + ": " + e.what());
  }
  const double t_register = seconds_since(t0);

  t0 = Clock::now();
  const MapMetrics mm = map_metrics(dev, before, ball, mesh.tets);
  const double t_metrics = seconds_since(t0);
  mesh.vertices = ball;
  mesh.set_point_field("vertex_volume_ratio", mm.vertex_ratio);
  mesh.set_cell_field("tet_volume_ratio", mm.tet_ratio);
  t0 = Clock::now();
  write_mesh(*out, mesh);
  const double t_write = seconds_since(t0);

  std::ostringstream line;
  line.precision(3);
  line << "registered: landmark rms error " << res.landmark_rms_error << " (max "
       << res.landmark_max_error << "), tet volume mean |r-1| "
       << mm.tet_volume_ratio.mean_abs_dev << ", vertex " << mm.vertex_volume_ratio.mean_abs_dev
       << ", max |u.n| " << res.max_normal_velocity << ", " << mm.inverted_tets
       << " inverted tets; wrote " << *out;
  cli::info(line.str());

  if (auto report_path = args.get("--report")) {
    Json r = Json::object();
    r["device"] = dev.name();
    Json input = Json::object();
    input["mesh"] = in;
    input["vertices"] = mesh.num_vertices();
    input["tets"] = mesh.num_tets();
    input["landmarks"] = static_cast<long>(lm.points.rows());
    r["input"] = input;
    const Json summary = to_json(registration_summary(res, mm));
    for (const char* k : {"landmark_rms_error", "landmark_max_error", "max_normal_velocity", "inverted_tets",
                          "vertex_volume_ratio", "tet_volume_ratio", "boundary_max_radius_error"})
      r[k] = *summary.find(k);
    r["registration"] = to_json(res);
    Json timings = Json::object();
    timings["read"] = t_read;
    timings["register"] = t_register;
    timings["metrics"] = t_metrics;
    timings["write"] = t_write;
    timings["total"] = seconds_since(t_start);
    r["timings_s"] = timings;
    write_json_file(*report_path, r);
  }
  return 0;
}

vpm::cli::Registrar reg(
    {"register", "MAPPED -o OUT", "register a mapped mesh: move landmarks to targets by a divergence-free flow",
     {{"--landmarks", "SRC.csv", "landmarks in MAPPED's ball (x,y,z or vertex_id a line)", true},
      {"--targets", "DST.csv", "their targets, paired line by line", true},
      {"--steps", "K", "pathline samples and RK4 steps (default 50)"},
      {"--report", "R.json", "write the report (landmark errors, metrics, timings)"},
      {"--width", "W", "Gaussian width of the RBF kernel in ball units", false, 1},
      {"--lambda", "L", "kernel exponent lambda = 1 / width^2", false, 1},
      {"--width-factor", "F", "width = F x the mean nearest-neighbour spacing of the landmarks (default 0.5)", false, 1},
      {"--width-loo", "", "choose the width factor by leave-one-out", false, 1},
      {"--boundary", "tangent|samples|none", "sphere-tangent kernel (default), eq. 29 samples, or none"},
      {"--boundary-samples", "N", "sphere samples for --boundary samples (default 200)", false, 0, true},
      {"--field", "per-step|steady", "a field per RK4 stage (default) or the paper's steady field"},
      {"--no-rigid", "", "skip the rotation step"},
      {"--no-untangle", "", "skip local untangling (folded results exit 3)"},
      {"--no-restore", "", "skip the volume restoration after the flow"}},
     run});
}  // namespace
