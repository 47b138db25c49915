#pragma once
// Running the `vpm` program from tests: exit status of a shell command, file contents.
#include <string>

namespace vpm::test {

/// Runs `command` with /bin/sh; returns its exit status, -1 when it did not exit normally.
int run_status(const std::string& command);

/// The whole contents of file `path` ("" when it cannot be read).
std::string slurp(const std::string& path);

}  // namespace vpm::test
