#pragma once
// The devices every numeric test body runs on: the host reference and the OpenCL device
// (VPM_TEST_DEVICE, else VPM_DEVICE, else the default rule). With VPM_TEST_REQUIRE_OPENCL=1
// (set by .ci/run) a missing OpenCL device fails the test instead of being skipped.
#include <memory>
#include <vector>

#include "vpm/device.hpp"

namespace vpm::test {

/// The host device, then the OpenCL device when one exists.
std::vector<std::shared_ptr<Device>> devices();
/// The OpenCL device, or nullptr (then the caller WARNs and skips device checks).
std::shared_ptr<Device> opencl_device();

}  // namespace vpm::test
