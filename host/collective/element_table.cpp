// The element table writer (vpm/elements.hpp).
#include <Eigen/Core>
#include <cmath>
#include <iomanip>

#include "core/atomic_file.hpp"
#include "vpm/elements.hpp"

namespace vpm {

std::string sidecar_path(const std::string& table_path) {
  const std::string ext = ".tsv";
  if (table_path.size() > ext.size() && table_path.compare(table_path.size() - ext.size(), ext.size(), ext) == 0)
    return table_path.substr(0, table_path.size() - ext.size()) + ".json";
  return table_path + ".json";
}

namespace {

Json sidecar(const CanonicalElements& el) {
  Json j = Json::object();
  j["definition"] = to_json(el.definition());
  j["elements"] = el.size();
  j["triangles"] = el.triangles();
  const ElementVolumeStats st = el.volume_stats();
  Json v = Json::object();
  v["mean"] = st.mean;
  v["min"] = st.min;
  v["max"] = st.max;
  v["std_relative"] = st.std_relative;
  j["volume"] = v;
  Json c = Json::object();
  c["element"] = "element id = shell * triangles + triangle";
  c["shell"] = "radial shell k: radii (k/K)^(1/3) to ((k+1)/K)^(1/3)";
  c["triangle"] = "triangle of the icosahedral subdivision of the sphere";
  c["volume"] = "exact volume in the unit ball (ball volume 4 pi / 3)";
  c["centre_x"] = "direction of the triangle centroid at the radius halving the shell volume (ball coordinates)";
  j["columns"] = c;
  return j;
}

}  // namespace

void write_element_table(const std::string& tsv_path, const CanonicalElements& el) {
  detail::AtomicFile f(tsv_path);
  std::ostream& out = f.stream();
  out << "element\tshell\ttriangle\tvolume\tcentre_x\tcentre_y\tcentre_z\n" << std::setprecision(17);
  for (int e = 0; e < el.size(); ++e) {
    const Eigen::Vector3d c = el.centre(e);
    out << e << '\t' << el.shell_of(e) << '\t' << el.triangle_of(e) << '\t' << el.volume(e) << '\t' << c.x() << '\t'
        << c.y() << '\t' << c.z() << '\n';
  }
  const std::string json_path = sidecar_path(tsv_path);
  write_json_file(json_path, sidecar(el));
  f.commit();
}

}  // namespace vpm
