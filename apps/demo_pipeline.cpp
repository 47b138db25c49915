// The demo's pipeline (demo_pipeline.hpp).
#include "demo_pipeline.hpp"

#include <algorithm>
#include <fstream>
#include <sstream>

#include "cli.hpp"
#include "vpm/collective.hpp"
#include "vpm/error.hpp"
#include "vpm/format.hpp"
#include "vpm/io.hpp"
#include "vpm/timing.hpp"

namespace vpm::cli {

namespace fs = std::filesystem;

const std::vector<int> kDemoHeldOut = {71, 72, 77, 78};

Eigen::Vector3d mask_centroid(const Image& im) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  double n = 0;
  for (int k = 0; k < im.dims[2]; ++k)
    for (int j = 0; j < im.dims[1]; ++j)
      for (int i = 0; i < im.dims[0]; ++i)
        if (im.at(i, j, k) > 0) {
          sum += Eigen::Vector3d(i, j, k);
          n += 1;
        }
  if (n == 0) throw InputError(im.path + ": empty mask (no voxel > 0)");
  return im.to_world(sum / n);
}

RegionNames aal_names(const std::string& path) {
  RegionNames names;
  std::ifstream in(path);
  int id;
  std::string name, code;
  while (in >> id >> name >> code) names[id] = name;
  return names;
}

std::string name_of(const RegionNames& names, int l) {
  return names.count(l) ? names.at(l) : "label " + std::to_string(l);
}

Json to_json(const DemoSubject& s) {
  Json j = Json::object();
  j["vertices"] = s.vertices;
  j["tets"] = s.tets;
  j["min_dihedral_deg"] = s.min_dihedral_deg;
  j["mesh_seconds"] = s.mesh_seconds;
  j["map_seconds"] = s.map_seconds;
  j["initial"] = vpm::to_json(s.map.initial);
  j["final"] = vpm::to_json(s.map.final);
  return j;
}

DemoSubject mesh_and_map(Device& dev, const Image& image, const Image& atlas, const MeshImageOptions& mo,
                         const std::string& name, const fs::path& out) {
  DemoSubject s;
  auto t0 = Clock::now();
  TetMesh mesh = mesh_image(image, mo, nullptr, &atlas);
  s.mesh_seconds = seconds_since(t0);
  write_mesh((out / (name + ".vtu")).string(), mesh);
  const ValidationReport vr = validate_mesh(mesh, name);
  info("demo: " + name + ": " + std::to_string(mesh.num_vertices()) + " vertices, " +
       std::to_string(mesh.num_tets()) + " tets, smallest dihedral " + strprintf("%.1f", vr.min_dihedral_deg) +
       " deg (" + strprintf("%.1f", s.mesh_seconds) + " s); mapping");
  t0 = Clock::now();
  BallMapOptions bo;
  bo.volume.progress = [&](const std::string& line) { progress("demo: " + name + ": " + line); };
  s.map = map_to_ball(dev, mesh, vr, name, bo);
  s.map_seconds = seconds_since(t0);
  if (!s.map.convergence.converged) convergence_status("demo: " + name, s.map.convergence, true);  // a warning line
  write_mesh((out / (name + "_ball.vtu")).string(), s.map.mesh);
  write_json_file((out / (name + "_map.json")).string(), vpm::to_json(s.map));
  s.vertices = mesh.num_vertices();
  s.tets = mesh.num_tets();
  s.min_dihedral_deg = vr.min_dihedral_deg;
  return s;
}

DemoRegistration register_demo_subject(Device& dev, const DemoSubject& tmpl, const DemoSubject& subj,
                                       const RegistrationOptions& flow, const DenseRegistrationOptions& dense,
                                       const Image& tmpl_image, const Image& subj_image, const fs::path& out) {
  DemoRegistration r;
  r.tmpl_labels = cell_labels(tmpl.map.mesh);
  r.subj_labels = cell_labels(subj.map.mesh);
  const TetMesh& sm = subj.map.mesh;
  TemplateRegistrationOptions opt;
  opt.exclude_labels = kDemoHeldOut;  // held out: neither landmarks nor the dense force see them
  opt.flow = flow;
  opt.dense = dense;
  const auto t0 = Clock::now();
  TemplateRegistration reg = register_to_template(dev, sm, tmpl.map.mesh, opt, {&subj_image, &tmpl_image});
  r.seconds = seconds_since(t0);
  r.landmark_labels = std::move(reg.landmark_labels);
  write_landmarks_csv((out / "landmarks.csv").string(), reg.landmarks);
  write_landmarks_csv((out / "targets.csv").string(), reg.targets);
  info("demo: registered subject to colin27 by " + std::to_string(r.landmark_labels.size()) + " region centroids");
  r.registered = std::move(reg.ball);
  r.result = reg.result;
  if (reg.dense) r.dense = std::move(*reg.dense);
  r.metrics = map_metrics(dev, sm.vertices, r.registered, sm.tets);
  return r;
}

Json to_json(const DemoRegistration& r) {
  Json j = vpm::to_json(registration_summary(r.result, r.metrics));
  j["landmarks"] = static_cast<long>(r.landmark_labels.size());
  j["rotation_deg"] = r.result.report.rotation_deg;
  j["dense"] = vpm::to_json(r.dense);
  return j;
}

namespace {
std::string two_pcts(const char* f, const MapMetrics& m) {
  return strprintf(f, 100 * m.vertex_volume_ratio.mean_abs_dev) + " / " + strprintf(f, 100 * m.tet_volume_ratio.mean_abs_dev);
}
}  // namespace

std::string subjects_summary(const std::string& heading, const DemoSubject& t, const DemoSubject& s,
                             const DemoRegistration& reg) {
  std::ostringstream out;
  auto row = [&](const std::string& what, const std::string& a, const std::string& b) {
    std::string line = strprintf("  %-34s %14s %14s", what.c_str(), a.c_str(), b.c_str());
    line.erase(line.find_last_not_of(' ') + 1);
    out << line << "\n";
  };
  out << heading << "\n";
  row("", "colin27", "subject");
  row("mesh vertices / tets", std::to_string(t.vertices) + "/" + std::to_string(t.tets),
      std::to_string(s.vertices) + "/" + std::to_string(s.tets));
  row("smallest dihedral angle (deg)", strprintf("%.1f", t.min_dihedral_deg), strprintf("%.1f", s.min_dihedral_deg));
  row("initial map: vertex / tet |r-1|", two_pcts("%.1f%%", t.map.initial), two_pcts("%.1f%%", s.map.initial));
  row("volume map: vertex / tet |r-1|", two_pcts("%.2f%%", t.map.final), two_pcts("%.2f%%", s.map.final));
  row("inverted tets", std::to_string(t.map.final.inverted_tets), std::to_string(s.map.final.inverted_tets));
  row("mesh + map seconds", strprintf("%.1f", t.mesh_seconds) + " + " + strprintf("%.1f", t.map_seconds),
      strprintf("%.1f", s.mesh_seconds) + " + " + strprintf("%.1f", s.map_seconds));
  const auto kept = std::count_if(reg.dense.iterations.begin(), reg.dense.iterations.end(),
                                  [](const auto& i) { return i.accepted; });
  out << "registration of subject to colin27: " << reg.landmark_labels.size() << " region centroids, landmark rms "
      << strprintf("%.1e", reg.result.landmark_rms_error) << ", max |u.n| "
      << strprintf("%.1e", reg.result.max_normal_velocity) << ", vertex / tet |r-1| " << two_pcts("%.2f%%", reg.metrics)
      << ", " << reg.metrics.inverted_tets << " inverted, " << kept << " of " << reg.dense.iterations.size()
      << " dense iterations kept, " << strprintf("%.1f", reg.seconds) << " s\n";
  return out.str();
}

void write_registered(const std::string& path, const TetMesh& subject, const DemoRegistration& reg,
                      const std::vector<std::pair<std::string, Eigen::VectorXd>>& extra) {
  TetMesh mesh = subject;
  mesh.vertices = reg.registered;
  mesh.set_point_field("registration_vertex_volume_ratio", reg.metrics.vertex_ratio);
  mesh.set_cell_field("registration_tet_volume_ratio", reg.metrics.tet_ratio);
  for (const auto& [name, values] : extra) mesh.set_point_field(name, values);
  write_mesh(path, mesh);
}

}  // namespace vpm::cli
