// `vpm register SPHERE -o OUT` (register_surface.hpp): landmarks on the sphere moved onto their
// targets by a surface-divergence-free flow, with a template a per-vertex scalar pulled onto the
// template's, the face areas restored.
#include "register_surface.hpp"

#include <algorithm>
#include <filesystem>
#include <cmath>
#include <iterator>
#include <optional>

#include "dense_options.hpp"
#include "vpm/device.hpp"
#include "vpm/error.hpp"
#include "vpm/format.hpp"
#include "vpm/io.hpp"
#include "vpm/json.hpp"
#include "vpm/landmarks.hpp"
#include "vpm/surface_map.hpp"
#include "vpm/surface_registration.hpp"

namespace vpm::cli {

namespace {

// Landmark error above which the registration warns (as for the ball).
constexpr double kLandmarkTolerance = 5e-4;

// The options of `vpm register` that apply to surfaces.
constexpr const char* kSurfaceOptions[] = {"-o", "--landmarks", "--targets", "--template", "--overlay", "--template-overlay",
                                           "--dense-iterations", "--dense-widths", "--steps", "--width-factor", "--no-rigid",
                                           "--no-restore", "--report", "--allow-partial", "--quiet", "--verbose"};

// A surface mapped to the sphere: every vertex within 1e-4 of it (put on it exactly), else
// InputError naming `path` and the vertex.
TriSurface read_sphere(const std::string& path, TriSurface surface) {
  for (Eigen::Index i = 0; i < surface.vertices.rows(); ++i) {
    const double r = surface.vertices.row(i).norm();
    if (!(std::abs(r - 1) <= 1e-4))
      throw InputError(path + ": vertex " + std::to_string(i) + " is not on the unit sphere (|x| = " + std::to_string(r) +
                       "); map the surface first: vpm map SURFACE -o SPHERE.gii");
    surface.vertices.row(i) /= r;  // float files: vertex_id landmarks then lie on the sphere too
  }
  return surface;
}
TriSurface read_sphere(const std::string& path) { return read_sphere(path, read_surface(path)); }

// A surface mapped to the disk (one boundary loop): z = 0 and |x| <= 1 within 1e-4 (put there
// exactly), else InputError naming `path` and the vertex.
TriSurface read_disk(const std::string& path, TriSurface surface) {
  for (Eigen::Index i = 0; i < surface.vertices.rows(); ++i) {
    const double r = surface.vertices.row(i).head<2>().norm(), z = surface.vertices(i, 2);
    if (!(std::abs(z) <= 1e-4 && r <= 1 + 1e-4))
      throw InputError(path + ": vertex " + std::to_string(i) + " is not in the unit disk (x, y, z = " +
                       std::to_string(surface.vertices(i, 0)) + ", " + std::to_string(surface.vertices(i, 1)) + ", " +
                       std::to_string(z) + "); map the surface first: vpm map SURFACE -o DISK.gii");
    surface.vertices(i, 2) = 0;
    if (r > 1) surface.vertices.row(i).head<2>() /= r;
  }
  return surface;
}

// A per-vertex scalar of `surface` (read from `of`): the point field named `what` (a .vtp written
// by `vpm map SURFACE --overlays`), else the per-vertex file `what` (--overlay, --template-overlay).
Eigen::VectorXd read_values(const std::string& what, const TriSurface& surface, const std::string& of) {
  const Eigen::Index vertices = surface.vertices.rows();
  Eigen::VectorXd v;
  const auto field = std::find_if(surface.point_data.begin(), surface.point_data.end(),
                                  [&](const Field& f) { return f.name == what && f.values.cols() == 1; });
  if (field != surface.point_data.end()) {
    v = field->values.col(0);
  } else {
    if (!std::filesystem::exists(what)) {
      std::string names;
      for (const Field& f : surface.point_data)
        if (f.values.cols() == 1) names += (names.empty() ? "" : ", ") + f.name;
      throw InputError(what + ": neither a file nor a point field of " + of +
                       (names.empty() ? std::string(" (it has none)") : " (its point fields: " + names + ")"));
    }
    v = read_overlay(what);
  }
  if (v.size() != vertices)
    throw InputError(what + ": " + std::to_string(v.size()) + " values, but " + of + " has " + std::to_string(vertices) + " vertices");
  for (Eigen::Index i = 0; i < v.size(); ++i)
    if (!std::isfinite(v(i))) throw InputError(what + ": value " + std::to_string(i) + " is not finite");
  return v;
}

SurfaceRegistrationOptions parse_options(const Args& args) {
  for (const std::string& flag : args.given())
    if (std::find(std::begin(kSurfaceOptions), std::end(kSurfaceOptions), flag) == std::end(kSurfaceOptions))
      throw InputError("option " + flag + ": applies to tet meshes only; the input is a surface, registered on the sphere");
  SurfaceRegistrationOptions opt;
  opt.steps = args.get_int("--steps", 32);
  if (opt.steps < 1 || opt.steps > 100000) throw InputError("--steps: expected 1 to 100000");
  if (args.has("--width-factor")) {  // otherwise chosen by leave-one-out
    opt.width_factor = args.get_double("--width-factor", 0);
    if (!(opt.width_factor > 0)) throw InputError("--width-factor: must be positive");
  }
  opt.rigid = !args.has("--no-rigid");
  if (args.has("--no-restore")) opt.restore_rounds = 0;
  const bool dense = args.has("--template");
  for (const char* flag : {"--overlay", "--template-overlay", "--dense-iterations", "--dense-widths"})
    if (!dense && args.has(flag)) throw InputError(std::string(flag) + " needs --template");
  if (dense) {
    if (!args.has("--overlay") || !args.has("--template-overlay"))
      throw InputError("--template: a surface is registered onto a template by a per-vertex scalar; give --overlay and --template-overlay");
    opt.match.iterations = args.get_int("--dense-iterations", opt.match.iterations);
    if (opt.match.iterations < 0 || opt.match.iterations > 1000) throw InputError("--dense-iterations: expected 0 to 1000");
    if (args.has("--dense-widths")) opt.match.widths = parse_widths(args, "--dense-widths");
  }
  if (args.has("--landmarks") != args.has("--targets"))
    throw InputError(std::string("missing ") + (args.has("--landmarks") ? "--targets DST.csv" : "--landmarks SRC.csv"));
  if (!args.has("--landmarks") && !dense) throw InputError("missing --landmarks SRC.csv --targets DST.csv (or --template)");
  return opt;
}

Json report_json(const std::string& in, const TriSurface& surface, const std::optional<std::string>& templ, Eigen::Index landmarks,
                 const SurfaceRegistrationResult& r, const SurfaceRegistrationOptions& opt) {
  Json report = Json::object();
  report["domain"] = "sphere";
  report["input"] = Json::object();
  report["input"]["surface"] = in;
  report["input"]["vertices"] = static_cast<long>(surface.vertices.rows());
  report["input"]["faces"] = static_cast<long>(surface.triangles.rows());
  report["input"]["landmarks"] = static_cast<long>(landmarks);
  if (templ) report["input"]["template"] = *templ;
  report["landmark_rms_error"] = r.landmark_rms_error;
  report["landmark_max_error"] = r.landmark_max_error;
  report["converged"] = r.landmark_max_error <= kLandmarkTolerance && r.metrics.flipped_faces == 0;
  report["registration"] = to_json(r, opt);
  return report;
}

}  // namespace

int register_surface(const Args& args, const std::string& in, const std::string& out, Clock::time_point t_start) {
  const SurfaceRegistrationOptions opt = parse_options(args);
  if (!is_surface_output_path(out))
    throw InputError(out + ": unknown output extension for a surface (expected .vtp, .gii, .off, .obj, .stl or a FreeSurfer name)");
  auto t0 = Clock::now();
  TriSurface input = read_surface(in);
  const SurfaceDomain domain = surface_domain(input);
  const TriSurface surface = domain == SurfaceDomain::disk ? read_disk(in, std::move(input)) : read_sphere(in, std::move(input));
  LandmarkFile from, to;
  const auto src = args.get("--landmarks"), dst = args.get("--targets"), templ = args.get("--template");
  if (src) {
    from = read_landmarks_csv(*src, surface.vertices);
    to = read_landmarks_csv(*dst, surface.vertices);
    if (from.points.rows() != to.points.rows())
      throw InputError(*src + ", " + *dst + ": " + std::to_string(from.points.rows()) + " landmarks but " +
                       std::to_string(to.points.rows()) + " targets");
  } else {
    from.points = to.points = Points(0, 3);
  }
  TriSurface ts;  // the template, mapped to the subject's domain
  Eigen::VectorXd values, tvalues;
  if (templ) {
    ts = domain == SurfaceDomain::disk ? read_disk(*templ, read_surface(*templ)) : read_sphere(*templ);
    tvalues = read_values(*args.get("--template-overlay"), ts, *templ);
    values = read_values(*args.get("--overlay"), surface, in);
  }
  const double t_read = seconds_since(t0);
  Device& dev = Device::current();
  SurfaceRegistrationResult r;
  try {
    const Points &v = surface.vertices, &p = from.points, &q = to.points;
    const Triangles& f = surface.triangles;
    if (domain == SurfaceDomain::disk)
      r = templ ? register_in_disk(v, f, values, DiskTemplate{ts.vertices, ts.triangles, tvalues}, p, q, opt, &dev)
                : register_in_disk(v, f, p, q, opt, &dev);
    else
      r = templ ? register_on_sphere(v, f, values, SphereTemplate{ts.vertices, ts.triangles, tvalues}, p, q, opt, &dev)
                : register_on_sphere(v, f, p, q, opt, &dev);
  } catch (const InputError& e) {
    throw InputError((src ? *src + ", " + *dst : in + ", " + *templ) + ": " + e.what());
  }
  if (r.metrics.flipped_faces > 0)
    throw NumericalError(in + ": the registration flipped " + std::to_string(r.metrics.flipped_faces) +
                         " faces (landmarks too close together for their targets?)");
  TriSurface registered;
  registered.vertices = r.points;
  registered.triangles = surface.triangles;
  registered.point_data.push_back({"original_position", surface.vertices, false});
  registered.point_data.push_back({"vertex_area_ratio", r.metrics.vertex_ratio, false});
  registered.cell_data.push_back({"face_area_ratio", r.metrics.face_ratio, false});
  t0 = Clock::now();
  write_surface(out, registered);
  info(std::string("registered ") + (domain == SurfaceDomain::disk ? "in the disk" : "on the sphere") + ": landmark rms error " + strprintf("%.2e", r.landmark_rms_error) + " (max " +
       strprintf("%.2e", r.landmark_max_error) + ")" +
       (templ ? strprintf(", scalar correlation %.3f -> %.3f", r.match.correlation_before, r.match.correlation_after) : "") +
       ", face area mean |r-1| " + strprintf("%.3f %%", 100 * r.metrics.face_area_ratio.mean_abs_dev) + " (flow " +
       strprintf("%.3f %%", 100 * r.flow_metrics.face_area_ratio.mean_abs_dev) + "), " +
       std::to_string(r.metrics.flipped_faces) + " flipped faces; wrote " + out);
  if (const auto report_path = args.get("--report")) {
    Json report = report_json(in, surface, templ, from.points.rows(), r, opt);
    report["domain"] = to_string(domain);
    report["device"] = dev.name();  // where the flows' advections ran
    report["timings_s"] = Json::object();
    report["timings_s"]["read"] = t_read;
    report["timings_s"]["register"] = r.seconds;
    report["timings_s"]["write"] = seconds_since(t0);
    report["timings_s"]["total"] = seconds_since(t_start);
    write_json_file(*report_path, report);
  }
  return convergence_status("register", "landmark max error", r.landmark_max_error, kLandmarkTolerance,
                            "after the flow", args.has("--allow-partial"), [](double v) { return strprintf("%.2e", v); });
}

}  // namespace vpm::cli
