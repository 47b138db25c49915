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
#include <boost/compute/command_queue.hpp>
#include <boost/compute/context.hpp>
#include <boost/compute/kernel.hpp>
#include <boost/compute/program.hpp>
#include <map>
#include <mutex>
#include <optional>
#include <memory>
#include <string>
#include <vector>

namespace vpm {

/// Sets arguments first, first + 1, ... of kernel `k` to `args`: a run in the middle or at the
/// end of a kernel's argument list (Boost.Compute's k.set_args(...) sets a run from 0).
template <class... T>
void set_args_at(boost::compute::kernel& k, size_t first, const T&... args) {
  size_t i = first;
  (k.set_arg(i++, args), ...);
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

  bool is_host() const { return host_; }
  /// "host" or "P:D platform: device".
  std::string name() const;
  const DeviceDescription& description() const { return desc_; }

  /// OpenCL objects (precondition: !is_host()).
  boost::compute::context& context() { return context_; }
  boost::compute::command_queue& queue() { return queue_; }
  boost::compute::device& cl_device() { return device_; }

  /// Kernel `kernel_name` of kernels/<program>.cl. Programs are built once per
  /// (program, options) and cached for the life of the device. The build prepends the fp64
  /// pragma and `#define real double`; `options` adds -D definitions. A build failure throws
  /// DeviceError (see build_program).
  boost::compute::kernel kernel(const std::string& program, const std::string& kernel_name,
                                const std::string& options = "");
  /// Builds `source` as program `name` (e.g. "kernels/solver.cl") the way kernel() builds the
  /// embedded ones: fp64 preamble and kernels/common.clh first, -cl-std=CL1.2 -DLS=<local size>
  /// [-DGROUP_REDUCE] and `options`. Not cached. A build failure throws DeviceError, one line:
  /// the program, the device, the options and the first lines of the compiler's log.
  boost::compute::program build_program(const std::string& name, const std::string& source,
                                        const std::string& options = "");

  /// Throws DeviceError naming `what` when one buffer of `bytes` exceeds what this device allows
  /// (CL_DEVICE_MAX_MEM_ALLOC_SIZE) or its global memory. Does nothing on the host.
  void check_buffer(unsigned long long bytes, const std::string& what) const;

  /// Work-group size used for every 1-D launch (fixed so PoCL compiles each kernel once).
  size_t local_size() const { return local_size_; }
  /// `n` rounded up to a multiple of local_size() (at least one group).
  size_t padded(size_t n) const;
  /// Enqueues `k` over `n` work items (global size padded; kernels must guard `i < n`).
  void launch(boost::compute::kernel& k, size_t n);

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
  Device() = default;
  bool host_ = true;
  DeviceDescription desc_;
  boost::compute::device device_;
  boost::compute::context context_;
  boost::compute::command_queue queue_;
  size_t local_size_ = 64;
  std::optional<bool> group_reduce_override_;
  std::map<std::string, boost::compute::program> programs_;
  std::mutex programs_mutex_;  ///< kernel() may be called from several threads
};

}  // namespace vpm
