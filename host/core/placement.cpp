#include "vpm/placement.hpp"

#include "vpm/error.hpp"

namespace vpm {

ExecutionPlace parse_execution_place(const std::string& name, const std::string& what) {
  if (name == "auto") return ExecutionPlace::automatic;
  if (name == "host") return ExecutionPlace::host;
  if (name == "device") return ExecutionPlace::device;
  throw InputError(what + " '" + name + "' is not one of auto, host, device");
}

const char* to_string(ExecutionPlace p) {
  switch (p) {
    case ExecutionPlace::host: return "host";
    case ExecutionPlace::device: return "device";
    case ExecutionPlace::automatic: break;
  }
  return "auto";
}

const char* to_string(PlacedWork w) {
  switch (w) {
    case PlacedWork::density_solve: return "density_solve";
    case PlacedWork::advection: return "advection";
    case PlacedWork::gradients: return "gradients";
    case PlacedWork::polish: return "polish";
    case PlacedWork::sampling: break;
  }
  return "sampling";
}

namespace {

constexpr PlacedWork kAllWork[] = {PlacedWork::density_solve, PlacedWork::advection, PlacedWork::gradients,
                                   PlacedWork::polish, PlacedWork::sampling};

Placed automatic_place(const Device& device, PlacedWork work, long long size) {
  const bool gpu = device.description().kind == DeviceKind::gpu;
  const std::string kind = to_string(device.description().kind);
  switch (work) {
    case PlacedWork::density_solve:
      if (!gpu) return {false, kind + " device: its kernels would share the cores with the Poisson solver"};
      if (size < kDeviceDensityVertices)
        return {false, "gpu, boundary of " + std::to_string(size) + " < " + std::to_string(kDeviceDensityVertices) +
                           " vertices: the host's sparse Cholesky is faster"};
      return {true, "gpu, boundary of " + std::to_string(size) + " >= " + std::to_string(kDeviceDensityVertices) +
                        " vertices"};
    case PlacedWork::advection: return {true, "OpenCL device: the advection runs on every OpenCL device"};
    case PlacedWork::sampling:
      if (gpu) return {true, "gpu"};
      return {false, kind + " device: the host threads are faster and read the images where they are"};
    case PlacedWork::gradients:
    case PlacedWork::polish:
      if (gpu) return {true, "gpu"};
      return {false, kind + " device: the host threads are as fast and keep the host's round-off"};
  }
  return {false, "unknown work"};
}

}  // namespace

Placed place_work(const Device& device, PlacedWork work, ExecutionPlace requested, long long size) {
  if (device.is_host()) return {false, "host device"};
  if (requested == ExecutionPlace::host) return {false, "asked for the host"};
  if (requested == ExecutionPlace::device) return {true, "asked for the device"};
  return automatic_place(device, work, size);
}

std::optional<Placed>& Placement::at(PlacedWork w) {
  switch (w) {
    case PlacedWork::density_solve: return density_solve;
    case PlacedWork::advection: return advection;
    case PlacedWork::gradients: return gradients;
    case PlacedWork::polish: return polish;
    case PlacedWork::sampling: break;
  }
  return sampling;
}

const std::optional<Placed>& Placement::at(PlacedWork w) const { return const_cast<Placement*>(this)->at(w); }

bool Placement::decide(const Device& d, PlacedWork work, ExecutionPlace requested, long long size) {
  device = d.name();
  kind = d.description().kind;
  at(work) = place_work(d, work, requested, size);
  return at(work)->on_device;
}

void Placement::merge(const Placement& other) {
  if (device.empty()) {
    device = other.device;
    kind = other.kind;
  }
  for (PlacedWork w : kAllWork)
    if (other.at(w)) at(w) = other.at(w);
}

Json to_json(const Placement& p) {
  Json j = Json::object();
  j["device"] = p.device;
  j["kind"] = to_string(p.kind);
  for (PlacedWork w : kAllWork) {
    if (!p.at(w)) continue;
    Json e = Json::object();
    e["where"] = p.at(w)->on_device ? "device" : "host";
    e["why"] = p.at(w)->reason;
    j[to_string(w)] = e;
  }
  return j;
}

}  // namespace vpm
