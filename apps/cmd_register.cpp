// vpm register MAPPED -o OUT --landmarks SRC.csv --targets DST.csv: volume-preserving
// landmark registration of a mesh already mapped to the unit ball (paper section 5).
#include <chrono>
#include <sstream>

#include "cli.hpp"
#include "dense_options.hpp"
#include "register_surface.hpp"
#include "vpm/device.hpp"
#include "vpm/error.hpp"
#include "vpm/format.hpp"
#include "vpm/image.hpp"
#include "vpm/io.hpp"
#include "vpm/json.hpp"
#include "vpm/metrics.hpp"
#include "vpm/dense_registration.hpp"
#include "vpm/registration.hpp"
#include "vpm/template_registration.hpp"
#include "vpm/timing.hpp"

namespace {

using namespace vpm;

// Landmark error (ball units, about 0.07 mm in a brain) above which the registration warns.
constexpr double kLandmarkTolerance = 5e-4;

// The flag of a RegistrationOptions member a RegistrationInputError names.
std::string cli_flag(const std::string& option) {
  if (option == "boundary") return "--flow-boundary";
  return "--" + option;
}

RegistrationOptions parse_options(const cli::Args& args) {
  RegistrationOptions opt;
  opt.steps = args.get_int("--steps", opt.steps);
  if (opt.steps < 1 || opt.steps > 100000) throw InputError("--steps: expected 1 to 100000");
  if (args.has("--width") && args.has("--lambda")) throw InputError("--width and --lambda both given; use one");
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
    opt.boundary = parse_registration_boundary(args.get("--flow-boundary", "tangent"));
    opt.field = parse_registration_field(args.get("--field", "per-step"));
  } catch (const RegistrationInputError& e) {
    throw InputError(cli_flag(e.option) + ": " + e.problem);
  }
  opt.boundary_samples = args.get_int("--flow-boundary-samples", opt.boundary_samples);
  if (opt.boundary_samples < 1) throw InputError("--flow-boundary-samples: must be positive");
  opt.rigid = !args.has("--no-rigid");
  opt.untangle = !args.has("--no-untangle");
  opt.restore_volumes = !args.has("--no-restore");
  opt.restore_iterations = args.get_int("--restore-iterations", opt.restore_iterations);
  if (opt.restore_iterations < 1) throw InputError("--restore-iterations: must be positive");
  if (!opt.restore_volumes && args.has("--restore-iterations"))
    throw InputError("--restore-iterations: the restoration is off (--no-restore)");
  cli::restore_step_options(args, opt);
  return opt;
}

// The mapped mesh and its landmarks: two files checked against each other, or the landmarks
// register_to_template pairs with a template's registered or mapped mesh (--template).
struct Inputs {
  std::string in, out, src, dst, templ;
  TetMesh mesh, templ_mesh;
  LandmarkFile landmarks, targets;
  TemplateRegistrationOptions by_template;  // --template-landmarks, --exclude-labels, the dense step
  std::string image, templ_image;  // --image, --template-image: the image force's two images
  Image subject_image, template_image;
};

std::vector<int> label_list(const std::string& option, const std::string& text) {
  std::vector<int> out;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    try {
      size_t used = 0;
      out.push_back(std::stoi(item, &used));
      if (used != item.size()) throw std::invalid_argument(item);
    } catch (const std::exception&) {
      throw InputError(option + ": expected integer labels separated by commas, got '" + item + "'");
    }
  }
  return out;
}

// The template's options (--template-landmarks, --exclude-labels, --preset and the dense flags,
// the images), checked against each other.
void template_options(const cli::Args& args, Inputs& io) {
  for (const char* flag : {"--exclude-labels", "--template-landmarks", "--preset", "--dense-iterations", "--dense-widths",
                           "--dense-step", "--dense-force", "--image", "--template-image", "--dense-image-grid",
                           "--dense-image-smoothing"})
    if (io.templ.empty() && args.has(flag)) throw InputError(std::string(flag) + " needs --template");
  TemplateRegistrationOptions& t = io.by_template;
  try {
    t.landmarks = template_landmarks_from_string(args.get("--template-landmarks", "regions"));
  } catch (const InputError& e) {
    throw InputError(std::string("--template-landmarks: ") + e.what());
  }
  t.dense = cli::dense_options(args, cli::preset_option(args));
  io.image = args.get("--image").value_or("");
  io.templ_image = args.get("--template-image").value_or("");
  if (io.image.empty() != io.templ_image.empty())
    throw InputError(io.image.empty() ? "--template-image needs --image" : "--image needs --template-image");
  if (t.dense.force != DenseForce::labels && io.image.empty())
    throw InputError(std::string("--dense-force ") + to_string(t.dense.force) +
                     " needs --image SUBJECT.nii.gz and --template-image TEMPLATE.nii.gz");
  if (!io.image.empty() && t.dense.force == DenseForce::labels)  // read for nothing otherwise
    throw InputError("--image and --template-image need --dense-force image or both");
  if (const auto ex = args.get("--exclude-labels")) t.exclude_labels = label_list("--exclude-labels", *ex);
}

Inputs read_inputs(const cli::Args& args, const cli::Command& self) {
  const std::string usage = cli::synopsis(self);
  args.expect_positional(1, usage);
  Inputs io;
  io.in = args.positional()[0];
  const auto out = args.get("-o");
  const auto src = args.get("--landmarks");
  const auto dst = args.get("--targets");
  const auto templ = args.get("--template");
  if (templ && (src || dst)) throw InputError("--template and --landmarks/--targets both given; use one");
  if (!out || (!templ && (!src || !dst)))
    throw InputError(std::string("missing ") +
                     (!out ? "-o OUT" : !src ? "--landmarks SRC.csv (or --template)" : "--targets DST.csv") +
                     "; usage: " + usage);
  io.out = *out;
  io.src = src.value_or("");
  io.dst = dst.value_or("");
  io.templ = templ.value_or("");
  template_options(args, io);
  if (!is_mesh_path(io.out)) throw InputError(io.out + ": unknown file extension for a tet mesh");
  return io;
}

void read_files(Inputs& io) {
  io.mesh = read_mesh(io.in);
  for (int t = 0; t < io.mesh.num_tets(); ++t)
    for (int c = 0; c < 4; ++c)
      if (io.mesh.tets(t, c) < 0 || io.mesh.tets(t, c) >= io.mesh.num_vertices())
        throw InputError(io.in + ": tet " + std::to_string(t) + ": vertex index " + std::to_string(io.mesh.tets(t, c)) +
                         " out of range");
  if (!io.templ.empty()) {
    io.templ_mesh = read_mesh(io.templ);
    io.src = io.dst = io.templ + (io.by_template.landmarks == TemplateLandmarks::moments ? " (moments)" : " (region centroids)");
    if (!io.image.empty()) {
      io.subject_image = read_image(io.image);
      io.template_image = read_image(io.templ_image);
    }
    return;
  }
  io.landmarks = read_landmarks_csv(io.src, io.mesh.vertices);
  io.targets = read_landmarks_csv(io.dst, io.mesh.vertices);
  if (io.landmarks.points.rows() != io.targets.points.rows())
    throw InputError(io.src + " has " + std::to_string(io.landmarks.points.rows()) + " landmarks but " + io.dst +
                     " has " + std::to_string(io.targets.points.rows()) + " targets");
}

// register_to_template (--template) or register_landmarks (the two files), with their structured
// errors turned into file:line and flag messages; io.landmarks holds the paired points after.
RegistrationResult register_mapped(Device& dev, Inputs& io, Points& ball, const RegistrationOptions& opt,
                                   std::optional<DenseRegistrationResult>& dense) {
  try {
    if (io.templ.empty())
      return register_landmarks(dev, ball, io.mesh.tets, io.landmarks.points, io.targets.points, opt);
    io.by_template.flow = opt;
    const TemplateImages images =
        io.image.empty() ? TemplateImages{} : TemplateImages{&io.subject_image, &io.template_image};
    TemplateRegistration r = register_to_template(dev, io.mesh, io.templ_mesh, io.by_template, images);
    ball = std::move(r.ball);
    dense = std::move(r.dense);
    io.landmarks.points = std::move(r.landmarks);
    return r.result;
  } catch (const TemplateRegistrationError& e) {
    using Mesh = TemplateRegistrationError::Mesh;
    throw InputError((e.mesh == Mesh::subject ? io.in : e.mesh == Mesh::templ ? io.templ : io.in + ", " + io.templ) +
                     ": " + e.what());
  } catch (const RegistrationInputError& e) {
    using Subject = RegistrationInputError::Subject;
    const size_t i = static_cast<size_t>(e.landmark);
    if (e.subject == Subject::Mesh) throw InputError(io.in + ": " + e.what() + " (run `vpm map` first)");
    if (e.subject == Subject::Landmark && e.landmark >= 0 && i < io.landmarks.lines.size())
      throw InputError(io.src + ":" + std::to_string(io.landmarks.lines[i]) + " / " + io.dst + ":" +
                       std::to_string(io.targets.lines[i]) + ": " + e.what());
    if (e.subject == Subject::Option) throw InputError(cli_flag(e.option) + ": " + e.problem);
    throw InputError(io.src + ", " + io.dst + ": " + e.what());
  }
}

// The image refinement moves the region-centroid landmarks with the image (their errors stay in
// the report): they are no convergence criterion then.
bool landmarks_free(const std::optional<DenseRegistrationResult>& dense) { return dense && dense->refine; }

Json report_json(const std::string& device, const Inputs& io, const RegistrationResult& res,
                 const std::optional<DenseRegistrationResult>& dense, const MapMetrics& mm, Json timings) {
  Json r = Json::object();
  r["device"] = device;
  Json input = Json::object();
  input["mesh"] = io.in;
  input["vertices"] = io.mesh.num_vertices();
  input["tets"] = io.mesh.num_tets();
  input["landmarks"] = static_cast<long>(io.landmarks.points.rows());
  r["input"] = input;
  const Json summary = to_json(registration_summary(res, mm));
  for (const char* k : {"landmark_rms_error", "landmark_max_error", "max_normal_velocity", "inverted_tets",
                        "vertex_volume_ratio", "tet_volume_ratio", "boundary_max_radius_error"})
    r[k] = *summary.find(k);
  r["converged"] = (landmarks_free(dense) || res.landmark_max_error <= kLandmarkTolerance) &&
                   !(dense && dense->time_budget_spent);
  r["registration"] = to_json(res);
  if (dense) r["dense"] = to_json(*dense);
  r["timings_s"] = timings;
  return r;
}

int run(const cli::Command& self, const std::vector<std::string>& argv) {
  const auto t_start = Clock::now();
  const cli::Args args(argv, self);
  // a triangle surface on the sphere is registered there (apps/register_surface.cpp)
  if (args.positional().size() == 1 && !is_mesh_path(args.positional()[0]) && is_surface_path(args.positional()[0])) {
    const auto out = args.get("-o");
    if (!out) throw InputError("missing -o OUT; usage: " + cli::synopsis(self));
    return cli::register_surface(args, args.positional()[0], *out, t_start);
  }
  Inputs io = read_inputs(args, self);
  io.by_template.dense.deadline = cli::time_budget(args, t_start);
  io.by_template.dense.progress = [](const std::string& line) { cli::progress("register: " + line); };
  const RegistrationOptions opt = parse_options(args);
  Json timings = Json::object();
  auto t0 = Clock::now();
  read_files(io);
  timings["read"] = seconds_since(t0);
  cli::info("register: " + std::to_string(io.mesh.num_vertices()) + " vertices, " + std::to_string(io.mesh.num_tets()) +
            " tets, " + (io.templ.empty() ? std::to_string(io.landmarks.points.rows()) + " landmarks" : "landmarks from " + io.src) +
            ", " + std::to_string(opt.steps) + " steps");

  Device& dev = Device::current();
  Points ball = io.mesh.vertices;
  t0 = Clock::now();
  std::optional<DenseRegistrationResult> dense;
  const RegistrationResult res = register_mapped(dev, io, ball, opt, dense);
  timings["register"] = seconds_since(t0);
  t0 = Clock::now();
  const MapMetrics mm = map_metrics(dev, io.mesh.vertices, ball, io.mesh.tets);
  timings["metrics"] = seconds_since(t0);
  TetMesh mesh = io.mesh;
  mesh.vertices = ball;
  mesh.set_point_field("vertex_volume_ratio", mm.vertex_ratio);
  mesh.set_cell_field("tet_volume_ratio", mm.tet_ratio);
  t0 = Clock::now();
  write_mesh(io.out, mesh);
  timings["write"] = seconds_since(t0);

  std::ostringstream line;
  line.precision(3);
  line << "registered: landmark rms error " << res.landmark_rms_error << " (max " << res.landmark_max_error
       << "), tet volume mean |r-1| " << mm.tet_volume_ratio.mean_abs_dev << ", vertex "
       << mm.vertex_volume_ratio.mean_abs_dev << ", max |u.n| " << res.max_normal_velocity << ", " << mm.inverted_tets
       << " inverted tets; wrote " << io.out;
  cli::info(line.str());
  if (const auto report_path = args.get("--report")) {
    timings["total"] = seconds_since(t_start);
    write_json_file(*report_path, report_json(dev.name(), io, res, dense, mm, timings));
  }
  if (dense && dense->time_budget_spent)
    return cli::time_budget_status("register", std::to_string(dense->iterations.size()) + " of " +
                                                   std::to_string(io.by_template.dense.iterations) + " dense iterations",
                                   args.has("--allow-partial"));
  if (landmarks_free(dense)) return 0;
  // the flow's landmarks are exact up to the RK4 error (about 1e-10); far from it something is off
  return cli::convergence_status("register", "landmark max error", res.landmark_max_error, kLandmarkTolerance,
                                 "after the flow and volume restoration", args.has("--allow-partial"),
                                 [](double v) { return strprintf("%.2e", v); });
}

vpm::cli::Registrar reg(cli::with_expert(cli::with_dense_options(
    {"register", "MAPPED -o OUT (--landmarks SRC.csv --targets DST.csv | --template TEMPLATE.vtu)", "register a mapped mesh (or a surface mapped to the sphere or the disk): move landmarks to targets by a divergence-free flow",
     {{"--landmarks", "SRC.csv", "landmarks in MAPPED's ball (x,y,z or vertex_id a line)", false, 0, true},
      {"--targets", "DST.csv", "their targets, paired line by line", false, 0, true},
      {"--template", "TEMPLATE.vtu", "instead of the two files: the centroids of the atlas regions (cell field label) MAPPED shares with this mapped template (surfaces: a surface mapped to the sphere, with --overlay and --template-overlay; the landmarks then optional)", false, 0, true},
      {"--overlay", "VALUES", "surfaces, with --template: MAPPED's per-vertex scalar pulled onto the template's by dense iterations: a file (FreeSurfer lh.sulc / lh.curv, GIfTI .shape.gii) or the name of a point field of MAPPED (a .vtp of vpm map --overlays)"},
      {"--template-overlay", "VALUES", "surfaces: the template's per-vertex scalar, a file or a point field of TEMPLATE (with --overlay)"},
      {"--template-landmarks", "regions|moments", "with --template: centroids of the atlas regions both carry (default), or, for a subject without atlas labels, points paired by the affine matching the two native solids' moments (then --dense-force image)"},
      {"--exclude-labels", "L[,L...]", "with --template: regions never used as landmarks (held out)"},
      {"--preset", "landmarks|standard|accurate", "with --template: the dense settings by name: landmarks (none; the default), standard (12 iterations), accurate (32 iterations to width 0.1, 2 restore cycles); --dense-* flags override it"},
      {"--image", "SUBJECT.nii.gz", "with --template: MAPPED's image in its native space (for --dense-force image|both)"},
      {"--template-image", "TEMPLATE.nii.gz", "the template's image in its native space (with --image)"},
      {"--steps", "K", "pathline samples and RK4 steps of the landmarks' flow (default 50; surfaces 32)"},
      {"--report", "R.json", "write the report (landmark errors, metrics, timings)"},
      {"--width", "W", "Gaussian width of the RBF kernel in ball units", false, 1},
      {"--lambda", "L", "kernel exponent lambda = 1 / width^2", false, 1},
      {"--width-factor", "F", "width = F x the mean nearest-neighbour spacing of the landmarks (default 0.5; surfaces: chosen by leave-one-out)", false, 1},
      {"--width-loo", "", "choose the width factor by leave-one-out", false, 1},
      {"--flow-boundary", "tangent|samples|none", "how the flow keeps the sphere: a sphere-tangent kernel (default), eq. 29 samples, or not at all"},
      {"--flow-boundary-samples", "N", "sphere samples for --flow-boundary samples (default 200)", false, 0, true},
      {"--field", "per-step|steady", "a field per RK4 stage (default) or the paper's steady field"},
      {"--no-rigid", "", "skip the rotation step"},
      {"--no-untangle", "", "skip local untangling (folded results exit 3)"},
      {"--no-restore", "", "skip the volume (surfaces: face area) restoration after the flow"},
      {"--restore-iterations", "N", "CGLS iterations per restoration step (default 10; more: lower volume distortion, the regions drift more)"},
      {"--restore-rounds", "N", "restoration steps at most (default 12)", false, 0, true},
      {"--restore-min-gain", "G", "restoration steps end once one gains less than this fraction (default 0.01)", false,
       0, true},
      {"--max-seconds", "S", "time budget: the dense iterations stop when it is spent (the landmarks and volumes are still restored; exit 4)"},
      {"--allow-partial", "", "exit 0 even when a landmark misses its target by over 1e-3 or the time budget stopped the iterations (the warning stays)"}},
     run}, "--preset", 0),
    {"--steps", "--width", "--lambda", "--width-factor", "--width-loo", "--flow-boundary", "--flow-boundary-samples", "--field",
     "--no-rigid", "--no-untangle", "--no-restore", "--restore-iterations", "--restore-rounds", "--restore-min-gain"}));
}  // namespace
