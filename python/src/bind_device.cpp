// vpm.devices(), vpm.select_device(), and the device each call runs on (VPM_DEVICE by default).
#include <map>
#include <mutex>

#include "common.hpp"
#include "vpm/error.hpp"

namespace vpm::python {
namespace {

std::mutex g_mutex;
std::optional<std::string> g_default;                      // select_device(); nullopt: VPM_DEVICE
std::map<std::string, std::shared_ptr<Device>> g_devices;  // one Device per spec, kept for the process

std::shared_ptr<Device> by_spec(const std::string& spec) {
  std::lock_guard<std::mutex> lock(g_mutex);
  auto& d = g_devices[spec];
  if (!d) d = spec == "host" ? Device::host() : Device::select(spec);
  return d;
}

py::dict describe(const DeviceDescription& d, bool selected) {
  py::dict r;
  r["index"] = std::to_string(d.platform_index) + ":" + std::to_string(d.device_index);
  r["platform"] = d.platform;
  r["name"] = d.name;
  r["type"] = to_string(d.kind);
  r["fp64"] = d.fp64;
  r["compute_units"] = d.compute_units;
  r["global_memory_bytes"] = d.global_memory_bytes;
  r["selected"] = selected;
  return r;
}

}  // namespace

std::shared_ptr<Device> device_for(const std::optional<std::string>& spec) {
  std::optional<std::string> s = spec;
  if (!s) {
    std::lock_guard<std::mutex> lock(g_mutex);
    s = g_default;
  }
  if (s) return by_spec(*s);
  // VPM_DEVICE's device lives for the process (Device::current()); not owned here
  return std::shared_ptr<Device>(&Device::current(), [](Device*) {});
}

void bind_device(py::module_& m) {
  m.def(
      "devices",
      [] {
        std::string why;
        const auto list = list_opencl_devices(&why);
        const std::string selected = device_for(std::nullopt)->name();
        py::list out;
        py::dict host;
        host["index"] = "host";
        host["platform"] = "";
        host["name"] = "host (Eigen/C++ reference, no OpenCL)";
        host["type"] = "host";
        host["fp64"] = true;
        host["selected"] = selected == "host";
        out.append(host);
        for (const auto& d : list) out.append(describe(d, selected == d.label()));
        return out;
      },
      "The compute devices: the host and every OpenCL device, each a dict with 'index' ('host' or\n"
      "'P:D', as `vpm devices` numbers them), 'platform', 'name', 'type', 'fp64' and 'selected'\n"
      "(the device calls use when given no device=: select_device()'s, else VPM_DEVICE's).");
  m.def(
      "select_device",
      [](std::optional<std::string> spec) {
        if (spec) by_spec(*spec);  // fails here (ValueError listing the devices) when it matches nothing
        {
          std::lock_guard<std::mutex> lock(g_mutex);
          g_default = spec;
        }
        return device_for(std::nullopt)->name();
      },
      py::arg("spec"),
      "Chooses the device of every later call given no device=: 'host', 'cpu', 'gpu', 'P:D' or a\n"
      "part of a platform or device name (VPM_DEVICE's grammar); None: back to VPM_DEVICE's choice.\n"
      "Returns the device's name. ValueError (listing the devices) when nothing matches.");
  m.def(
      "device_name", [](std::optional<std::string> spec) { return device_for(spec)->name(); },
      py::arg("spec") = py::none(), "The name of the device `spec` selects (None: the default device).");
}

}  // namespace vpm::python
