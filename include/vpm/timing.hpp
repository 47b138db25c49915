#pragma once
// Wall-clock and CPU timing of stages: the one home for timings in the library, the program
// and the benchmarks. Reports carry seconds as doubles (`timings_s` in the report JSON).
#include <algorithm>
#include <chrono>
#include <ctime>

namespace vpm {

using Clock = std::chrono::steady_clock;

/// Seconds of wall-clock time since `t0`.
inline double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

/// A time budget for long work (`vpm map --max-seconds`): iterative stages check it between
/// rounds and stop with the best result so far (reported as not converged, reason
/// "time_budget"); a stage that has no result yet (an initial map with folds left) fails with a
/// NumericalError that says the budget ran out. The default never passes.
struct Deadline {
  Clock::time_point at = Clock::time_point::max();

  /// `seconds` from now; `seconds` <= 0 or not finite: none.
  static Deadline in_seconds(double seconds) {
    Deadline d;
    if (seconds > 0 && seconds < 1e9)
      d.at = Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(seconds));
    return d;
  }
  /// Whether a budget was set.
  bool set() const { return at != Clock::time_point::max(); }
  /// Whether the budget is spent.
  bool passed() const { return set() && Clock::now() >= at; }
  /// Seconds left (0 when passed; a large number when not set).
  double remaining() const {
    if (!set()) return 1e18;
    return std::max(0.0, std::chrono::duration<double>(at - Clock::now()).count());
  }
};

/// Measures a stage: wall-clock seconds and the process's CPU seconds since construction or
/// the last restart().
class Stopwatch {
 public:
  Stopwatch() { restart(); }
  void restart() {
    wall_ = Clock::now();
    cpu_ = std::clock();
  }
  /// Wall-clock seconds.
  double seconds() const { return seconds_since(wall_); }
  /// CPU seconds of the whole process (all threads).
  double cpu_seconds() const { return double(std::clock() - cpu_) / CLOCKS_PER_SEC; }

 private:
  Clock::time_point wall_;
  std::clock_t cpu_;
};

}  // namespace vpm
