#pragma once
// Where each part of a run executes: the host's code or the OpenCL kernels of the device. The
// rules live here, once, as one function of the device's kind, the problem's size and what the
// caller asked for; the stages ask it with their own sizes and report the answer (where and why)
// in their results and in the JSON reports ("placement"). No stage compares device names or
// kinds to decide where it runs.
#include <optional>
#include <string>

#include "vpm/device.hpp"
#include "vpm/json.hpp"

namespace vpm {

/// Where a part of a stage runs when the device is an OpenCL device.
enum class ExecutionPlace {
  automatic,  ///< the rule of place_work below
  host,       ///< the host reference, even with an OpenCL device
  device,     ///< the OpenCL kernels (the host reference when the device is `host`)
};
/// "auto", "host" or "device"; InputError naming `what` otherwise.
ExecutionPlace parse_execution_place(const std::string& name, const std::string& what);
const char* to_string(ExecutionPlace p);  ///< "auto", "host", "device"

/// The parts of a run whose place is chosen per run.
enum class PlacedWork {
  density_solve,  ///< the initial map's equal-area steps (one Laplacian solve each)
  advection,      ///< the Moser rounds' RK4 advection (point location, field interpolation)
  gradients,      ///< the Moser field's vertex gradients (next to a device advection only)
  polish,         ///< the polish's CGLS (volume map, registration's restoration)
  sampling,       ///< a subject's images read at the element samples (vpm/element_sampler.hpp)
};
/// "density_solve", "advection", "gradients", "polish", "sampling"
const char* to_string(PlacedWork w);

/// Boundaries of at least this many vertices have their equal-area steps solved on a GPU under
/// ExecutionPlace::automatic (at 32k vertices the host and the CPU device tie;
/// bench/results/volume_map_10m_cpu_again/, bench/results/gpu_h200_19s/).
inline constexpr long long kDeviceDensityVertices = 50'000;

/// Where one part runs and the rule that put it there (one line, for reports).
struct Placed {
  bool on_device = false;
  std::string reason;
};

/// Where `work` runs on `device` when the caller asked for `requested` and the problem has
/// `size` elements of the kind the rule reads (density_solve: boundary vertices; the others do
/// not read it). The rules:
///   - the host device, or requested host: the host;
///   - requested device: the device;
///   - automatic: density_solve on GPUs for boundaries of at least kDeviceDensityVertices (on CPU
///     devices the kernels share the cores with the Poisson solver built beside them and lose);
///     advection on every OpenCL device; gradients, polish and sampling on GPUs only (on PoCL the
///     host threads are as fast or faster, and keep the host's round-off: docs/volume_map.md,
///     docs/collective.md).
/// Gradients are only placed on the device next to a device advection: ask for them with the
/// advection's request and place them only when the advection is on the device.
Placed place_work(const Device& device, PlacedWork work, ExecutionPlace requested, long long size = 0);

/// The placement of a run: the device and, for each part the run reached, where it ran and why.
struct Placement {
  std::string device;  ///< Device::name()
  DeviceKind kind = DeviceKind::host;
  std::optional<Placed> density_solve, advection, gradients, polish, sampling;

  /// The part's slot (density_solve, advection, ...).
  std::optional<Placed>& at(PlacedWork w);
  const std::optional<Placed>& at(PlacedWork w) const;
  /// Decides `work` by place_work and records it; returns whether it runs on the device.
  bool decide(const Device& d, PlacedWork work, ExecutionPlace requested, long long size = 0);
  /// Takes the parts `other` placed (a later stage of the same run).
  void merge(const Placement& other);
};

/// {"device", "kind", and per placed part {"where": "host"|"device", "why"}}.
Json to_json(const Placement& p);

}  // namespace vpm
