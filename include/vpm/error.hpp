#pragma once
// Error kinds and the exit status each maps to in the `vpm` program.
#include <exception>
#include <stdexcept>
#include <string>

namespace vpm {

/// Bad input or usage: a malformed file, an invalid mesh, an unknown device. Exit status 2.
/// The message is one line naming the file (or option), the place (line, element) and the problem.
class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Numerical failure: a solver that did not converge, a map that could not be untangled.
/// Exit status 3. The message says what was reached (residual, folded tets, where).
class NumericalError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The compute device failed: an OpenCL program did not build, a buffer larger than the device
/// allows or than it has free, an OpenCL call that returned an error. Exit status 5. The message
/// names the device, the program or buffer, and the OpenCL error (or the first lines of the
/// build log); VPM_DEVICE=host runs the same work without OpenCL.
class DeviceError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The description of an OpenCL error that reached the caller without being turned into a
/// DeviceError (a stage that missed one): "OpenCL error -5 (CL_OUT_OF_RESOURCES)". Empty when
/// `e` is not an OpenCL error. Lets programs report it without including OpenCL headers.
std::string opencl_error_description(const std::exception& e);

/// Exit status the command-line program uses for each error kind.
/// 4: the output was written but missed its tolerance by a wide margin (vpm map, vpm register;
/// `--allow-partial` turns it into 0; the warning and the report's "converged": false stay).
/// 5: DeviceError, or any other OpenCL error. 1: anything else ("internal error", a bug).
enum ExitCode : int {
  kExitOk = 0,
  kExitInternal = 1,
  kExitInput = 2,
  kExitNumerical = 3,
  kExitNotConverged = 4,
  kExitDevice = 5
};

}  // namespace vpm
