#pragma once
// Fault tests: processes killed at random moments (SIGKILL, as a scheduler or the OOM killer
// does) and what they leave in a folder.
#include <sys/types.h>

#include <functional>
#include <string>
#include <vector>

namespace vpm::test {

/// Starts argv[0] (a path) with `argv`, its stdout to /dev/null and stderr to `err_path`, with
/// `env` ("NAME=value") added to the environment. Returns the child's pid.
pid_t spawn(const std::vector<std::string>& argv, const std::string& err_path = "/dev/null",
            const std::vector<std::string>& env = {});

/// Forks a child that runs `body` and then _exit(0)s (an exception in it: _exit(1)). Returns its pid.
pid_t fork_child(const std::function<void()>& body);

/// Waits `delay_s` seconds, SIGKILLs `pid` if it still runs, reaps it. True when the kill ended
/// it, false when it had exited by itself before.
bool kill_after(pid_t pid, double delay_s);

/// Waits for `pid`; its exit status, or -(signal) when a signal ended it.
int wait_status(pid_t pid);

/// The names of the entries of folder `dir` (hidden ones included), sorted.
std::vector<std::string> folder_entries(const std::string& dir);

/// Seconds since an arbitrary fixed moment (steady clock).
double now_s();

}  // namespace vpm::test
