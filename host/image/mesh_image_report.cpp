// MeshImageReport -> JSON (vpm/mesh_image_report.hpp).
#include "vpm/mesh_image_report.hpp"

namespace vpm {

namespace {

template <class T, size_t N>
Json array_json(const std::array<T, N>& a) {
  Json j = Json::array();
  for (const T& x : a) j.push_back(x);
  return j;
}

Json input_json(const MeshImageReport& r) {
  const MeshImageReport::Input& in = r.input;
  Json j = Json::object();
  j["path"] = in.path;
  if (!r.image_input) {
    j["volume_mm3"] = in.volume_mm3;
    return j;
  }
  j["dims"] = array_json(in.dims);
  j["spacing_mm"] = array_json(in.spacing_mm);
  j["affine_source"] = in.affine_source;
  j["threshold"] = in.threshold;
  if (!in.select_labels.empty()) {
    Json sel = Json::array();
    for (int l : in.select_labels) sel.push_back(l);
    j["select_labels"] = sel;
  }
  j["mask_voxels"] = in.mask_voxels;
  j["mask_volume_mm3"] = in.mask_volume_mm3;
  j["components_removed"] = in.components_removed;
  j["cavities_filled"] = in.cavities_filled;
  j["border_voxels"] = in.border_voxels;
  return j;
}

Json parameters_json(const MeshImageReport& r) {
  const MeshImageReport::Parameters& p = r.parameters;
  Json j = Json::object();
  j["target_edge_mm"] = p.target_edge_mm;
  j["edge_mm"] = p.edge_mm;
  j["remesh_retries"] = p.remesh_retries;
  if (r.image_input) {
    j["grid_mm"] = p.grid_mm;
    j["smooth_sigma_mm"] = p.smooth_sigma_mm;
  }
  j["max_volume_mm3"] = p.max_volume_mm3;
  j["tetgen_switches"] = p.tetgen_switches;
  if (p.voxelize_mm > 0) j["voxelize_mm"] = p.voxelize_mm;
  return j;
}

Json topology_json(const MeshImageReport::Topology& t) {
  Json j = Json::object();
  j["repairs"] = Json::array();
  for (const ClosingRepair& c : t.repairs) {
    Json r = Json::object();
    r["closing_radius_cells"] = c.closing_radius_cells;
    r["closing_radius_mm"] = c.closing_radius_mm;
    r["euler_before"] = c.euler_before;
    r["euler_after"] = c.euler_after;
    j["repairs"].push_back(r);
  }
  j["euler_before"] = t.euler_before;
  j["genus_before"] = t.genus_before;
  j["grid_components_removed"] = t.grid_components_removed;
  j["grid_cavities_filled"] = t.grid_cavities_filled;
  j["closing_radius_cells"] = t.closing_radius_cells;
  j["euler"] = t.euler;
  return j;
}

Json mesh_json(const MeshImageReport::Mesh& m) {
  Json j = Json::object();
  j["vertices"] = m.vertices;
  j["tets"] = m.tets;
  j["boundary_vertices"] = m.boundary_vertices;
  j["boundary_faces"] = m.boundary_faces;
  j["boundary_euler"] = m.boundary_euler;
  j["min_dihedral_deg"] = m.min_dihedral_deg;
  j["max_dihedral_deg"] = m.max_dihedral_deg;
  j["four_boundary_vertex_tets"] = m.four_boundary_vertex_tets;
  j["interior_points_added"] = m.interior_points_added;
  j["edge_splits"] = m.edge_splits;
  j["volume_mm3"] = m.volume_mm3;
  j["surface_volume_mm3"] = m.surface_volume_mm3;
  return j;
}

Json labels_json(const std::map<int, LabelVolume>& labels) {
  Json j = Json::object();
  for (const auto& [l, v] : labels) {
    Json& e = j[std::to_string(l)];
    e["tets"] = v.tets;
    e["volume_mm3"] = v.volume_mm3;
    e["voxels"] = v.voxels;
    e["voxel_volume_mm3"] = v.voxel_volume_mm3;
  }
  return j;
}

}  // namespace

Json to_json(const SurfaceStats& s) {
  Json j = Json::object();
  j["vertices"] = s.vertices;
  j["triangles"] = s.triangles;
  j["euler"] = s.euler;
  j["mean_edge_mm"] = s.mean_edge_mm;
  j["min_angle_deg"] = s.min_angle_deg;
  j["max_angle_deg"] = s.max_angle_deg;
  return j;
}

Json to_json(const MeshImageReport& r) {
  Json j = Json::object();
  j["input"] = input_json(r);
  // An image input has its first timing (mask) before the parameters are chosen; a surface
  // input chooses them first.
  if (!r.image_input) j["parameters"] = parameters_json(r);
  Json wall = Json::object(), cpu = Json::object();
  for (const StageTime& t : r.timings) wall[t.stage] = t.wall_s, cpu[t.stage] = t.cpu_s;
  j["timings_s"] = wall;
  j["cpu_s"] = cpu;
  if (r.image_input) {
    j["parameters"] = parameters_json(r);
    j["topology"] = topology_json(r.topology);
    j["extracted_surface"] = to_json(r.extracted_surface);
    j["extracted_surface"]["volume_mm3"] = r.extracted_surface_volume_mm3;
  }
  j["surface"] = to_json(r.surface);
  j["mesh"] = mesh_json(r.mesh);
  if (r.has_labels) j["labels"] = labels_json(r.labels);
  return j;
}

}  // namespace vpm
