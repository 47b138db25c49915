// Where each part of a run executes (vpm/placement.hpp): the rules decided in one place, the
// caller's requests honoured, and the decision reported by the stages and in the JSON.
#include <catch2/catch.hpp>

#include "support/devices.hpp"
#include "support/fixtures.hpp"
#include "support/shapes.hpp"
#include "vpm/ball_map.hpp"
#include "vpm/error.hpp"
#include "vpm/placement.hpp"
#include "vpm/validate.hpp"

using namespace vpm;

namespace {
const PlacedWork kAll[] = {PlacedWork::density_solve, PlacedWork::advection, PlacedWork::gradients,
                           PlacedWork::polish, PlacedWork::sampling};
}

TEST_CASE("placement: the host device runs everything on the host whatever is asked") {
  const std::shared_ptr<Device> host = Device::host();
  for (PlacedWork w : kAll)
    for (ExecutionPlace p : {ExecutionPlace::automatic, ExecutionPlace::host, ExecutionPlace::device}) {
      const Placed placed = place_work(*host, w, p, 10 * kDeviceDensityVertices);
      CHECK_FALSE(placed.on_device);
      CHECK(placed.reason == "host device");
    }
}

TEST_CASE("placement: requests are honoured on an OpenCL device, automatic follows the device kind") {
  const std::shared_ptr<Device> dev = test::opencl_device();
  if (!dev) {
    WARN("no OpenCL device: skipped");
    return;
  }
  const bool gpu = dev->description().kind == DeviceKind::gpu;
  for (PlacedWork w : kAll) {
    CHECK_FALSE(place_work(*dev, w, ExecutionPlace::host).on_device);
    CHECK(place_work(*dev, w, ExecutionPlace::device).on_device);
  }
  CHECK(place_work(*dev, PlacedWork::advection, ExecutionPlace::automatic).on_device);
  CHECK(place_work(*dev, PlacedWork::sampling, ExecutionPlace::automatic).on_device == gpu);
  CHECK(place_work(*dev, PlacedWork::gradients, ExecutionPlace::automatic).on_device == gpu);
  CHECK(place_work(*dev, PlacedWork::polish, ExecutionPlace::automatic).on_device == gpu);
  CHECK_FALSE(place_work(*dev, PlacedWork::density_solve, ExecutionPlace::automatic, 100).on_device);
  CHECK(place_work(*dev, PlacedWork::density_solve, ExecutionPlace::automatic, kDeviceDensityVertices).on_device ==
        gpu);
  for (PlacedWork w : kAll) CHECK_FALSE(place_work(*dev, w, ExecutionPlace::automatic, 100).reason.empty());
}

TEST_CASE("placement: parse, merge and JSON") {
  CHECK(parse_execution_place("auto", "x") == ExecutionPlace::automatic);
  CHECK(parse_execution_place("host", "x") == ExecutionPlace::host);
  CHECK(parse_execution_place("device", "x") == ExecutionPlace::device);
  CHECK_THROWS_WITH(parse_execution_place("gpu", "--polish-on"), "--polish-on 'gpu' is not one of auto, host, device");
  const std::shared_ptr<Device> host = Device::host();
  Placement a, b;
  CHECK_FALSE(a.decide(*host, PlacedWork::density_solve, ExecutionPlace::device));
  b.polish = Placed{true, "asked for the device"};
  a.merge(b);
  REQUIRE(a.density_solve);
  REQUIRE(a.polish);
  CHECK_FALSE(a.advection);
  Json j = to_json(a);
  CHECK(j["device"].string() == "host");
  CHECK(j["kind"].string() == "host");
  CHECK(j["density_solve"]["where"].string() == "host");
  CHECK(j["polish"]["where"].string() == "device");
  CHECK(j["polish"]["why"].string() == "asked for the device");
  CHECK(j.find("advection") == nullptr);
}

TEST_CASE("placement: a ball map reports where its parts ran, as its options asked") {
  TetMesh mesh = test::box_mesh(5, 4, 4);
  const ValidationReport validation = validate_mesh(mesh, "box");
  for (const auto& dev : test::devices()) {
    INFO(dev->name());
    BallMapOptions o;
    o.volume.rounds = 2;
    o.volume.polish = ExecutionPlace::host;
    const BallMap m = map_to_ball(*dev, mesh, validation, "box", o);
    CHECK(m.placement.device == dev->name());
    REQUIRE(m.placement.polish);
    CHECK_FALSE(m.placement.polish->on_device);
    REQUIRE(m.placement.advection);
    CHECK(m.placement.advection->on_device == !dev->is_host());
    CHECK(m.volume_map->device_advection == m.placement.advection->on_device);
    Json j = to_json(m);
    CHECK(j["placement"]["polish"]["where"].string() == "host");
    CHECK(j["placement"]["advection"]["where"].string() == (dev->is_host() ? "host" : "device"));
  }
}
