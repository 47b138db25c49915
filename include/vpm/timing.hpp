#pragma once
// Wall-clock and CPU timing of stages: the one home for timings in the library, the program
// and the benchmarks. Reports carry seconds as doubles (`timings_s` in the report JSON).
#include <chrono>
#include <ctime>

namespace vpm {

using Clock = std::chrono::steady_clock;

/// Seconds of wall-clock time since `t0`.
inline double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

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
