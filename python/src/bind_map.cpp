// vpm.initial_map and vpm.map_to_ball, with their reports as typed objects.
#include "common.hpp"
#include "report.hpp"
#include "vpm/ball_map.hpp"
#include "vpm/error.hpp"
#include "vpm/initial_map.hpp"
#include "vpm/metrics.hpp"
#include "vpm/solver.hpp"
#include "vpm/timing.hpp"
#include "vpm/validate.hpp"

namespace vpm::python {
namespace {

// What a map report holds besides its JSON: the main numbers, typed.
struct MapReport : Report {
  std::string device;
  MapMetrics initial, final;
  bool converged = true;
  int input_vertices = 0, input_tets = 0;
  double seconds = 0;
};

struct InitialReport : Report {
  std::string device;
  int folds_before_untangle = 0, inserted_vertices = 0;
};

InitialMapOptions initial_options(const std::string& sphere, const std::string& sphere_start,
                                  const std::string& sphere_solve, const std::string& untangle,
                                  const std::string& preconditioner, bool split) {
  InitialMapOptions o;
  o.sphere_density = parse_sphere_density(sphere);
  o.sphere_start = parse_sphere_start(sphere_start);
  o.density_solve = parse_density_solve(sphere_solve);
  if (untangle == "never") o.untangle = InitialMapOptions::Untangle::Never;
  else if (untangle == "if-folded") o.untangle = InitialMapOptions::Untangle::IfFolded;
  else if (untangle == "always") o.untangle = InitialMapOptions::Untangle::Always;
  else throw InputError("untangle: '" + untangle + "' is not one of never, if-folded, always");
  o.preconditioner = parse_preconditioner_choice(preconditioner);
  o.split_edges = split;
  return o;
}

void bind_reports(py::module_& m) {
  py::class_<RatioStats>(m, "RatioStats", "Statistics of volume ratios r (docs/design.md 5).")
      .def_readonly("mean_abs_dev", &RatioStats::mean_abs_dev, "mean |r - 1|: the paper's volume distortion")
      .def_readonly("std_log", &RatioStats::std_log)
      .def_readonly("p99_abs_log", &RatioStats::p99_abs_log)
      .def_readonly("max_abs_log", &RatioStats::max_abs_log)
      .def_readonly("min", &RatioStats::min)
      .def_readonly("max", &RatioStats::max)
      .def("to_dict", [](const RatioStats& s) { return json_to_python(to_json(s)); })
      .def("__repr__", [](const RatioStats& s) { return "<vpm.RatioStats mean |r-1| " + std::to_string(s.mean_abs_dev) + ">"; });
  py::class_<MapMetrics>(m, "MapMetrics", "Distortion of a map against its input (docs/design.md 5).")
      .def_readonly("inverted_tets", &MapMetrics::inverted_tets)
      .def_readonly("vertex_volume_ratio", &MapMetrics::vertex_volume_ratio)
      .def_readonly("tet_volume_ratio", &MapMetrics::tet_volume_ratio)
      .def_readonly("boundary_max_radius_error", &MapMetrics::boundary_max_radius_error)
      .def("to_dict", [](const MapMetrics& s) { return json_to_python(to_json(s)); })
      .def("__repr__", [](const MapMetrics& s) {
        return "<vpm.MapMetrics vertex mean |r-1| " + std::to_string(s.vertex_volume_ratio.mean_abs_dev) + ", tet " +
               std::to_string(s.tet_volume_ratio.mean_abs_dev) + ", " + std::to_string(s.inverted_tets) + " inverted>";
      });
  bind_report_base(m);
  py::class_<MapReport, Report>(m, "MapReport", "What map_to_ball did; to_dict() is `vpm map --report`'s JSON.")
      .def_readonly("device", &MapReport::device)
      .def_readonly("initial", &MapReport::initial, "metrics of the initial (harmonic) map")
      .def_readonly("final", &MapReport::final, "metrics of the returned map")
      .def_readonly("converged", &MapReport::converged, "reached the tolerance (True when not checked)")
      .def_readonly("input_vertices", &MapReport::input_vertices)
      .def_readonly("input_tets", &MapReport::input_tets)
      .def_readonly("seconds", &MapReport::seconds, "the library call's wall time");
  py::class_<InitialReport, Report>(m, "InitialMapReport", "What initial_map did; to_dict() is its JSON.")
      .def_readonly("device", &InitialReport::device)
      .def_readonly("folds_before_untangle", &InitialReport::folds_before_untangle)
      .def_readonly("inserted_vertices", &InitialReport::inserted_vertices);
}

// long: the keyword arguments of `vpm map`, one line each
void bind_map_to_ball(py::module_& m) {
  m.def(
      "_map_to_ball",
      [](const py::object& vertices, const py::object& tets, int rounds, double tolerance, const std::string& sphere,
         const std::string& sphere_start, const std::string& sphere_solve, const std::string& boundary,
         const std::string& preconditioner, int rk_steps,
         double max_seconds, const std::string& source, std::optional<std::string> device, py::object progress) {
        auto mesh = mesh_argument(vertices, tets);
        BallMapOptions bo;
        bo.volume.rounds = rounds;
        if (rounds < -1) throw InputError("rounds: must be >= 0 (or -1: until the tolerance)");
        if (!(tolerance >= 0)) throw InputError("tolerance: must be >= 0");
        if (rk_steps < 1) throw InputError("rk_steps: must be >= 1");
        bo.volume.tolerance = tolerance;
        bo.volume.boundary = parse_map_boundary(boundary);
        bo.initial = initial_options(sphere, sphere_start, sphere_solve, "if-folded", preconditioner, true);
        bo.volume.preconditioner = bo.initial.preconditioner;
        bo.volume.rk_steps = rk_steps;
        bo.deadline = Deadline::in_seconds(max_seconds);  // 0: none
        Progress p(std::move(progress));
        bo.volume.progress = p.function();
        auto dev = device_for(device);
        auto report = std::make_unique<MapReport>();
        auto ball = without_gil(&p, [&] {
          const Stopwatch clock;
          const ValidationReport vr = validate_mesh(*mesh, source);
          BallMap bm = map_to_ball(*dev, *mesh, vr, source, bo);
          report->seconds = clock.seconds();
          report->json = to_json(bm).dump(-1);
          report->device = bm.device;
          report->initial = std::move(bm.initial);
          report->final = std::move(bm.final);
          report->converged = bm.convergence.converged;
          report->input_vertices = bm.input_vertices;
          report->input_tets = bm.input_tets;
          return std::make_shared<TetMesh>(std::move(bm.mesh));
        });
        return py::make_tuple(ball, std::move(report));
      },
      py::arg("vertices"), py::arg("tets") = py::none(), py::kw_only(), py::arg("rounds") = -1,
      py::arg("tolerance") = 0.01, py::arg("sphere") = "area",
      py::arg("sphere_start") = "auto", py::arg("sphere_solve") = "auto", py::arg("boundary") = "auto",
      py::arg("preconditioner") = "auto", py::arg("rk_steps") = VolumeMapOptions{}.rk_steps,
      py::arg("max_seconds") = 0.0, py::arg("source") = "mesh", py::arg("device") = py::none(), py::arg("progress") = py::none());
}

}  // namespace

void bind_map(py::module_& m) {
  bind_reports(m);
  bind_map_to_ball(m);
  m.def(
      "_initial_map",
      [](const py::object& vertices, const py::object& tets, const std::string& sphere, const std::string& sphere_start,
         const std::string& sphere_solve, const std::string& untangle, bool split, const std::string& source,
         std::optional<std::string> device) {
        auto mesh = mesh_argument(vertices, tets);
        const InitialMapOptions o = initial_options(sphere, sphere_start, sphere_solve, untangle, "auto", split);
        auto dev = device_for(device);
        auto report = std::make_unique<InitialReport>();
        auto ball = without_gil(nullptr, [&] {
          validate_mesh(*mesh, source);
          InitialMapResult r = initial_map(*dev, *mesh, o);
          report->json = to_json(r.report).dump(-1);
          report->device = r.report.device;
          report->folds_before_untangle = r.report.folds_before_untangle;
          report->inserted_vertices = r.report.inserted_vertices;
          auto out = std::make_shared<TetMesh>(std::move(r.mesh));  // input coordinates, original_position
          out->vertices = std::move(r.ball);
          return out;
        });
        return py::make_tuple(ball, std::move(report));
      },
      py::arg("vertices"), py::arg("tets") = py::none(), py::kw_only(), py::arg("sphere") = "area",
      py::arg("sphere_start") = "auto", py::arg("sphere_solve") = "auto", py::arg("untangle") = "if-folded",
      py::arg("split") = true, py::arg("source") = "mesh", py::arg("device") = py::none());
}

}  // namespace vpm::python
