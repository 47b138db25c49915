// vpm_bench_sphere_map [--sizes 100000,400000] [--repeats 3] [--json FILE] [MESH|SURFACE ...]:
// the initial map's step 2 (vpm::sphere_map: conformal map, Moebius balancing, equal-area steps)
// on boundary surfaces, with the equal-area steps' systems solved on the host (sparse Cholesky,
// factors reused: CHOLMOD's supernodal where vpm was built with it) and, when VPM_DEVICE selects
// an OpenCL device, by Jacobi CG on it (InitialMapOptions::density_solve). Surfaces: the
// boundaries of jittered voxel ellipsoids of about the given tet counts, then the given files
// (a tet mesh gives its boundary). Prints a table (medians of the repeats) and writes JSON; exits
// 3 if the two solves give spheres more than 1e-6 apart.
#include <algorithm>
#include <cstdio>
#include <string>
#include <vector>

#include "support/shapes.hpp"
#include "vpm/device.hpp"
#include "vpm/error.hpp"
#include "vpm/initial_map.hpp"
#include "vpm/io.hpp"
#include "vpm/json.hpp"
#include "vpm/timing.hpp"
#include "vpm/topology.hpp"
#include "bench_util.hpp"

using namespace vpm;
using bench::median;

namespace {

struct Timed {
  SphereMapResult map;
  double seconds = 0;
};

Timed timed(const TriSurface& s, InitialMapOptions::DensitySolve where, Device* dev, int repeats) {
  InitialMapOptions o;
  o.density_solve = where;
  std::vector<double> t;
  Timed r;
  for (int k = 0; k < repeats; ++k) {
    const auto t0 = Clock::now();
    r.map = sphere_map(s, o, dev);
    t.push_back(seconds_since(t0));
  }
  r.seconds = median(t);
  return r;
}

TriSurface surface_of(const std::string& path) {
  return is_surface_path(path) ? read_surface(path) : boundary_surface(read_mesh(path));
}

}  // namespace

int main(int argc, char** argv) try {
  const bench::SizedRun run_opts = bench::parse_sized_run(argc, argv, {{100000, 400000}, 3, "sphere_map.json", {}},
                                                          "usage: vpm_bench_sphere_map [--sizes N,N,...] [--repeats R] [--json FILE] [MESH|SURFACE ...]");
  const std::vector<long>& sizes = run_opts.sizes;
  const std::vector<std::string>& files = run_opts.files;
  const int repeats = run_opts.repeats;
  const std::string& json_path = run_opts.json;
  Device& dev = Device::current();
  const bool on_device = !dev.is_host();
  std::printf("device: %s, %d repeats (medians)\n", dev.name().c_str(), repeats);
  std::printf("%-18s %9s %6s %-22s %8s %9s %9s %9s\n", "surface", "vertices", "steps", "host solver", "host s",
              "device s", "distort", "max diff");
  Json out = Json::object();
  out["device"] = dev.name();
  out["repeats"] = repeats;
  Json& rows = out["surfaces"] = Json::array();
  bool agree = true;
  auto run = [&](const std::string& name, const TriSurface& s) {
    const Timed host = timed(s, InitialMapOptions::DensitySolve::host, nullptr, repeats);
    Json j = Json::object();
    j["name"] = name;
    j["vertices"] = host.map.report.vertices;
    j["steps"] = host.map.report.density_steps.value_or(0);
    j["area_distortion"] = host.map.report.area_distortion_final;
    j["host_solver"] = host.map.report.density_solver;
    j["host_s_median"] = host.seconds;
    double device_s = 0, diff = 0;
    if (on_device) {
      const Timed d = timed(s, InitialMapOptions::DensitySolve::device, &dev, repeats);
      device_s = d.seconds;
      diff = (d.map.sphere - host.map.sphere).cwiseAbs().maxCoeff();
      j["device_solver"] = d.map.report.density_solver;
      j["device_s_median"] = device_s;
      j["max_difference"] = diff;
      agree = agree && diff <= 1e-6;
    }
    std::printf("%-18s %9d %6d %-22s %8.3f %9.3f %9.4f %9.2g\n", name.c_str(), host.map.report.vertices,
                host.map.report.density_steps.value_or(0), host.map.report.density_solver.c_str(), host.seconds,
                device_s, host.map.report.area_distortion_final, diff);
    rows.push_back(j);
  };
  for (long n : sizes) {
    const TetMesh m = test::voxel_ellipsoid_mesh(n);
    run("ellipsoid-" + std::to_string(n / 1000) + "k", boundary_surface(m));
  }
  for (const std::string& f : files) run(f.substr(f.find_last_of('/') + 1), surface_of(f));
  write_json_file(json_path, out);
  std::printf("wrote %s\n", json_path.c_str());
  if (!agree) {
    std::fprintf(stderr, "vpm_bench_sphere_map: the host and device solves give spheres more than 1e-6 apart\n");
    return 3;
  }
  return 0;
} catch (const InputError& e) {
  std::fprintf(stderr, "vpm_bench_sphere_map: %s\n", e.what());
  return 2;
} catch (const std::exception& e) {
  std::fprintf(stderr, "vpm_bench_sphere_map: %s\n", e.what());
  return 3;
}
