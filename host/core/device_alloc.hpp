#pragma once
// Private: allocating a stage's device buffers so that a device too small for them ends in a
// DeviceError naming the stage, the sizes and the device's limits (exit status 5), never in an
// unexplained OpenCL error or a crash.
#include <string>
#include <utility>

#include <boost/compute/exception/opencl_error.hpp>

#include "vpm/device.hpp"
#include "vpm/error.hpp"

namespace vpm::detail {

/// Checks the largest buffer (`largest` bytes) against CL_DEVICE_MAX_MEM_ALLOC_SIZE and `total`
/// against the device's global memory, then runs `allocate`, turning an OpenCL error it throws
/// (CL_INVALID_BUFFER_SIZE, CL_MEM_OBJECT_ALLOCATION_FAILURE, CL_OUT_OF_RESOURCES, ...) into a
/// DeviceError. Nothing is checked on the host device.
template <class F>
void allocate_on_device(Device& dev, const std::string& what, unsigned long long largest, unsigned long long total,
                        F&& allocate) {
  if (!dev.is_host()) {
    dev.check_buffer(largest, what);
    const unsigned long long global = dev.description().global_memory_bytes;
    if (global && total > global)
      throw DeviceError(what + ": needs " + std::to_string(total) + " bytes of device memory, " + dev.name() +
                        " has " + std::to_string(global) + "; use a smaller input or VPM_DEVICE=host");
  }
  try {
    std::forward<F>(allocate)();
  } catch (const boost::compute::opencl_error& e) {
    throw DeviceError(what + ": cannot allocate " + std::to_string(total) + " bytes of buffers on " + dev.name() +
                      ": OpenCL error " + std::to_string(e.error_code()) + " (" + e.error_string() +
                      "); use a smaller input or VPM_DEVICE=host");
  }
}

}  // namespace vpm::detail
