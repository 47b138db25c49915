#pragma once
// Compute devices: the host (Eigen reference) or an OpenCL device, chosen by VPM_DEVICE.
//
//   VPM_DEVICE=host     no OpenCL; every stage runs its Eigen reference
//   VPM_DEVICE=cpu|gpu  the first OpenCL device of that type
//   VPM_DEVICE=P:D      platform index P, device index D (as `vpm devices` numbers them)
//   VPM_DEVICE=text     first device whose "platform: device" name contains text (any case)
//   unset               the first GPU if there is one, else the first CPU device, else host
//
// No match is an InputError listing the devices; there is never a silent fallback.
// OpenCL devices must support double precision.
//
// This header names no OpenCL type: the context, queue, programs and launches live behind
// Device::cl() in the library's private host/core/device_cl.hpp (pimpl), so a program that
// links vpm needs neither Boost.Compute nor the OpenCL headers to select and describe devices.
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace vpm {

namespace detail {
struct DeviceCl;  // host/core/device_cl.hpp: the OpenCL side of a Device
}

/// What kind of processor a Device is: the host (vpm's C++ code, no OpenCL) or an OpenCL
/// device of CL_DEVICE_TYPE GPU, CPU (PoCL), accelerator or other. Where work runs is decided
/// from this kind (and the problem size), never from names.
enum class DeviceKind { host, cpu, gpu, accelerator, other };

/// "host", "cpu", "gpu", "accelerator" or "other" (VPM_DEVICE's words, `vpm devices`, reports).
const char* to_string(DeviceKind kind);

/// One OpenCL device as the ICD loader reports it.
struct DeviceDescription {
  int platform_index = -1;
  int device_index = -1;
  std::string platform;   ///< platform name, e.g. "Portable Computing Language"
  std::string name;       ///< device name
  DeviceKind kind = DeviceKind::other;
  bool fp64 = false;      ///< cl_khr_fp64 or CL_DEVICE_DOUBLE_FP_CONFIG non-zero
  unsigned compute_units = 0;
  unsigned long long global_memory_bytes = 0;
  unsigned long long max_alloc_bytes = 0;  ///< CL_DEVICE_MAX_MEM_ALLOC_SIZE: the largest one buffer
  std::string label() const;  ///< "P:D platform: name"
};

/// All OpenCL devices visible now; empty (never an exception) when no platform is installed.
/// `error`, if given, receives why the list is empty (e.g. "no OpenCL platform (ICD) found").
std::vector<DeviceDescription> list_opencl_devices(std::string* error = nullptr);

/// A selected compute device. Non-copyable; obtain with Device::current() or Device::select().
class Device {
 public:
  /// The device VPM_DEVICE selects, created on first use and shared by the whole process.
  /// Throws InputError when the value matches nothing or the device lacks fp64.
  static Device& current();
  /// Selects by the VPM_DEVICE grammar above ("" = the default rule).
  static std::shared_ptr<Device> select(const std::string& spec);
  /// The host device (always available). A new device each call: keep the pointer while the
  /// device is used (`Device& d = *Device::host();` would dangle at the end of the statement;
  /// passing `*Device::host()` straight to a call is fine).
  static std::shared_ptr<Device> host();

  Device(const Device&) = delete;
  Device& operator=(const Device&) = delete;
  ~Device();

  bool is_host() const { return host_; }
  /// "host" or "P:D platform: device".
  std::string name() const;
  const DeviceDescription& description() const { return desc_; }

  /// The OpenCL side: context, queue, kernels (built and cached per program and options) and
  /// launches (host/core/device_cl.hpp, private to the library, its tests and benchmarks).
  /// Precondition: !is_host() (throws std::logic_error on the host device).
  detail::DeviceCl& cl();

  /// Throws DeviceError naming `what` when one buffer of `bytes` exceeds what this device allows
  /// (CL_DEVICE_MAX_MEM_ALLOC_SIZE) or its global memory. Does nothing on the host.
  void check_buffer(unsigned long long bytes, const std::string& what) const;

  /// Work-group size used for every 1-D launch (fixed so PoCL compiles each kernel once).
  size_t local_size() const { return local_size_; }
  /// `n` rounded up to a multiple of local_size() (at least one group).
  size_t padded(size_t n) const;

  /// Two-stage reductions (kernels/common.clh): true when each work group sums its work
  /// items' partials in local memory before writing (GPUs), false when every work item writes
  /// its own (CPU devices, where barriers are slow). Every program is built with -DLS=<local
  /// size>, and with -DGROUP_REDUCE when this is true.
  bool group_reduce() const;
  /// Overrides group_reduce() for the kernels built from now on (nullopt: the device's own
  /// rule). Tests use it to run the GPU reduction path on a CPU device.
  void set_group_reduce(std::optional<bool> on) { group_reduce_override_ = on; }
  /// Number of partial-sum pairs a reduction kernel launched over `global` work items writes.
  size_t reduction_partials(size_t global) const;
  /// Work items to launch a combining kernel (COMBINE_PARTIALS) with: one group or one item.
  size_t combine_items() const;

 private:
  Device();
  bool host_ = true;
  DeviceDescription desc_;
  size_t local_size_ = 64;
  std::optional<bool> group_reduce_override_;
  std::unique_ptr<detail::DeviceCl> cl_;  ///< null on the host device
};

}  // namespace vpm
