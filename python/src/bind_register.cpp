// vpm.register: landmarks or a template (region centroids or the moments' affine), dense.
#include "common.hpp"
#include "report.hpp"
#include "vpm/collective.hpp"
#include "vpm/dense_registration.hpp"
#include "vpm/error.hpp"
#include "vpm/image.hpp"
#include "vpm/metrics.hpp"
#include "vpm/registration.hpp"
#include "vpm/registration_preset.hpp"
#include "vpm/timing.hpp"

namespace vpm::python {
namespace {

struct RegistrationReportPy : Report {
  std::string device;
  double landmark_rms_error = 0, landmark_max_error = 0, max_normal_velocity = 0;
  int landmarks = 0, inverted_tets = 0;
  MapMetrics metrics;  ///< the registered mesh against the mapped one
};

// (N, 3) ball coordinates, or (N,) vertex ids of `mesh`.
Points landmark_points(const py::object& values, const TetMesh& mesh, const char* what) {
  const py::array a = py::array::ensure(values);
  if (a && a.ndim() == 1) {
    const auto ids = py::array_t<long long, py::array::forcecast>::ensure(a);
    Points p(ids.shape(0), 3);
    for (py::ssize_t i = 0; i < ids.shape(0); ++i) {
      const long long v = ids.at(i);
      if (v < 0 || v >= mesh.num_vertices())
        throw InputError(std::string(what) + ": vertex id " + std::to_string(v) + " out of range");
      p.row(i) = mesh.vertices.row(v);
    }
    return p;
  }
  return to_points(values, what);
}

struct Request {
  std::shared_ptr<TetMesh> mesh, templ;
  Points landmarks, targets;
  RegistrationOptions options;
  DenseRegistrationOptions dense;
  std::shared_ptr<Image> image, templ_image;
  bool moments = false;
};

std::vector<int> labels_or_none(const Request& r, const TetMesh& mesh, const char* what) {
  if (mesh.find_cell_field("label") || !r.moments) return cell_labels(mesh);
  if (r.dense.force != DenseForce::image)
    throw InputError(std::string(what) + ": no cell field 'label': dense_force '" + to_string(r.dense.force) +
                     "' needs atlas labels on both meshes; use dense_force='image'");
  return std::vector<int>(static_cast<size_t>(mesh.num_tets()), 0);
}

RegistrationResult run(const Request& r, Device& dev, Points& ball) {
  if (r.dense.iterations == 0) return register_landmarks(dev, ball, r.mesh->tets, r.landmarks, r.targets, r.options);
  if (!r.templ) throw InputError("dense_iterations: needs template=");
  DenseImages images;
  if (r.dense.force != DenseForce::labels) {
    if (!r.image || !r.templ_image) throw InputError("dense_force: image and both need image= and template_image=");
    images = {r.image.get(), native_positions(*r.mesh, "mesh"), r.templ_image.get(),
              native_positions(*r.templ, "template")};
  }
  const DenseRegistrationResult d =
      register_dense(dev, {ball, r.mesh->tets, labels_or_none(r, *r.mesh, "mesh")},
                     {r.templ->vertices, r.templ->tets, labels_or_none(r, *r.templ, "template")}, r.landmarks, r.targets,
                     r.options, r.dense,
                     r.dense.force == DenseForce::labels ? nullptr : &images);
  RegistrationResult res = d.landmark;
  res.landmark_rms_error = d.landmark_rms_error;
  res.landmark_max_error = d.landmark_max_error;
  res.max_normal_velocity = d.max_normal_velocity;
  res.inverted_tets = d.inverted_tets;
  return res;
}

// long: one keyword argument a line, as `vpm register`'s options
py::tuple register_py(const py::object& mesh, const py::object& landmarks, const py::object& targets,
                      const py::object& templ, const std::string& template_landmarks, std::vector<int> exclude,
                      const std::optional<std::string>& preset, std::optional<int> dense_iterations,
                      const std::string& dense_force, std::shared_ptr<Image> image,
                      std::shared_ptr<Image> template_image, int steps, std::optional<double> width,
                      double width_factor, const std::string& boundary, const std::string& field, bool rigid,
                      bool untangle, bool restore, double max_seconds, std::optional<std::string> device,
                      py::object progress) {
  Request r;
  r.mesh = mesh_argument(mesh, py::none());
  if (!templ.is_none()) r.templ = mesh_argument(templ, py::none());
  if (template_landmarks != "regions" && template_landmarks != "moments")
    throw InputError("template_landmarks: '" + template_landmarks + "' is not one of regions, moments");
  r.moments = template_landmarks == "moments";
  if (r.templ && (!landmarks.is_none() || !targets.is_none()))
    throw InputError("template= and landmarks=/targets= both given; use one");
  if (r.templ && r.moments) {
    const MomentLandmarks lm = moment_landmarks(*r.mesh, *r.templ);
    r.landmarks = lm.source, r.targets = lm.target;
  } else if (r.templ) {
    const RegionLandmarks lm = region_landmarks(*r.mesh, *r.templ, exclude);
    if (lm.labels.size() < 4)
      throw InputError(std::to_string(lm.labels.size()) + " atlas regions in common (cell field 'label'); need at least 4");
    r.landmarks = lm.source, r.targets = lm.target;
  } else {
    if (landmarks.is_none() || targets.is_none()) throw InputError("landmarks= and targets= (or template=) needed");
    r.landmarks = landmark_points(landmarks, *r.mesh, "landmarks");
    r.targets = landmark_points(targets, *r.mesh, "targets");
  }
  r.options.steps = steps;
  if (width) {
    if (!(*width > 0)) throw InputError("width: must be positive (ball units)");
    r.options.lambda = 1 / (*width * *width);
  }
  r.options.width_factor = width_factor;
  r.options.boundary = parse_registration_boundary(boundary);
  r.options.field = parse_registration_field(field);
  r.options.rigid = rigid, r.options.untangle = untangle, r.options.restore_volumes = restore;
  if (preset) r.dense = with_preset(registration_preset_from_string(*preset));
  if (dense_iterations) r.dense.iterations = *dense_iterations;
  r.dense.force = dense_force_from_string(dense_force);
  r.dense.exclude_labels = std::move(exclude);
  r.image = std::move(image), r.templ_image = std::move(template_image);
  r.dense.deadline = Deadline::in_seconds(max_seconds);  // 0: none
  Progress p(std::move(progress));
  r.dense.progress = p.function();
  auto dev = device_for(device);
  auto report = std::make_unique<RegistrationReportPy>();
  auto out = without_gil(&p, [&] {
    Points ball = r.mesh->vertices;
    const RegistrationResult res = run(r, *dev, ball);
    report->metrics = map_metrics(*dev, r.mesh->vertices, ball, r.mesh->tets);
    report->json = to_json(res).dump(-1);
    report->device = dev->name();
    report->landmarks = static_cast<int>(r.landmarks.rows());
    report->landmark_rms_error = res.landmark_rms_error, report->landmark_max_error = res.landmark_max_error;
    report->max_normal_velocity = res.max_normal_velocity, report->inverted_tets = res.inverted_tets;
    auto m = std::make_shared<TetMesh>(*r.mesh);
    m->vertices = std::move(ball);
    m->set_point_field("vertex_volume_ratio", report->metrics.vertex_ratio);
    m->set_cell_field("tet_volume_ratio", report->metrics.tet_ratio);
    return m;
  });
  return py::make_tuple(out, std::move(report));
}

}  // namespace

void bind_register(py::module_& m) {
  py::class_<RegistrationReportPy, Report>(m, "RegistrationReport",
                                           "What register did; to_dict() is the registration's JSON.")
      .def_readonly("device", &RegistrationReportPy::device)
      .def_readonly("landmarks", &RegistrationReportPy::landmarks)
      .def_readonly("landmark_rms_error", &RegistrationReportPy::landmark_rms_error)
      .def_readonly("landmark_max_error", &RegistrationReportPy::landmark_max_error)
      .def_readonly("max_normal_velocity", &RegistrationReportPy::max_normal_velocity)
      .def_readonly("inverted_tets", &RegistrationReportPy::inverted_tets)
      .def_readonly("metrics", &RegistrationReportPy::metrics, "the registered mesh against the mapped one");
  m.def("_register", &register_py, py::arg("mesh"), py::kw_only(), py::arg("landmarks") = py::none(),
        py::arg("targets") = py::none(), py::arg("template") = py::none(), py::arg("template_landmarks") = "regions",
        py::arg("exclude_labels") = std::vector<int>{}, py::arg("preset") = py::none(),
        py::arg("dense_iterations") = py::none(),
        py::arg("dense_force") = "labels", py::arg("image") = nullptr, py::arg("template_image") = nullptr,
        py::arg("steps") = RegistrationOptions{}.steps, py::arg("width") = py::none(),
        py::arg("width_factor") = RegistrationOptions{}.width_factor, py::arg("boundary") = "tangent",
        py::arg("field") = "per-step", py::arg("rigid") = true, py::arg("untangle") = true,
        py::arg("restore") = true, py::arg("max_seconds") = 0.0, py::arg("device") = py::none(),
        py::arg("progress") = py::none());
}

}  // namespace vpm::python
