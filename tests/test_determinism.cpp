// Determinism (docs/robustness.md, "Determinism"): the same input gives bit-identical outputs
// on the same device; the host reference and the OpenCL device agree within a stated tolerance.
#include <catch2/catch.hpp>
#include <algorithm>
#include <cmath>
#include <filesystem>

#include "support/devices.hpp"
#include "support/fixtures.hpp"
#include "support/kill.hpp"
#include "support/process.hpp"
#include "support/shapes.hpp"
#include "support/scratch.hpp"
#include "vpm/ball_map.hpp"
#include "vpm/config.hpp"
#include "vpm/device.hpp"
#include "vpm/io.hpp"
#include "vpm/json.hpp"
#include "vpm/mesh_image.hpp"
#include "vpm/validate.hpp"

using namespace vpm;
namespace fs = std::filesystem;

namespace {

std::string fresh_dir(const std::string& name) { return test::fresh_dir("determinism_" + name); }

// "P:D" of an OpenCL device, for VPM_DEVICE.
std::string spec_of(const Device& d) {
  return std::to_string(d.description().platform_index) + ":" + std::to_string(d.description().device_index);
}

// The stated tolerances between the host and an OpenCL device (docs/robustness.md), for maps
// that take the same discrete path (the same rounds, halvings and untangled regions): the
// largest vertex distance between the two maps (ball units, radius 1) and the largest
// difference of the vertex and tet mean |r-1|. Measured on PoCL: at most 4.6e-3 and 1.1e-5.
constexpr double kHostDevicePosition = 1e-2;
constexpr double kHostDeviceMetric = 5e-5;

}  // namespace

TEST_CASE("determinism: two runs of vpm map on the same input write byte-identical meshes, on every device") {
  const std::string dir = fresh_dir("runs"), in = dir + "/in.vtu";
  write_mesh(in, test::voxel_ellipsoid_mesh(8000, 5));
  std::vector<std::pair<std::string, std::vector<std::string>>> runs = {{"host", {"VPM_DEVICE=host"}}};
  if (auto dev = test::opencl_device()) {
    runs.push_back({"device", {"VPM_DEVICE=" + spec_of(*dev)}});
    if (dev->description().platform.find("Portable Computing Language") != std::string::npos)  // one PoCL thread
      runs.push_back({"device_1thread", {"VPM_DEVICE=" + spec_of(*dev), "POCL_MAX_PTHREAD_COUNT=1"}});
  } else {
    WARN("no OpenCL device: the host only");
  }
  std::string first_device;
  for (const auto& [name, env] : runs) {
    INFO(name);
    for (int k = 0; k < 2; ++k) {
      const std::string out = dir + "/" + name + "_" + std::to_string(k);
      // --allow-partial: this irregular mesh stops at 9.8 % (exit 4 otherwise); written either way
      REQUIRE(test::wait_status(test::spawn({VPM_BINARY, "map", in, "-o", out + ".vtu", "--report", out + ".json",
                                             "--allow-partial"},
                                            out + ".err", env)) == 0);
    }
    const std::string a = test::slurp(dir + "/" + name + "_0.vtu"), b = test::slurp(dir + "/" + name + "_1.vtu");
    REQUIRE(!a.empty());
    CHECK(a == b);
    const Json ja = read_json_file(dir + "/" + name + "_0.json"), jb = read_json_file(dir + "/" + name + "_1.json");
    CHECK(ja.find("final")->dump() == jb.find("final")->dump());
    if (name == "device") first_device = a;
    if (name == "device_1thread") CHECK(a == first_device);  // PoCL's thread count does not change the map
  }
}

TEST_CASE("determinism: two runs of vpm mesh-image on the same image write byte-identical meshes") {
  const std::string colin = "/usr/share/mricron/templates/ch2bet.nii.gz";
  if (!(VPM_HAVE_NIFTI && VPM_HAVE_TETGEN && VPM_HAVE_CGAL && fs::exists(colin))) {
    WARN("no Colin27 (mricron-data) or no meshing: skipped");
    return;
  }
  const std::string dir = fresh_dir("mesh_image");
  for (int k = 0; k < 2; ++k)
    REQUIRE(test::wait_status(test::spawn({VPM_BINARY, "mesh-image", colin, "-o", dir + "/m" + std::to_string(k) + ".vtu",
                                           "--target-vertices", "2000"})) == 0);
  const std::string a = test::slurp(dir + "/m0.vtu");
  REQUIRE(a.size() > 100000);
  CHECK(a == test::slurp(dir + "/m1.vtu"));
}

TEST_CASE("determinism: the host and the OpenCL device give the same map within the stated tolerance") {
  auto dev = test::opencl_device();
  if (!dev) {
    WARN("no OpenCL device: skipped");
    return;
  }
  auto host = Device::host();
  std::vector<std::pair<std::string, TetMesh>> meshes = {
      {"voxel_ellipsoid", test::voxel_ellipsoid_mesh(8000, 5)},
      {"bent", test::bent_mesh(3)},
  };
  const std::string colin = "/usr/share/mricron/templates/ch2bet.nii.gz";
  if (VPM_HAVE_NIFTI && VPM_HAVE_TETGEN && VPM_HAVE_CGAL && fs::exists(colin)) {
    MeshImageOptions mo;
    mo.target_vertices = 2000;  // Colin27 at about 10k tets
    meshes.push_back({"colin27", mesh_image_file(colin, mo)});
  } else {
    WARN("no Colin27 (mricron-data) or no meshing: the synthetic meshes only");
  }
  for (auto [name, mesh] : meshes) {
    INFO(name);
    const ValidationReport vr = validate_mesh(mesh, name);
    const BallMap h = map_to_ball(*host, mesh, vr, name);
    const BallMap d = map_to_ball(*dev, mesh, vr, name);
    REQUIRE(h.mesh.tets == d.mesh.tets);  // the same topology: edge splits are decided on the host
    REQUIRE(h.volume_map->rounds.size() == d.volume_map->rounds.size());  // the same path
    const double dx = (h.mesh.vertices - d.mesh.vertices).rowwise().norm().maxCoeff();
    const double dv = std::abs(h.final.vertex_volume_ratio.mean_abs_dev - d.final.vertex_volume_ratio.mean_abs_dev);
    const double dt = std::abs(h.final.tet_volume_ratio.mean_abs_dev - d.final.tet_volume_ratio.mean_abs_dev);
    WARN(name << ": " << mesh.num_tets() << " tets, host vs " << dev->name() << ": max vertex distance " << dx
              << ", vertex mean |r-1| " << h.final.vertex_volume_ratio.mean_abs_dev << " vs "
              << d.final.vertex_volume_ratio.mean_abs_dev << ", tet mean |r-1| difference " << dt << ", rounds "
              << h.volume_map->rounds.size());
    CHECK(dx <= kHostDevicePosition);
    CHECK(dv <= kHostDeviceMetric);
    CHECK(dt <= kHostDeviceMetric);
    CHECK(h.final.inverted_tets == 0);
    CHECK(d.final.inverted_tets == 0);
  }
}

TEST_CASE("determinism: where a round's decision flips, host and device give two different fold-free maps") {
  // the dumbbell's neck: host 11 rounds at 0.80 %, PoCL 6 rounds at 2.23 % (2026-11-27); the
  // tolerance above holds only for maps on the same path, and this test keeps the counter-example
  auto dev = test::opencl_device();
  if (!dev) {
    WARN("no OpenCL device: skipped");
    return;
  }
  auto host = Device::host();
  TetMesh mesh = test::dumbbell_mesh(4);
  const ValidationReport vr = validate_mesh(mesh, "dumbbell");
  const BallMap h = map_to_ball(*host, mesh, vr, "dumbbell");
  const BallMap d = map_to_ball(*dev, mesh, vr, "dumbbell");
  WARN("dumbbell: rounds " << h.volume_map->rounds.size() << " vs " << d.volume_map->rounds.size()
                           << ", vertex mean |r-1| " << h.final.vertex_volume_ratio.mean_abs_dev << " vs "
                           << d.final.vertex_volume_ratio.mean_abs_dev);
  CHECK(h.final.inverted_tets == 0);
  CHECK(d.final.inverted_tets == 0);
}
