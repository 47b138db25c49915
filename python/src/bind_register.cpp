// vpm.register: landmarks or a template (region centroids or the moments' affine), dense.
#include "common.hpp"
#include "report.hpp"
#include "vpm/dense_registration.hpp"
#include "vpm/error.hpp"
#include "vpm/image.hpp"
#include "vpm/metrics.hpp"
#include "vpm/registration.hpp"
#include "vpm/registration_preset.hpp"
#include "vpm/template_registration.hpp"
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
  Points landmarks, targets;  // landmarks= and targets=; with template=, the pairs it made
  RegistrationOptions options;
  TemplateRegistrationOptions by_template;
  std::shared_ptr<Image> image, templ_image;
};

RegistrationResult run(Request& r, Device& dev, Points& ball) {
  if (!r.templ) {
    if (r.by_template.dense.iterations > 0) throw InputError("dense_iterations: needs template=");
    return register_landmarks(dev, ball, r.mesh->tets, r.landmarks, r.targets, r.options);
  }
  r.by_template.flow = r.options;
  try {
    TemplateRegistration out = register_to_template(dev, *r.mesh, *r.templ, r.by_template,
                                                    {r.image.get(), r.templ_image.get()});
    ball = std::move(out.ball);
    r.landmarks = std::move(out.landmarks);
    return out.result;
  } catch (const TemplateRegistrationError& e) {
    using Mesh = TemplateRegistrationError::Mesh;
    throw InputError(std::string(e.mesh == Mesh::subject ? "mesh" : e.mesh == Mesh::templ ? "template" : "mesh, template") +
                     ": " + e.what());
  }
}

// long: one keyword argument a line, as `vpm register`'s options
py::tuple register_py(const py::object& mesh, const py::object& landmarks, const py::object& targets,
                      const py::object& templ, const std::string& template_landmarks, std::vector<int> exclude,
                      const std::optional<std::string>& preset, std::optional<int> dense_iterations,
                      const std::string& dense_force, int dense_refine, std::shared_ptr<Image> image,
                      std::shared_ptr<Image> template_image, int steps, std::optional<double> width,
                      double width_factor, const std::string& boundary, const std::string& field, bool rigid,
                      bool untangle, bool restore, double max_seconds, std::optional<std::string> device,
                      py::object progress) {
  Request r;
  r.mesh = mesh_argument(mesh, py::none());
  if (!templ.is_none()) r.templ = mesh_argument(templ, py::none());
  try {
    r.by_template.landmarks = template_landmarks_from_string(template_landmarks);
  } catch (const InputError& e) {
    throw InputError(std::string("template_landmarks: ") + e.what());
  }
  if (r.templ && (!landmarks.is_none() || !targets.is_none()))
    throw InputError("template= and landmarks=/targets= both given; use one");
  if (!r.templ) {
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
  DenseRegistrationOptions& dense = r.by_template.dense;
  if (preset) dense = with_preset(registration_preset_from_string(*preset));
  if (dense_iterations) dense.iterations = *dense_iterations;
  dense.force = dense_force_from_string(dense_force);
  if (dense_refine < 0) throw InputError("dense_refine: expected 0 (none) or more iterations");
  if (dense_refine > 0 && dense.force == DenseForce::labels)
    throw InputError("dense_refine: the image refinement needs dense_force='image' or 'both'");
  dense.refine.iterations = dense_refine;
  r.by_template.exclude_labels = std::move(exclude);
  if (dense.iterations > 0 && dense.force != DenseForce::labels && (!image || !template_image))
    throw InputError("dense_force: image and both need image= and template_image=");
  r.image = std::move(image), r.templ_image = std::move(template_image);
  dense.deadline = Deadline::in_seconds(max_seconds);  // 0: none
  Progress p(std::move(progress));
  dense.progress = p.function();
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
        py::arg("dense_force") = "labels", py::arg("dense_refine") = 0, py::arg("image") = nullptr, py::arg("template_image") = nullptr,
        py::arg("rk_steps") = RegistrationOptions{}.steps, py::arg("width") = py::none(),
        py::arg("width_factor") = RegistrationOptions{}.width_factor, py::arg("flow_boundary") = "tangent",
        py::arg("field") = "per-step", py::arg("rigid") = true, py::arg("untangle") = true,
        py::arg("restore") = true, py::arg("max_seconds") = 0.0, py::arg("device") = py::none(),
        py::arg("progress") = py::none());
}

}  // namespace vpm::python
