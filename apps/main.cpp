// vpm: volume-preserving mapping and registration of 3-D shapes. See README.md.
#include <csignal>
#include <exception>
#include <iostream>
#include <malloc.h>
#include <new>

#include "cli.hpp"
#include "vpm/config.hpp"
#include "vpm/error.hpp"

namespace {
void usage(std::ostream& out) {
  out << "vpm " VPM_VERSION ": volume-preserving mapping and registration of 3-D shapes\n"
         "usage:\n";
  for (const auto& c : vpm::cli::commands()) out << "  " << vpm::cli::synopsis(c) << "\n      " << c.summary << '\n';
  out << "environment: VPM_DEVICE=host|cpu|gpu|P:D|name-substring selects the compute device;\n"
         "  VPM_MAX_MEMORY=SIZE|off replaces the measured free memory work is checked against\n"
         "exit status: 0 ok, 2 bad input or usage, 3 numerical failure, 4 written but not converged,\n"
         "  5 device fault, 1 internal error\n";
}
}  // namespace

int main(int argc, char** argv) {
  // a file size limit (ulimit -f, RLIMIT_FSIZE) makes write(2) fail with EFBIG instead of killing
  // the process: the output is then refused with a message and nothing is left (AtomicFile)
  std::signal(SIGXFSZ, SIG_IGN);
  // large arrays (an element table's columns at level 6 are 17 MB each) come from one heap and go
  // back to it, not to the system: glibc would otherwise map each one afresh (and each thread's
  // in an arena of its own) and fault in every page again; on a virtual machine that was most of
  // the time of a reference's normal (0.14 -> 0.01 s for its values; bench/results/LEDGER.md)
  mallopt(M_MMAP_MAX, 0);
  mallopt(M_ARENA_MAX, 1);
  mallopt(M_TRIM_THRESHOLD, 1 << 30);
  std::vector<std::string> args(argv + 1, argv + argc);
  if (args.empty() || args[0] == "--help" || args[0] == "-h" || args[0] == "help") {
    usage(args.empty() ? std::cerr : std::cout);
    return args.empty() ? vpm::kExitInput : vpm::kExitOk;
  }
  if (args[0] == "--version") {
    std::cout << "vpm " VPM_VERSION "\n";
    return 0;
  }
  for (const auto& c : vpm::cli::commands()) {
    if (c.name != args[0]) continue;
    if (args.size() == 2 && (args[1] == "--help" || args[1] == "-h")) {
      std::cout << vpm::cli::help_text(c);
      return vpm::kExitOk;
    }
    if (args.size() == 3 && (args[1] == "--help" || args[1] == "-h") && args[2] == "--expert") {
      std::cout << vpm::cli::help_text(c, true);
      return vpm::kExitOk;
    }
    try {
      return c.run(c, std::vector<std::string>(args.begin() + 1, args.end()));
    } catch (const vpm::InputError& e) {
      std::cerr << "vpm " << c.name << ": error: " << e.what() << '\n';
      return vpm::kExitInput;
    } catch (const vpm::NumericalError& e) {
      std::cerr << "vpm " << c.name << ": numerical failure: " << e.what() << '\n';
      return vpm::kExitNumerical;
    } catch (const vpm::DeviceError& e) {
      std::cerr << "vpm " << c.name << ": device error: " << e.what() << '\n';
      return vpm::kExitDevice;
    } catch (const std::bad_alloc&) {
      std::cerr << "vpm " << c.name << ": error: out of memory\n";
      return vpm::kExitInternal;
    } catch (const std::exception& e) {
      const std::string cl = vpm::opencl_error_description(e);  // a call no stage turned into a DeviceError
      if (!cl.empty()) {
        std::cerr << "vpm " << c.name << ": device error: " << cl << "; VPM_DEVICE=host runs without OpenCL\n";
        return vpm::kExitDevice;
      }
      std::cerr << "vpm " << c.name << ": internal error: " << e.what() << '\n';
      return vpm::kExitInternal;
    }
  }
  std::cerr << "vpm: unknown command '" << args[0] << "'\n";
  usage(std::cerr);
  return vpm::kExitInput;
}
