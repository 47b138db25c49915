// vpm.map_to_sphere, vpm.map_to_disk and vpm.read_surface / vpm.write_surface: closed surfaces to
// the sphere, disk-like ones to the disk
// (vpm/surface_map.hpp), with the report as a typed object.
#include <pybind11/stl.h>

#include "common.hpp"
#include "report.hpp"
#include "vpm/curvature.hpp"
#include "vpm/error.hpp"
#include "vpm/initial_map.hpp"
#include "vpm/io.hpp"
#include "vpm/locate.hpp"
#include "vpm/surface_map.hpp"
#include "vpm/surface_registration.hpp"
#include "vpm/timing.hpp"

namespace vpm::python {
namespace {

struct SurfaceReport : Report {
  SurfaceMetrics initial, final;
  Triangles faces;  // of the returned points (the input's unless a disk's ears were split)
  Eigen::Matrix<int, Eigen::Dynamic, 2, Eigen::RowMajor> added;  // per added vertex, its edge's ends
  bool converged = true;
  double seconds = 0;
};

// (k, 3) integer array-like -> Triangles (indices checked against `vertices`).
Triangles to_triangles(const py::handle& values, Eigen::Index vertices) {
  const auto a = py::array_t<long long, py::array::c_style | py::array::forcecast>::ensure(values);
  if (!a || a.ndim() != 2 || a.shape(1) != 3) throw InputError("faces: expected a (k, 3) array of vertex indices");
  Triangles t(a.shape(0), 3);
  const long long* d = a.data();
  for (py::ssize_t i = 0; i < a.size(); ++i) {
    if (d[i] < 0 || d[i] >= vertices)
      throw InputError("faces: face " + std::to_string(i / 3) + ": vertex index " + std::to_string(d[i]) +
                       " out of range (" + std::to_string(vertices) + " vertices)");
    t.data()[i] = static_cast<int>(d[i]);
  }
  return t;
}

// A (k,) float array-like of `n` values.
Eigen::VectorXd to_values(const py::handle& values, Eigen::Index n, const char* what) {
  const auto a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(values);
  if (!a || a.ndim() != 1 || a.shape(0) != n)
    throw py::value_error(std::string(what) + ": expected " + std::to_string(n) + " values (one per vertex)");
  return Eigen::Map<const Eigen::VectorXd>(a.data(), n);
}

// The landmark registration's options of both domains.
SurfaceRegistrationOptions landmark_options(int steps, double width_factor, bool rigid, bool restore) {
  SurfaceRegistrationOptions o;
  o.steps = steps;
  o.width_factor = width_factor;
  o.rigid = rigid;
  if (!restore) o.restore_rounds = 0;
  return o;
}

// (points, report) of a registration `work` run without the GIL: a SurfaceMapReport whose
// `initial` holds the metrics after the flow.
template <class Work>
py::tuple registration_result(const SurfaceRegistrationOptions& o, Work&& work) {
  auto report = std::make_unique<SurfaceReport>();
  Points out = without_gil(nullptr, [&] {
    SurfaceRegistrationResult r = work();
    report->seconds = r.seconds;
    report->json = to_json(r, o).dump(-1);
    report->initial = std::move(r.flow_metrics);
    report->final = std::move(r.metrics);
    report->converged = r.landmark_max_error <= 5e-4 && report->final.flipped_faces == 0;
    return std::move(r.points);
  });
  return py::make_tuple(owned_array(std::move(out)), std::move(report));
}

// A dense registration's scalars: `values` and `templ` ((vertices, faces, values)) both given or
// neither; false when neither.
bool dense_inputs(const py::object& values, const py::object& templ, Eigen::Index vertices, Eigen::VectorXd& subject,
                  SphereTemplate& t) {
  const bool dense = !templ.is_none();
  if (dense != !values.is_none()) throw py::value_error("values and template: give both (a dense registration) or neither");
  if (!dense) return false;
  const auto parts = templ.cast<py::tuple>();
  if (parts.size() != 3) throw py::value_error("template: expected (vertices, faces, values)");
  t.sphere = to_points(parts[0], "template vertices");
  t.faces = to_triangles(parts[1], t.sphere.rows());
  t.values = to_values(parts[2], t.sphere.rows(), "template values");
  subject = to_values(values, vertices, "values");
  return true;
}

// vpm._register_on_sphere (vpm/surface_registration.hpp).
void bind_sphere_registration(py::module_& m) {
  m.def(
      "_register_on_sphere",
      [](const py::object& vertices, const py::object& faces, const py::object& landmarks, const py::object& targets,
         int steps, double width_factor, bool rigid, bool restore, const py::object& values, const py::object& templ,
         int iterations, const std::vector<double>& widths, std::optional<std::string> device) {
        const Points v = to_points(vertices, "vertices");
        const Triangles f = to_triangles(faces, v.rows());
        const Points from = to_points(landmarks, "landmarks"), to = to_points(targets, "targets");
        SurfaceRegistrationOptions o = landmark_options(steps, width_factor, rigid, restore);
        o.match.iterations = iterations;
        if (!widths.empty()) o.match.widths = widths;
        SphereTemplate t;
        Eigen::VectorXd subject_values;
        const bool dense = dense_inputs(values, templ, v.rows(), subject_values, t);
        const std::shared_ptr<Device> dev = device_for(device);
        return registration_result(o, [&] {
          return dense ? register_on_sphere(v, f, subject_values, t, from, to, o, dev.get())
                       : register_on_sphere(v, f, from, to, o, dev.get());
        });
      },
      py::arg("vertices"), py::arg("faces"), py::arg("landmarks"), py::arg("targets"), py::kw_only(),
      py::arg("steps") = SurfaceRegistrationOptions{}.steps, py::arg("width_factor") = SurfaceRegistrationOptions{}.width_factor,
      py::arg("rigid") = true, py::arg("restore") = true, py::arg("values") = py::none(), py::arg("template") = py::none(),
      py::arg("iterations") = SphereMatchOptions{}.iterations, py::arg("widths") = std::vector<double>{},
      py::arg("device") = py::none());
}

void bind_disk_registration(py::module_& m) {
  m.def(
      "_register_in_disk",
      [](const py::object& vertices, const py::object& faces, const py::object& landmarks, const py::object& targets,
         int steps, double width_factor, bool rigid, bool restore, const py::object& values, const py::object& templ,
         int iterations, const std::vector<double>& widths, std::optional<std::string> device) {
        const Points v = to_points(vertices, "vertices");
        const Triangles f = to_triangles(faces, v.rows());
        const Points from = to_points(landmarks, "landmarks"), to = to_points(targets, "targets");
        SurfaceRegistrationOptions o = landmark_options(steps, width_factor, rigid, restore);
        o.match.iterations = iterations;
        if (!widths.empty()) o.match.widths = widths;
        SphereTemplate t;
        Eigen::VectorXd subject_values;
        const bool dense = dense_inputs(values, templ, v.rows(), subject_values, t);
        const std::shared_ptr<Device> dev = device_for(device);
        return registration_result(o, [&] {
          return dense ? register_in_disk(v, f, subject_values, DiskTemplate{t.sphere, t.faces, t.values}, from, to, o, dev.get())
                       : register_in_disk(v, f, from, to, o, dev.get());
        });
      },
      py::arg("vertices"), py::arg("faces"), py::arg("landmarks"), py::arg("targets"), py::kw_only(),
      py::arg("steps") = SurfaceRegistrationOptions{}.steps, py::arg("width_factor") = SurfaceRegistrationOptions{}.width_factor,
      py::arg("rigid") = true, py::arg("restore") = true, py::arg("values") = py::none(), py::arg("template") = py::none(),
      py::arg("iterations") = SphereMatchOptions{}.iterations, py::arg("widths") = std::vector<double>{},
      py::arg("device") = py::none());
}

void bind_sphere_locator(py::module_& m) {
  m.def(
      "_mean_curvature",
      [](const py::object& vertices, const py::object& faces) {
        TriSurface s;
        s.vertices = to_points(vertices, "vertices");
        s.triangles = to_triangles(faces, s.vertices.rows());
        return owned_array(mean_curvature(s));
      },
      py::arg("vertices"), py::arg("faces"));
  m.def(
      "_locate_on_sphere",
      [](const py::object& vertices, const py::object& faces, const py::object& points) {
        const Points v = to_points(vertices, "vertices");
        const Triangles f = to_triangles(faces, v.rows());
        const Points p = to_points(points, "points");
        std::vector<SphereLocation> loc = without_gil(nullptr, [&] { return SphereLocator(v, f).locate_all(p); });
        Eigen::Matrix<int, Eigen::Dynamic, 1> face(p.rows());
        Points bary(p.rows(), 3);
        for (Eigen::Index i = 0; i < p.rows(); ++i) {
          face(i) = loc[static_cast<size_t>(i)].face;
          for (int k = 0; k < 3; ++k) bary(i, k) = loc[static_cast<size_t>(i)].bary[k];
        }
        return py::make_tuple(owned_array(std::move(face)), owned_array(std::move(bary)));
      },
      py::arg("vertices"), py::arg("faces"), py::arg("points"));
}

}  // namespace

void bind_surface(py::module_& m) {
  py::class_<SurfaceMetrics>(m, "SurfaceMetrics", "Area distortion of a sphere map against its surface.")
      .def_readonly("flipped_faces", &SurfaceMetrics::flipped_faces)
      .def_readonly("face_area_ratio", &SurfaceMetrics::face_area_ratio)
      .def_readonly("vertex_area_ratio", &SurfaceMetrics::vertex_area_ratio)
      .def_readonly("max_radius_error", &SurfaceMetrics::max_radius_error)
      .def("to_dict", [](const SurfaceMetrics& s) { return json_to_python(to_json(s)); });
  py::class_<SurfaceReport, Report>(m, "SurfaceMapReport",
                                    "What map_to_sphere did; to_dict() is `vpm map SURFACE --report`'s JSON.")
      .def_readonly("initial", &SurfaceReport::initial, "metrics after the sphere map")
      .def_readonly("final", &SurfaceReport::final, "metrics of the returned map")
      .def_readonly("converged", &SurfaceReport::converged, "face area mean |r-1| within the tolerance")
      .def_readonly("seconds", &SurfaceReport::seconds, "the library call's wall time")
      .def_property_readonly("faces", [](const SurfaceReport& r) { return owned_array(Triangles(r.faces)); },
                             "(k, 3) faces of the returned points: the input's, or with a disk's ears split")
      .def_property_readonly("added", [](const SurfaceReport& r) { return owned_array(decltype(r.added)(r.added)); },
                             "(a, 2): per vertex added by splitting ears (rows n, n + 1, ...), its edge's ends");
  m.def(
      "_map_to_sphere",
      [](const py::object& vertices, const py::object& faces, int rounds, double tolerance, const std::string& sphere,
         const std::string& sphere_start, double max_seconds, const std::string& source, bool disk, py::object progress) {
        TriSurface s;
        s.vertices = to_points(vertices, "vertices");
        s.triangles = to_triangles(faces, s.vertices.rows());
        SurfaceMapOptions o;
        if (rounds < 0) throw InputError("rounds: must be >= 0");
        if (!(tolerance >= 0)) throw InputError("tolerance: must be >= 0");
        o.polish_rounds = rounds;
        o.tolerance = tolerance;
        o.sphere.sphere_density = parse_sphere_density(sphere);
        o.sphere.sphere_start = parse_sphere_start(sphere_start);
        o.deadline = Deadline::in_seconds(max_seconds);  // 0: none
        Progress p(std::move(progress));
        o.progress = p.function();
        auto report = std::make_unique<SurfaceReport>();
        Points sphere_points = without_gil(&p, [&] {
          const Stopwatch clock;
          if (disk) validate_disk_surface(s, source);
          else validate_closed_surface(s, source);
          SurfaceMapResult r = disk ? map_to_disk(s, o) : map_to_sphere(s, o);
          report->seconds = clock.seconds();
          report->json = to_json(r.report).dump(-1);
          report->initial = std::move(r.report.initial);
          report->final = std::move(r.report.final);
          report->converged = r.report.converged;
          report->faces = mapped_faces(s.triangles, r);
          report->added.resize(static_cast<Eigen::Index>(r.added.size()), 2);
          for (size_t i = 0; i < r.added.size(); ++i)
            report->added.row(static_cast<Eigen::Index>(i)) << r.added[i][0], r.added[i][1];
          return std::move(r.sphere);
        });
        return py::make_tuple(owned_array(std::move(sphere_points)), std::move(report));
      },
      py::arg("vertices"), py::arg("faces"), py::kw_only(), py::arg("rounds") = SurfaceMapOptions{}.polish_rounds,
      py::arg("tolerance") = SurfaceMapOptions{}.tolerance, py::arg("sphere") = "area", py::arg("sphere_start") = "auto",
      py::arg("max_seconds") = 0.0, py::arg("source") = "surface", py::arg("disk") = false,
      py::arg("progress") = py::none());
  bind_sphere_registration(m);
  bind_disk_registration(m);
  bind_sphere_locator(m);
  m.def(
      "_read_surface",
      [](const std::string& path) {
        TriSurface s = read_surface(path);
        return py::make_tuple(owned_array(std::move(s.vertices)), owned_array(std::move(s.triangles)));
      },
      py::arg("path"));
  m.def(
      "_read_overlay", [](const std::string& path) { return owned_array(read_overlay(path)); }, py::arg("path"));
  m.def(
      "_write_surface",
      [](const std::string& path, const py::object& vertices, const py::object& faces) {
        TriSurface s;
        s.vertices = to_points(vertices, "vertices");
        s.triangles = to_triangles(faces, s.vertices.rows());
        write_surface(path, s);
      },
      py::arg("path"), py::arg("vertices"), py::arg("faces"));
}

}  // namespace vpm::python
