#pragma once
// Private: the OpenCL side of a vpm::Device (its pimpl). Stages, tests and benchmarks that run
// kernels include this; the public vpm/device.hpp names no OpenCL type.
//
//   auto& cl = device.cl();                       // precondition: !device.is_host()
//   auto k = cl.kernel("moser", "advect_soa");    // kernels/moser.cl, built once, cached
//   set_args_at(k, 0, a, b, n);
//   cl.launch(k, n);                              // n work items, global size padded
#include <boost/compute/command_queue.hpp>
#include <boost/compute/context.hpp>
#include <boost/compute/device.hpp>
#include <boost/compute/kernel.hpp>
#include <boost/compute/program.hpp>
#include <map>
#include <mutex>
#include <string>

#include "vpm/device.hpp"

namespace vpm {

/// Sets arguments first, first + 1, ... of kernel `k` to `args`: a run in the middle or at the
/// end of a kernel's argument list (Boost.Compute's k.set_args(...) sets a run from 0).
template <class... T>
void set_args_at(boost::compute::kernel& k, size_t first, const T&... args) {
  size_t i = first;
  (k.set_arg(i++, args), ...);
}

namespace detail {

struct DeviceCl {
  DeviceCl(const Device& owner, const boost::compute::device& d);

  const Device& owner;  ///< local size, reduction mode and name come from the Device
  boost::compute::device device;
  boost::compute::context context;
  boost::compute::command_queue queue;

  /// Kernel `kernel_name` of kernels/<program>.cl. Programs are built once per
  /// (program, options, reduction mode) and cached for the life of the device. The build
  /// prepends the fp64 pragma and `#define real double`; `options` adds -D definitions. A build
  /// failure throws DeviceError (see build_program).
  boost::compute::kernel kernel(const std::string& program, const std::string& kernel_name,
                                const std::string& options = "");
  /// Builds `source` as program `name` (e.g. "kernels/solver.cl") the way kernel() builds the
  /// embedded ones: fp64 preamble and kernels/common.clh first, -cl-std=CL1.2 -DLS=<local size>
  /// [-DGROUP_REDUCE] and `options`. Not cached. A build failure throws DeviceError, one line:
  /// the program, the device, the options and the first lines of the compiler's log.
  boost::compute::program build_program(const std::string& name, const std::string& source,
                                        const std::string& options = "");
  /// Enqueues `k` over `n` work items (global size owner.padded(n); kernels guard `i < n`).
  void launch(boost::compute::kernel& k, size_t n);

 private:
  std::map<std::string, boost::compute::program> programs_;
  std::mutex programs_mutex_;  ///< kernel() may be called from several threads
};

}  // namespace detail
}  // namespace vpm
