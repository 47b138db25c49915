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

/// Forces the device's reduction mode (Device::set_group_reduce) for a scope, so the GPU path
/// (per-group partial sums) runs on PoCL in CI too; restores the device's own rule at exit.
class GroupReduceScope {
 public:
  GroupReduceScope(Device& d, bool on) : d_(d) { d_.set_group_reduce(on); }
  ~GroupReduceScope() { d_.set_group_reduce(std::nullopt); }
  GroupReduceScope(const GroupReduceScope&) = delete;
  GroupReduceScope& operator=(const GroupReduceScope&) = delete;

 private:
  Device& d_;
};

}  // namespace vpm::test
