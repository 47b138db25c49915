#include "support/devices.hpp"

#include <catch2/catch.hpp>
#include <cstdlib>
#include <string>

namespace vpm::test {

std::shared_ptr<Device> opencl_device() {
  static std::shared_ptr<Device> dev;
  static bool tried = false;
  if (!tried) {
    tried = true;
    const char* spec = std::getenv("VPM_TEST_DEVICE");
    if (!spec) spec = std::getenv("VPM_DEVICE");
    std::string s = spec ? spec : "";
    if (s == "host") s = "";
    try {
      auto d = Device::select(s);
      if (!d->is_host()) dev = d;
    } catch (const std::exception& e) {
      WARN("no OpenCL device: " << e.what());
    }
    const char* req = std::getenv("VPM_TEST_REQUIRE_OPENCL");
    if (!dev && req && std::string(req) == "1")
      FAIL("VPM_TEST_REQUIRE_OPENCL=1 but no OpenCL fp64 device was found");
  }
  return dev;
}

std::vector<std::shared_ptr<Device>> devices() {
  std::vector<std::shared_ptr<Device>> out{Device::host()};
  if (auto d = opencl_device()) out.push_back(d);
  return out;
}

}  // namespace vpm::test
