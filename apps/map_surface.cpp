// `vpm map SURFACE -o OUT` (map_surface.hpp): closed surfaces to the sphere, disk-like ones to the
// disk.
#include "map_surface.hpp"

#include <algorithm>
#include <vector>

#include "vpm/device.hpp"
#include "vpm/error.hpp"
#include "vpm/format.hpp"
#include "vpm/initial_map.hpp"
#include "vpm/io.hpp"
#include "vpm/json.hpp"
#include "vpm/surface_map.hpp"

namespace vpm::cli {

namespace {

// The point field an overlay file becomes: its name without the folder, FreeSurfer's hemisphere
// prefix (lh., rh.) and GIfTI's suffixes (lh.thickness.shape.gii -> thickness, lh.curv -> curv).
std::string overlay_name(const std::string& path) {
  std::string n = path.substr(path.find_last_of('/') + 1);
  for (const char* prefix : {"lh.", "rh."})
    if (n.rfind(prefix, 0) == 0) n = n.substr(3);
  for (const char* suffix : {".shape.gii", ".func.gii", ".gii"})
    if (n.size() > std::string(suffix).size() && n.compare(n.size() - std::string(suffix).size(), std::string::npos, suffix) == 0) {
      n.resize(n.size() - std::string(suffix).size());
      break;
    }
  return n.empty() ? "overlay" : n;
}

// --overlays A,B: each file's values, one a vertex of `surface` (InputError naming the file).
std::vector<Field> read_overlays(const std::string& list, const TriSurface& surface) {
  std::vector<Field> fields;
  size_t start = 0;
  while (start <= list.size()) {
    const size_t comma = std::min(list.find(',', start), list.size());
    const std::string path = list.substr(start, comma - start);
    start = comma + 1;
    if (path.empty()) continue;
    const Eigen::VectorXd v = read_overlay(path);
    if (v.size() != surface.vertices.rows())
      throw InputError(path + ": " + std::to_string(v.size()) + " values for a surface of " +
                       std::to_string(surface.vertices.rows()) + " vertices (another subject's or hemisphere's?)");
    fields.push_back({overlay_name(path), v, false});
  }
  return fields;
}

}  // namespace

int map_surface(const Args& args, const std::string& in, const std::string& out, Clock::time_point t_start) {
  for (const char* flag : {"--method", "--solver", "--boundary", "--preconditioner", "--rk-steps"})
    if (args.has(flag))
      throw InputError(std::string("option ") + flag + ": applies to tet meshes only; " + in +
                       " is a surface, mapped to the sphere");
  if (!is_surface_output_path(out))
    throw InputError(out + ": unknown output extension for a surface (expected .vtp, .gii, .off, .obj, .stl or a FreeSurfer name)");
  SurfaceMapOptions so;
  so.tolerance = args.get_double("--tolerance", so.tolerance);
  if (!(so.tolerance >= 0)) throw InputError("option --tolerance: must be >= 0");
  so.polish_rounds = args.get_int("--rounds", so.polish_rounds);
  if (so.polish_rounds < 0) throw InputError("option --rounds: must be >= 0");
  so.sphere.sphere_density = parse_option("--sphere", [&] { return parse_sphere_density(args.get("--sphere", "area")); });
  so.sphere.sphere_start = parse_option("--sphere-start", [&] { return parse_sphere_start(args.get("--sphere-start", "auto")); });
  so.sphere.density_solve = parse_option("--sphere-solve", [&] { return parse_density_solve(args.get("--sphere-solve", "auto")); });
  so.deadline = time_budget(args, t_start);
  so.progress = [](const std::string& line) { progress(line); };
  const auto report_path = args.get("--report");

  auto t0 = Clock::now();
  const TriSurface surface = read_surface(in);
  const std::vector<Field> overlays = read_overlays(args.get("--overlays", ""), surface);
  const double t_read = seconds_since(t0);
  progress("read " + in + ": " + std::to_string(surface.vertices.rows()) + " vertices, " +
           std::to_string(surface.triangles.rows()) + " triangles");
  // closed: to the sphere; one boundary loop: to the disk (the checks' messages name the file)
  const SurfaceDomain domain = surface_domain(surface);
  Device& dev = Device::current();
  SurfaceMapResult r;
  if (domain == SurfaceDomain::sphere) {
    validate_closed_surface(surface, in);
    r = map_to_sphere(surface, so, &dev);
  } else {
    validate_disk_surface(surface, in);
    r = map_to_disk(surface, so);
  }
  const SurfaceMapReport& rep = r.report;

  // the mapped surface: the input's faces, or with its ears split (disk; vertices appended, the
  // input positions and overlays there their edge's means)
  TriSurface mapped;
  mapped.vertices = r.sphere;
  mapped.triangles = mapped_faces(surface.triangles, r);
  mapped.point_data.push_back({"original_position", extend_to_mapped(surface.vertices, r), false});
  mapped.point_data.push_back({"vertex_area_ratio", rep.final.vertex_ratio, false});
  mapped.cell_data.push_back({"face_area_ratio", rep.final.face_ratio, false});
  for (const Field& f : overlays) mapped.point_data.push_back({f.name, extend_to_mapped(f.values, r), f.integer});
  t0 = Clock::now();
  write_surface(out, mapped);
  Json report = to_json(rep);
  report["device"] = dev.name();
  report["timings_s"]["read"] = t_read;
  report["timings_s"]["write"] = seconds_since(t0);
  report["timings_s"]["total"] = seconds_since(t_start);
  const bool sphere = domain == SurfaceDomain::sphere;
  info("wrote " + out + ": " + std::to_string(mapped.vertices.rows()) + " vertices " +
       (sphere ? "on the unit sphere, " : "in the unit disk, ") + std::to_string(mapped.triangles.rows()) +
       " triangles; face area mean |r-1| " + pct(rep.initial.face_area_ratio.mean_abs_dev) +
       (sphere ? " (sphere map) -> " : " (disk embedding) -> ") + pct(rep.final.face_area_ratio.mean_abs_dev) +
       ", 0 flipped faces");
  if (report_path) write_json_file(*report_path, report);
  if (rep.stop_reason == "time_budget" && !rep.converged)
    return time_budget_status("map", "face area mean |r-1| " + pct(rep.final.face_area_ratio.mean_abs_dev),
                              args.has("--allow-partial"));
  return convergence_status("map", "face area mean |r-1|", rep.final.face_area_ratio.mean_abs_dev, so.tolerance,
                            rep.stop_reason, args.has("--allow-partial"), pct);
}

}  // namespace vpm::cli
