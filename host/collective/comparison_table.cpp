// The comparison table writer (vpm/statistics.hpp).
#include <iomanip>

#include "core/atomic_file.hpp"
#include "vpm/statistics.hpp"

namespace vpm {

void write_comparison(const std::string& tsv_path, const CanonicalElements& el, const Reference& ref,
                      const std::vector<std::string>& normal_tables, const std::string& patient_table,
                      const CompareOptions& opt, const Comparison& c) {
  detail::AtomicFile file(tsv_path);
  std::ostream& out = file.stream();
  out << "element\tshell\ttriangle\tpatient\treference_mean\treference_std\tz\tcluster\n" << std::setprecision(10);
  for (int e = 0; e < el.size(); ++e)
    out << e << '\t' << el.shell_of(e) << '\t' << el.triangle_of(e) << '\t' << c.patient[e] << '\t' << c.expected[e] << '\t'
        << ref.std[e] << '\t' << c.z[e] << '\t' << c.cluster[e] << '\n';
  Json j = Json::object();
  j["definition"] = to_json(ref.definition);
  Json r = Json::object();
  r["feature"] = ref.feature;
  r["normalisation"] = to_string(ref.normalisation);
  r["smoothing"] = ref.smoothing;
  r["shrinkage"] = ref.shrinkage;
  r["subjects"] = ref.subjects;
  Json tables = Json::array();
  for (const std::string& t : normal_tables) tables.push_back(t);
  r["tables"] = tables;
  if (!ref.covariates.empty()) {
    Json cov = Json::object();
    cov["table"] = ref.covariate_table;
    Json names = Json::array(), columns = Json::array(), centre = Json::array(), patient = Json::array();
    for (const std::string& n : ref.covariate_names) names.push_back(n);
    for (const std::string& n : ref.covariates) columns.push_back(n);
    for (double v : ref.covariate_centre) centre.push_back(v);
    for (double v : c.covariates) patient.push_back(v);
    cov["names"] = names;
    cov["columns"] = columns;
    cov["centre"] = centre;
    cov["patient"] = patient;
    r["covariates"] = cov;
  }
  if (!ref.image_covariate.empty()) r["image_covariate"] = ref.image_covariate;
  j["reference"] = r;
  j["patient"] = patient_table;
  Json o = Json::object();
  o["threshold"] = opt.threshold;
  o["fdr_q"] = opt.fdr_q;
  o["min_cluster"] = opt.min_cluster;
  o["extend"] = opt.extend;
  o["relative_extent"] = opt.relative_extent;
  o["peak"] = opt.peak;
  o["test"] = to_string(opt.test);
  o["sign"] = opt.sign;
  o["tfce_level"] = opt.tfce_level;
  j["options"] = o;
  j["result"] = to_json(c);
  write_json_file(sidecar_path(tsv_path), j);
  file.commit();
}

}  // namespace vpm
