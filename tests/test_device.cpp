#include <catch2/catch.hpp>

#include "support/devices.hpp"
#include <boost/compute/exception/opencl_error.hpp>

#include "core/device_cl.hpp"
#include "vpm/device.hpp"
#include "vpm/error.hpp"

using namespace vpm;

TEST_CASE("host device is always available") {
  auto h = Device::select("host");
  CHECK(h->is_host());
  CHECK(h->name() == "host");
  CHECK(Device::select("HOST")->is_host());
}

TEST_CASE("an unknown device spec is an InputError that lists the devices") {
  try {
    Device::select("no-such-device-xyz");
    FAIL("expected InputError");
  } catch (const InputError& e) {
    const std::string msg = e.what();
    CHECK(msg.find("no-such-device-xyz") != std::string::npos);
    CHECK(msg.find("available: host") != std::string::npos);
  }
  CHECK_THROWS_AS(Device::select("9:9"), InputError);
}

TEST_CASE("OpenCL device selection by type, index and name") {
  auto dev = test::opencl_device();
  if (!dev) {
    WARN("no OpenCL device; skipped");
    return;
  }
  const auto& d = dev->description();
  CHECK(d.fp64);
  auto by_index = Device::select(std::to_string(d.platform_index) + ":" + std::to_string(d.device_index));
  CHECK(by_index->name() == dev->name());
  auto by_name = Device::select(d.name.substr(0, 6));
  CHECK_FALSE(by_name->is_host());
  auto by_type = Device::select(to_string(d.kind));
  CHECK(by_type->description().kind == d.kind);
  CHECK(dev->padded(1) == dev->local_size());
  CHECK(dev->padded(dev->local_size() + 1) == 2 * dev->local_size());
  // kernels are built once and cached: a second request reuses the program
  auto k1 = dev->cl().kernel("geometry", "tet_volumes");
  auto k2 = dev->cl().kernel("geometry", "tet_volumes");
  CHECK(k1.get_program() == k2.get_program());
  CHECK_THROWS(dev->cl().kernel("no_such_program", "x"));
}

TEST_CASE("an OpenCL error that escapes a stage is described through vpm/error.hpp, other errors are not") {
  // the vpm program reports such an error (exit 5) without including OpenCL headers
  const boost::compute::opencl_error cl(CL_OUT_OF_RESOURCES);
  const std::string d = vpm::opencl_error_description(cl);
  CHECK(d.find("OpenCL error -5 (") == 0);
  CHECK(d.size() > std::string("OpenCL error -5 ()").size());  // the error's name in the parentheses
  CHECK(d.back() == ')');
  CHECK(vpm::opencl_error_description(std::runtime_error("x")).empty());
  CHECK(vpm::opencl_error_description(vpm::DeviceError("y")).empty());
}
