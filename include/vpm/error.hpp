#pragma once
// Error kinds and the exit status each maps to in the `vpm` program.
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

/// Exit status the command-line program uses for each error kind.
/// 4: the output was written but missed its tolerance by a wide margin (vpm map, vpm register;
/// `--allow-partial` turns it into 0; the warning and the report's "converged": false stay).
enum ExitCode : int { kExitOk = 0, kExitInternal = 1, kExitInput = 2, kExitNumerical = 3, kExitNotConverged = 4 };

}  // namespace vpm
