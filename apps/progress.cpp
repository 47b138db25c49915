// Progress display of the `vpm` commands (declared in cli.hpp): where long work is, on a
// terminal and in logs, so that a slow run can be told from a stuck one.
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <mutex>
#include <string>
#include <thread>

#include "cli.hpp"
#include "vpm/format.hpp"
#include "vpm/timing.hpp"

namespace vpm::cli {

namespace {

double interval_from_environment() {
  const char* e = std::getenv("VPM_PROGRESS_SECONDS");
  if (!e || !*e) return 10;
  char* end = nullptr;
  const double v = std::strtod(e, &end);
  return end && *end == '\0' && v >= 0 && v < 1e6 ? v : 10;
}

// The last step reported and what was printed when; a watcher thread (started with the first
// line) prints "still running" lines while a step stays silent.
class Display {
 public:
  Display() : interval_(interval_from_environment()) {}
  ~Display() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stop_ = true;
    }
    wake_.notify_all();
    if (watcher_.joinable()) watcher_.join();
  }

  void step(const std::string& line) {
    std::lock_guard<std::mutex> lock(mutex_);
    const Clock::time_point now = Clock::now();
    current_ = line;
    step_start_ = now;
    const bool log = !verbosity().terminal;
    if (verbosity().verbose || (log && due(now))) {
      print_line(stamped(line));
    } else if (!log) {
      std::cerr << '\r' << stamped(line) << "\033[K" << std::flush;
      showing_ = true;
    }
    if (!watcher_.joinable()) watcher_ = std::thread([this] { watch(); });
  }

  void info(const std::string& line) {
    std::lock_guard<std::mutex> lock(mutex_);
    print_line(line);
  }

 private:
  std::string stamped(const std::string& line) const {
    return strprintf("[%6.1f s] ", seconds_since(start_)) + line;
  }
  bool due(Clock::time_point now) const {
    return seconds_since(start_) >= interval_ && std::chrono::duration<double>(now - printed_).count() >= interval_;
  }
  void print_line(const std::string& line) {
    if (showing_) std::cerr << "\r\033[K";
    showing_ = false;
    std::cerr << line << '\n' << std::flush;
    printed_ = Clock::now();
  }
  // While a step runs: on a terminal its line with the seconds ticking; in a log a line after
  // 3 intervals (at least 0.75 s) without one.
  void watch() {
    const double silence = 3 * std::max(interval_, 0.25);
    const auto period = std::chrono::duration<double>(std::clamp(interval_, 0.05, 1.0));
    std::unique_lock<std::mutex> lock(mutex_);
    while (!wake_.wait_for(lock, period, [this] { return stop_; })) {
      const double quiet = std::chrono::duration<double>(Clock::now() - printed_).count();
      const double since = seconds_since(step_start_);
      const std::string still = strprintf("still working, %.0f s since: ", since) + current_;
      if (verbosity().terminal && !verbosity().verbose) {
        if (since < 2) continue;
        std::cerr << '\r' << stamped(still) << "\033[K" << std::flush;
        showing_ = true;
      } else if (quiet >= silence && since >= silence) {
        print_line(stamped(still));
      }
    }
  }

  const double interval_;
  const Clock::time_point start_ = Clock::now();
  Clock::time_point printed_ = Clock::now(), step_start_ = Clock::now();
  std::string current_;
  bool showing_ = false, stop_ = false;
  std::mutex mutex_;
  std::condition_variable wake_;
  std::thread watcher_;
};

Display& display() {
  static Display d;
  return d;
}

}  // namespace

Verbosity& verbosity() {
  static Verbosity v{false, false, static_cast<bool>(::isatty(2))};
  return v;
}

void info(const std::string& line) {
  if (!verbosity().quiet) display().info(line);
}

void progress(const std::string& line) {
  if (!verbosity().quiet) display().step(line);
}

}  // namespace vpm::cli
