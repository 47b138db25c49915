#pragma once
// Private helper: run a piece of work that may crash (third-party code with fragile error
// paths) in a forked child process, so that a crash becomes an error message instead of taking
// vpm down. The child sends back the bytes its work produced, or the error it threw.
#include <functional>
#include <string>

namespace vpm::detail {

/// Runs `work` in a child process (fork) and returns the bytes it returned. An InputError the child throws is rethrown as InputError with the same message, any
/// other exception as NumericalError; a child killed by a signal gives
/// InputError("WHAT crashed (signal N)" + crash_hint). The child never returns to the caller's
/// code: it ends with _exit after writing its result.
std::string run_in_child(const std::function<std::string()>& work, const std::string& what,
                         const std::string& crash_hint);

}  // namespace vpm::detail
