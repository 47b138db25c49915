// Benchmark: mesh the Colin27 brain (Debian mricron-data) at the paper's size and, with
// --large, at about 1M tets; AAL labels; prints sizes, per-stage times, smallest dihedral
// angle and label volumes vs voxel counts; writes <build>/bench-results/mesh_image.json
//
//   vpm_bench_mesh_image [--runs R] [--large] [--only-large] [--image PATH] [--labels PATH]
//                        [--target-vertices N] [--max-volume V] [--out JSON]
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "vpm/config.hpp"
#include "vpm/json.hpp"
#include "vpm/mesh_image.hpp"
#include "bench_util.hpp"

using vpm::bench::median;

namespace {

const char* kDir = "/usr/share/mricron/templates/";
const int kLabels[] = {71, 72, 77, 78};
const char* kNames[] = {"Caudate_L", "Caudate_R", "Thalamus_L", "Thalamus_R"};

// The stage's time in `rep`, or null when it did not run.
const vpm::StageTime* stage(const vpm::MeshImageReport& rep, const std::string& name) {
  for (const vpm::StageTime& t : rep.timings)
    if (t.stage == name) return &t;
  return nullptr;
}

vpm::Json run_case(const std::string& name, const vpm::Image& img, const vpm::Image* atlas,
                   const vpm::MeshImageOptions& o, int runs) {
  std::vector<double> totals, cpus;
  vpm::MeshImageReport last;
  vpm::Json times = vpm::Json::array();
  for (int r = 0; r < runs; ++r) {
    vpm::MeshImageReport rep;
    vpm::mesh_image(img, o, &rep, atlas);
    totals.push_back(stage(rep, "total")->wall_s);
    cpus.push_back(stage(rep, "total")->cpu_s);
    vpm::Json wall = vpm::Json::object();
    for (const vpm::StageTime& t : rep.timings) wall[t.stage] = t.wall_s;
    times.push_back(wall);
    last = rep;
  }
  const vpm::MeshImageReport::Mesh& m = last.mesh;
  std::printf("\n== %s (%d run%s) ==\n", name.c_str(), runs, runs > 1 ? "s" : "");
  std::printf("vertices %d, tets %d, boundary vertices %d, smallest dihedral %.2f deg, largest %.2f deg\n",
              m.vertices, m.tets, m.boundary_vertices, m.min_dihedral_deg, m.max_dihedral_deg);
  std::printf("boundary Euler %d, four-boundary-vertex tets %d (interior points added %d)\n",
              m.boundary_euler, m.four_boundary_vertex_tets, m.interior_points_added);
  std::printf("surface: %d triangles, angles %.2f .. %.2f deg, mean edge %.2f mm; topology: genus before %d, closing radius %d\n",
              last.surface.triangles, last.surface.min_angle_deg, last.surface.max_angle_deg,
              last.surface.mean_edge_mm, last.topology.genus_before, last.topology.closing_radius_cells);
  std::printf("times (last run, wall/cpu s):");
  for (const char* k : {"mask", "grid", "topology", "extract", "remesh", "tetgen", "labels", "total"})
    if (const vpm::StageTime* t = stage(last, k)) std::printf(" %s %.2f/%.2f", k, t->wall_s, t->cpu_s);
  std::printf("\nmedian total %.2f s wall, %.2f s cpu over %d run(s)\n", median(totals), median(cpus), runs);
  vpm::Json out = vpm::Json::object();
  out["runs"] = runs;
  out["median_total_s"] = median(totals);
  out["median_total_cpu_s"] = median(cpus);
  out["timings_per_run"] = times;
  out["report"] = vpm::to_json(last);
  if (atlas) {
    vpm::Json lab = vpm::Json::object();
    for (int i = 0; i < 4; ++i) {
      const auto e = last.labels.find(kLabels[i]);
      if (e == last.labels.end()) continue;
      const double vol = e->second.volume_mm3, vox = e->second.voxel_volume_mm3;
      std::printf("%-11s label %d: mesh %.0f mm^3, voxels %.0f mm^3, %+.1f %%\n", kNames[i], kLabels[i], vol, vox,
                  100 * (vol / vox - 1));
      vpm::Json& l = lab[kNames[i]];
      l["label"] = kLabels[i];
      l["mesh_volume_mm3"] = vol;
      l["voxel_volume_mm3"] = vox;
      l["relative_error"] = vol / vox - 1;
    }
    out["label_volumes"] = lab;
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  int runs = 3;
  bool large = false, only_large = false;
  std::string image = std::string(kDir) + "ch2bet.nii.gz", labels = std::string(kDir) + "aal.nii.gz";
  std::string out_path = VPM_BENCH_OUT "/mesh_image.json";
  vpm::MeshImageOptions paper;
  double large_volume = 3.4;  // mm^3: about 1.1M tets on Colin27
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto val = [&]() -> std::string {
      if (i + 1 >= argc) { std::fprintf(stderr, "%s needs a value\n", a.c_str()); std::exit(2); }
      return argv[++i];
    };
    if (a == "--runs") runs = std::max(1, std::atoi(val().c_str()));
    else if (a == "--large") large = true;
    else if (a == "--only-large") large = only_large = true;
    else if (a == "--image") image = val();
    else if (a == "--labels") labels = val();
    else if (a == "--target-vertices") paper.target_vertices = std::atoi(val().c_str());
    else if (a == "--max-volume") paper.max_volume = std::atof(val().c_str());
    else if (a == "--large-max-volume") large_volume = std::atof(val().c_str());
    else if (a == "--smooth") paper.smooth = std::atof(val().c_str());
    else if (a == "--out") out_path = val();
    else { std::fprintf(stderr, "unknown option %s\n", a.c_str()); return 2; }
  }
  if (!std::filesystem::exists(image)) {
    std::fprintf(stderr, "%s not found (install mricron-data)\n", image.c_str());
    return 0;
  }
  const vpm::Image img = vpm::read_nifti(image);
  vpm::Image atlas;
  const bool have_atlas = !labels.empty() && labels != "none" && std::filesystem::exists(labels);
  if (have_atlas) atlas = vpm::read_nifti(labels);
  vpm::Json result = vpm::Json::object();
  result["image"] = image;
  result["labels"] = have_atlas ? labels : std::string("none");
  result["machine"] = "2-core CPU (shared), Release build";
  if (!only_large) result["paper_size"] = run_case("paper size (default options)", img, have_atlas ? &atlas : nullptr, paper, runs);
  if (large) {
    vpm::MeshImageOptions o = paper;
    o.max_volume = large_volume;
    result["large"] = run_case("large (--max-volume " + std::to_string(large_volume) + ")", img,
                               have_atlas ? &atlas : nullptr, o, std::max(1, runs / 3));
  }
  std::filesystem::create_directories(std::filesystem::path(out_path).parent_path());
  vpm::write_json_file(out_path, result);
  std::printf("\nwrote %s\n", out_path.c_str());
  return 0;
}
