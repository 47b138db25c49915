// The collective analysis (paper 6.2) from Python: vpm.Elements, sample, compare, the tables,
// and the pull-back and map-back through a registered mesh.
#include <optional>

#include "common.hpp"
#include "report.hpp"
#include "vpm/calibration.hpp"
#include "vpm/covariates.hpp"
#include "vpm/elements.hpp"
#include "vpm/error.hpp"
#include "vpm/format.hpp"
#include "vpm/json.hpp"
#include "vpm/label_names.hpp"
#include "vpm/locate.hpp"
#include "vpm/map_back.hpp"
#include "vpm/sampling.hpp"
#include "vpm/statistics.hpp"

namespace vpm::python {
namespace {

template <class T>
py::array vector_array(std::vector<T> v) {
  return owned_array(Eigen::Matrix<T, Eigen::Dynamic, 1>(Eigen::Map<Eigen::Matrix<T, Eigen::Dynamic, 1>>(v.data(), v.size())));
}

py::dict table_features(const ElementTable& t) {
  py::dict out;
  for (const auto& f : t.features) {
    py::dict d;
    d["mean"] = vector_array(f.mean);
    d["std"] = vector_array(f.std);
    d["count"] = vector_array(f.count);
    d["source"] = f.source;
    out[py::str(f.name)] = d;
  }
  return out;
}

// Elements of `definition`, or those of a vpm.Elements.
std::shared_ptr<CanonicalElements> elements_of(const py::object& el) {
  if (el.is_none()) return std::make_shared<CanonicalElements>();
  return el.cast<std::shared_ptr<CanonicalElements>>();
}

std::shared_ptr<ElementTable> sample_py(const py::object& mesh, const py::dict& images, const py::object& labels,
                                        const py::object& elements, const std::string& subject) {
  auto m = mesh_argument(mesh, py::none());
  auto el = elements_of(elements);
  std::vector<std::pair<std::string, std::shared_ptr<Image>>> named;
  for (auto [k, v] : images) named.emplace_back(k.cast<std::string>(), v.cast<std::shared_ptr<Image>>());
  auto lab = labels.is_none() ? nullptr : labels.cast<std::shared_ptr<Image>>();
  if (named.empty() && !lab) throw InputError("nothing to sample: give images={name: image} and/or labels=");
  auto t = std::make_shared<ElementTable>();
  t->definition = el->definition();
  t->subject = subject;
  without_gil(nullptr, [&] {
    const Points positions = pull_back_samples(*el, m->vertices, m->tets, native_positions(*m, "mesh"));
    for (const auto& [name, img] : named) t->features.push_back(sample_feature(*el, positions, *img, name));
    if (lab) t->label_images.push_back(sample_label_fractions(*el, positions, *lab));
    return 0;
  });
  return t;
}

std::vector<ElementTable> tables_of(const py::list& items) {
  std::vector<ElementTable> out;
  for (auto it : items)
    out.push_back(py::isinstance<py::str>(it) ? read_subject_table(it.cast<std::string>()) : it.cast<ElementTable>());
  return out;
}

// The normals' names as a calibration records them: a table given by its path is named by the
// path (as `vpm calibrate --normals` names it), one in memory by its subject, else "normal i".
std::vector<std::string> names_of(const py::list& items, const std::vector<ElementTable>& tables) {
  std::vector<std::string> names;
  for (size_t i = 0; i < tables.size(); ++i)
    names.push_back(py::isinstance<py::str>(items[i])  ? items[i].cast<std::string>()
                    : tables[i].subject.empty()         ? "normal " + std::to_string(i)
                                                        : tables[i].subject);
  return names;
}

// What compare and calibrate share: the feature, the reference's recipe and the compare options
// (the keyword arguments are the fields' names, but fdr); min_cluster as given.
// long: the keyword arguments, one line each
CalibrationSettings settings_of(const std::string& feature, const std::string& normalisation, double threshold, double fdr,
                                int min_cluster, double extend, double relative_extent, double peak,
                                const std::string& sign, const std::string& test, int smooth, double shrink,
                                const std::vector<std::string>& covariates, const std::string& participants,
                                const std::string& image_covariate, double tfce_level) {
  CalibrationSettings s;
  s.feature = feature;
  s.normalisation = parse_normalisation(normalisation);
  s.smoothing = smooth, s.shrinkage = shrink, s.covariates = covariates, s.image_covariate = image_covariate;
  CompareOptions& o = s.compare;
  o.threshold = threshold, o.fdr_q = fdr, o.min_cluster = min_cluster, o.extend = extend, o.peak = peak;
  o.relative_extent = relative_extent;
  o.tfce_level = tfce_level;
  o.test = parse_single_case_test(test);
  if (sign == "both") o.sign = 0;
  else if (sign == "hyper") o.sign = 1;
  else if (sign == "hypo") o.sign = -1;
  else throw InputError("sign: '" + sign + "' is not one of both, hyper, hypo");
  if (const auto bad = compare_option_error(o))
    throw InputError((bad->field == "fdr_q" ? std::string("fdr") : bad->field) + ": " + bad->problem);
  if (covariates.empty() != participants.empty())
    throw InputError("covariates and participants: give both (the columns and the table that holds them) or neither");
  return s;
}

// long: the keyword arguments of `vpm compare`, one line each
py::dict compare_py(const py::list& normals, const py::object& patient, const std::string& feature,
                    const std::string& normalisation, double threshold, double fdr, int min_cluster, double extend,
                    double relative_extent, double peak, const std::string& sign, const std::string& test, int smooth, double shrink,
                    const std::vector<std::string>& covariates, const std::string& participants,
                    const std::string& image_covariate, double tfce_level, const std::string& calibration,
                    const std::string& calibration_source) {
  const std::vector<ElementTable> ns = tables_of(normals);
  py::list one;
  one.append(patient);
  const ElementTable p = tables_of(one).front();
  if (ns.empty()) throw InputError("normals: no tables");
  const CalibrationSettings s = settings_of(feature, normalisation, threshold, fdr, min_cluster, extend, relative_extent,
                                            peak, sign, test, smooth, shrink, covariates, participants,
                                            image_covariate, tfce_level);
  const std::vector<std::string> names = names_of(normals, ns);
  CompareOptions o = s.compare;
  CalibratedRule rule;
  if (!calibration.empty()) {  // what a calibration of these normals with these options sets
    rule = calibrated_rule(Json::parse(calibration), s, names, calibration_source);
    o.min_cluster = rule.min_cluster, o.peak = rule.peak;
    if (rule.tfce_level > 0) {
      if (tfce_level > 0) throw InputError("tfce_level: " + calibration_source + " is a TFCE calibration; it sets the level");
      o.tfce_level = rule.tfce_level;
    }
  }
  const auto [c, ref] = without_gil(nullptr, [&] {
    const CanonicalElements el(p.definition);
    std::optional<Covariates> cov;
    if (!covariates.empty()) cov = read_covariates(participants, covariates);
    Reference r = build_reference(el, ns, names, feature, s.normalisation, smooth, shrink,
                                  cov ? covariate_design(*cov, ns, names) : CovariateDesign{}, image_covariate);
    const std::vector<double> row = cov ? covariate_row(*cov, p.subject, "the patient") : std::vector<double>{};
    Comparison cmp = compare_to_reference(el, r, p, o, row);
    family_p_values(cmp, rule);
    return std::make_pair(std::move(cmp), r);
  });
  py::dict out = json_to_python(to_json(c)).cast<py::dict>();
  out["z"] = vector_array(c.z);
  out["patient"] = vector_array(c.patient);
  out["cluster"] = vector_array(c.cluster);
  out["reference_mean"] = vector_array(c.expected);  // with covariates: the patient's prediction
  out["reference_std"] = vector_array(ref.std);
  out["min_cluster"] = o.min_cluster, out["peak"] = o.peak, out["tfce_level"] = o.tfce_level;
  return out;
}

// `vpm calibrate`: each normal left out in turn against the others; peak < 0 calibrates the peak
// level too ("auto"). The calibration's JSON as `vpm calibrate -o` writes it.
// long: the keyword arguments of `vpm calibrate`, one line each
py::object calibrate_py(const py::list& normals, const std::string& feature, const std::string& normalisation,
                        double threshold, double fdr, double extend, double relative_extent, double peak,
                        const std::string& sign, const std::string& test, int smooth, double shrink,
                        const std::vector<std::string>& covariates, const std::string& participants,
                        const std::string& image_covariate, double rate, bool tfce) {
  const std::vector<ElementTable> ns = tables_of(normals);
  if (ns.size() < 4) throw InputError("normals: a calibration leaves each out in turn and needs at least 4, got " +
                                      std::to_string(ns.size()));
  CalibrationSettings s = settings_of(feature, normalisation, threshold, fdr, 1, extend, relative_extent,
                                      peak < 0 ? 0 : peak, sign, test, smooth, shrink, covariates, participants,
                                      image_covariate, 0);
  s.calibrate_peak = peak < 0;
  s.calibrate_tfce = tfce;
  s.rate = rate;
  if (tfce && (peak != 0)) throw InputError("tfce and peak exclude each other (a TFCE focus has no peak rule)");
  if (!(rate >= 0)) throw InputError("rate: must be >= 0 false clusters per 10 normals");
  const std::vector<std::string> names = names_of(normals, ns);
  const ClusterCalibration c = without_gil(nullptr, [&] {
    const CanonicalElements el(ns.front().definition);
    std::optional<Covariates> cov;
    if (!covariates.empty()) cov = read_covariates(participants, covariates);
    return calibrate_min_cluster(el, ns, names, s, cov ? covariate_design(*cov, ns, names) : CovariateDesign{});
  });
  if (c.min_cluster == 0)
    throw NumericalError("calibrate: no min_cluster keeps the normals at or under " + format_sig(rate) +
                         " false clusters per 10 normals (a peak rule keeps small clusters); lower peak or raise rate");
  return json_to_python(to_json(c));
}

void bind_elements(py::module_& m) {
  py::class_<CanonicalElements, std::shared_ptr<CanonicalElements>>(
      m, "Elements", "The canonical volume elements of the ball (paper 6.2; docs/collective.md).")
      .def(py::init([](int level, int shells, int samples, const std::string& layout) {
             ElementDefinition d;
             d.level = level, d.shells = shells, d.samples = samples, d.layout = parse_element_layout(layout);
             if (d.layout == ElementLayout::graded) d.shells = graded_shells(level);
             return std::make_shared<CanonicalElements>(d);
           }),
           py::arg("level") = 3, py::arg("shells") = 8, py::arg("samples") = 64, py::arg("layout") = "shells")
      .def_property_readonly("size", &CanonicalElements::size)
      .def("__len__", &CanonicalElements::size)
      .def_property_readonly("samples",
                             [](const py::object& self) {
                               const auto& el = self.cast<const CanonicalElements&>();
                               auto& s = const_cast<Points&>(el.samples());
                               return view_array(s.data(), s.rows(), 3, self);
                             }, "(size * S, 3) sample points, element e's at rows e*S .. e*S + S - 1 (a view)")
      .def("centres", [](const CanonicalElements& el) {
        Points c(el.size(), 3);
        for (int e = 0; e < el.size(); ++e) c.row(e) = el.centre(e).transpose();
        return owned_array(std::move(c));
      })
      .def("element_of", [](const CanonicalElements& el, const py::object& pts) {
        const Points p = to_points(pts, "points");
        Eigen::VectorXi out(p.rows());
        for (Eigen::Index i = 0; i < p.rows(); ++i) out(i) = el.element_of(p.row(i).transpose());
        return owned_array(std::move(out));
      }, py::arg("points"))
      .def("definition", [](const CanonicalElements& el) { return json_to_python(to_json(el.definition())); })
      .def("write", [](const CanonicalElements& el, const std::string& path) { write_element_table(path, el); }, py::arg("path"));
}

}  // namespace

void bind_collective(py::module_& m) {
  bind_elements(m);
  py::class_<ElementTable, std::shared_ptr<ElementTable>>(m, "ElementTable", "One subject's per-element features.")
      .def_readonly("subject", &ElementTable::subject)
      .def_property_readonly("features", &table_features, "{name: {'mean', 'std', 'count', 'source'}}")
      .def_property_readonly("labels", [](const ElementTable& t) {
        py::dict out;
        for (const auto& li : t.label_images)
          for (size_t l = 0; l < li.labels.size(); ++l) out[py::int_(li.labels[l])] = vector_array(li.fraction[l]);
        return out;
      }, "{label: per-element fraction}")
      .def("definition", [](const ElementTable& t) { return json_to_python(to_json(t.definition)); })
      .def("write", [](const ElementTable& t, const std::string& path) { write_subject_table(path, t); }, py::arg("path"));
  m.def("read_table", [](const std::string& path) { return std::make_shared<ElementTable>(read_subject_table(path)); },
        py::arg("path"), "Reads a subject table written by `vpm sample` or ElementTable.write.");
  m.def("_sample", &sample_py, py::arg("mesh"), py::arg("images"), py::arg("labels") = py::none(),
        py::arg("elements") = py::none(), py::arg("subject") = "");
  m.def("_compare", &compare_py, py::arg("normals"), py::arg("patient"), py::arg("feature"), py::kw_only(),
        py::arg("normalisation") = "proportional", py::arg("threshold") = 3.0, py::arg("fdr") = 0.0,
        py::arg("min_cluster") = 3, py::arg("extend") = 0.0, py::arg("relative_extent") = 0.0, py::arg("peak") = 0.0, py::arg("sign") = "both",
        py::arg("test") = "z", py::arg("smooth") = 0, py::arg("shrink") = 0.0,
        py::arg("covariates") = std::vector<std::string>{}, py::arg("participants") = "",
        py::arg("image_covariate") = "", py::arg("tfce_level") = 0.0, py::arg("calibration") = "",
        py::arg("calibration_source") = "calibration");
  m.def("_calibrate", &calibrate_py, py::arg("normals"), py::arg("feature"), py::kw_only(),
        py::arg("normalisation") = "proportional", py::arg("threshold") = 3.0, py::arg("fdr") = 0.0,
        py::arg("extend") = 0.0, py::arg("relative_extent") = 0.0, py::arg("peak") = 0.0, py::arg("sign") = "both",
        py::arg("test") = "z", py::arg("smooth") = 0, py::arg("shrink") = 0.0,
        py::arg("covariates") = std::vector<std::string>{}, py::arg("participants") = "",
        py::arg("image_covariate") = "", py::arg("rate") = 1.0, py::arg("tfce") = false);
  m.def("to_native", [](const py::object& mesh, const py::object& points) {
    auto msh = mesh_argument(mesh, py::none());
    Points p = to_points(points, "points");
    return owned_array(without_gil(nullptr, [&] {
      return pull_back_points(p, msh->vertices, msh->tets, native_positions(*msh, "mesh"));
    }));
  }, py::arg("mesh"), py::arg("points"),
  "Ball points (n, 3) carried to native space (mm) through a mapped or registered mesh (its\n"
  "original_position field): containing tet, the same barycentric combination.");
  m.def("to_image", [](const py::object& mesh, const std::shared_ptr<CanonicalElements>& el, const py::object& values,
                       const std::shared_ptr<Image>& grid) {
    auto msh = mesh_argument(mesh, py::none());
    const auto v = py::array_t<double, py::array::forcecast>::ensure(values);
    if (!v || v.ndim() != 1 || v.shape(0) != el->size()) throw InputError("values: expected one value per element");
    std::vector<double> vals(v.data(), v.data() + v.shape(0));
    return std::make_shared<Image>(without_gil(nullptr, [&] { return native_volume(*msh, *el, vals, *grid); }));
  }, py::arg("mesh"), py::arg("elements"), py::arg("values"), py::arg("grid"),
  "Per-element values mapped back onto `grid`'s voxels through a registered mesh (each voxel\n"
  "pushed into the ball), as `vpm compare --image` writes its z-map.");
  m.def("read_label_names", [](const std::string& path) { return read_label_names(path); }, py::arg("path"),
        "{id: name} from AAL's table ('id name [code]') or a FreeSurfer colour table ('id name R G B A').");
}

}  // namespace vpm::python
