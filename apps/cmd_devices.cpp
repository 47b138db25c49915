// vpm devices: list OpenCL platforms/devices and mark the one VPM_DEVICE selects.
#include <cstdlib>
#include <iostream>

#include "cli.hpp"
#include "vpm/device.hpp"
#include "vpm/error.hpp"

namespace {
int run(const vpm::cli::Command& self, const std::vector<std::string>& argv) {
  vpm::cli::Args args(argv, self);
  args.expect_positional(0, vpm::cli::synopsis(self));
  std::string why;
  const auto devs = vpm::list_opencl_devices(&why);
  const char* env = std::getenv("VPM_DEVICE");
  std::string selected, error;
  try {
    selected = vpm::Device::current().name();
  } catch (const vpm::InputError& e) {
    error = e.what();
  }
  std::cout << (selected == "host" ? "* " : "  ") << "host (Eigen reference, no OpenCL)\n";
  for (const auto& d : devs) {
    std::cout << (selected == d.label() ? "* " : "  ") << d.label() << "  [" << to_string(d.kind)
              << ", " << d.compute_units << " compute units, "
              << d.global_memory_bytes / (1024 * 1024) << " MiB, fp64 " << (d.fp64 ? "yes" : "no")
              << "]\n";
  }
  if (devs.empty()) std::cout << "  (no OpenCL device: " << why << ")\n";
  std::cout << "VPM_DEVICE=" << (env ? env : "(unset)") << " -> "
            << (error.empty() ? selected : "no match") << '\n';
  if (!error.empty()) throw vpm::InputError(error);
  return 0;
}
vpm::cli::Registrar reg({"devices", "", "list the compute devices and mark the one VPM_DEVICE selects", {}, run});
}  // namespace
