// Where the sphere map's equal-area steps solve (InitialMapOptions::density_solve): the device's
// AMG-CG against the host's Cholesky, the automatic rule, and an initial map whose sphere map
// solves on the device while its Poisson solver is built there on another thread.
#include <catch2/catch.hpp>
#include <cmath>

#include "support/devices.hpp"
#include "support/fixtures.hpp"
#include "support/shapes.hpp"
#include "vpm/device.hpp"
#include "vpm/error.hpp"
#include "vpm/initial_map.hpp"
#include "vpm/topology.hpp"

using namespace vpm;

TEST_CASE("equal-area sphere map: the steps' systems solved by device AMG-CG give the host's sphere") {
  const std::shared_ptr<Device> dev = test::opencl_device();
  if (!dev) {
    WARN("no OpenCL device: skipped");
    return;
  }
  TetMesh rod = test::box_mesh(24, 4, 4);  // elongated: many equal-area steps
  rod.vertices.col(0) *= 6.0;
  const TriSurface s{rod.vertices, boundary_faces(rod.tets)};
  const SphereMapResult host = sphere_map(s);
  InitialMapOptions on_device;
  on_device.density_solve = InitialMapOptions::DensitySolve::device;
  const SphereMapResult d = sphere_map(s, on_device, dev.get());
  CHECK(d.report.density_solver == "device-amg-cg");
  CHECK(host.report.density_solver != "device-amg-cg");
  REQUIRE(d.flipped_triangles == 0);
  CHECK(*d.report.density_steps == *host.report.density_steps);
  CHECK(std::abs(d.report.area_distortion_final - host.report.area_distortion_final) <
        1e-6 * host.report.area_distortion_final);
  CHECK((d.sphere - host.sphere).cwiseAbs().maxCoeff() < 1e-6);
  // without a device the option falls back to the host
  const SphereMapResult none = sphere_map(s, on_device, nullptr);
  CHECK(none.report.density_solver == host.report.density_solver);
  CHECK(none.sphere == host.sphere);
  // automatic (the default): this small boundary stays on the host, also given the device
  const SphereMapResult automatic = sphere_map(s, InitialMapOptions{}, dev.get());
  CHECK(automatic.report.density_solver == host.report.density_solver);
  CHECK(automatic.sphere == host.sphere);
}

TEST_CASE("where the equal-area steps solve: automatic takes a GPU for large boundaries only") {
  using S = InitialMapOptions::DensitySolve;
  InitialMapOptions o;
  CHECK(o.density_solve == S::automatic);
  CHECK(parse_density_solve("auto") == S::automatic);
  CHECK(parse_density_solve("device") == S::device);
  CHECK_THROWS_AS(parse_density_solve("gpu"), InputError);
  const auto on_device = [&](const Device& d, long long boundary) {
    return place_work(d, PlacedWork::density_solve, o.density_solve, boundary).on_device;
  };
  const std::shared_ptr<Device> host = Device::host();
  CHECK_FALSE(on_device(*host, 10 * kDeviceDensityVertices));
  const std::shared_ptr<Device> dev = test::opencl_device();
  if (!dev) return;
  const bool gpu = dev->description().kind == DeviceKind::gpu;
  CHECK_FALSE(on_device(*dev, kDeviceDensityVertices - 1));
  CHECK(on_device(*dev, kDeviceDensityVertices) == gpu);
  o.density_solve = S::host;
  CHECK_FALSE(on_device(*dev, 10 * kDeviceDensityVertices));
  o.density_solve = S::device;
  CHECK(on_device(*dev, 100));
  // the sphere map records what it decided: a small boundary stays on the host, and says why
  const TetMesh box = test::box_mesh(6, 4, 4);
  const TriSurface s{box.vertices, boundary_faces(box.tets)};
  const SphereMapResult automatic = sphere_map(s, InitialMapOptions{}, dev.get());
  REQUIRE(automatic.report.placement.density_solve);
  CHECK_FALSE(automatic.report.placement.density_solve->on_device);
  CHECK_FALSE(automatic.report.placement.density_solve->reason.empty());
}

TEST_CASE("initial map with the sphere map solving on the device beside the Poisson build") {
  // the equal-area steps on the device on one thread while the harmonic step's Poisson solver
  // is built on the same device on another (as on a GPU for large boundaries): the same map as
  // with the host's solves, to the solvers' tolerances
  const std::shared_ptr<Device> dev = test::opencl_device();
  if (!dev) {
    WARN("no OpenCL device: skipped");
    return;
  }
  const TetMesh in = test::bent_mesh(4);
  InitialMapOptions host, device;
  host.density_solve = InitialMapOptions::DensitySolve::host;
  device.density_solve = InitialMapOptions::DensitySolve::device;
  for (int run = 0; run < 2; ++run) {  // twice: the second finds the device's programs built
    const InitialMapResult a = initial_map(*dev, in, host);
    const InitialMapResult b = initial_map(*dev, in, device);
    CHECK(b.report.boundary.density_solver == "device-amg-cg");
    CHECK(a.report.boundary.density_solver != "device-amg-cg");
    CHECK(b.report.folds_after_untangle == 0);
    REQUIRE(b.ball.rows() == a.ball.rows());
    CHECK((b.ball - a.ball).cwiseAbs().maxCoeff() < 1e-6);
  }
}
