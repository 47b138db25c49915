// The C++ side of bench/python/overhead.py: the library call that vpm.map_to_ball makes
// (validate_mesh + map_to_ball on a copy of the mesh, default options, Device::current()), timed
// in one process after one warm-up call, as the Python side is.
// Usage: vpm_bench_map_call MESH RUNS   -> one JSON line {"seconds": [...], "vertex_mean_abs_dev": x}
#include <cstdio>
#include <string>
#include <vector>

#include "vpm/ball_map.hpp"
#include "vpm/device.hpp"
#include "vpm/io.hpp"
#include "vpm/timing.hpp"
#include "vpm/validate.hpp"

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: vpm_bench_map_call MESH RUNS\n");
    return 2;
  }
  const vpm::TetMesh input = vpm::read_mesh(argv[1]);
  const int runs = std::stoi(argv[2]);
  vpm::Device& dev = vpm::Device::current();
  std::vector<double> seconds;
  double distortion = 0;
  for (int r = 0; r <= runs; ++r) {  // run 0 warms the device's program cache, as Python's first call
    vpm::TetMesh mesh = input;        // the Python side copies the arrays into a mesh too
    const vpm::Stopwatch clock;
    const vpm::ValidationReport vr = vpm::validate_mesh(mesh, "mesh");
    const vpm::BallMap bm = vpm::map_to_ball(dev, mesh, vr, "mesh");
    if (r > 0) seconds.push_back(clock.seconds());
    distortion = bm.final.vertex_volume_ratio.mean_abs_dev;
  }
  std::printf("{\"device\": \"%s\", \"seconds\": [", dev.name().c_str());
  for (size_t i = 0; i < seconds.size(); ++i) std::printf("%s%.6f", i ? ", " : "", seconds[i]);
  std::printf("], \"vertex_mean_abs_dev\": %.9g}\n", distortion);
  return 0;
}
