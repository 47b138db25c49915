#pragma once
// Private helper: a fixed set of host threads that run one task set at a time. For loops called
// thousands of times on a few thousand items (the untangler's energy evaluations), where starting
// threads on every call (core/parallel.hpp) costs more than it saves.
#include <atomic>
#include <functional>
#include <thread>
#include <vector>

namespace vpm::detail {

class WorkerPool {
 public:
  /// `threads` in all, the calling thread included: threads - 1 are started here and wait,
  /// asleep, for run().
  explicit WorkerPool(int threads);
  ~WorkerPool();
  WorkerPool(const WorkerPool&) = delete;
  WorkerPool& operator=(const WorkerPool&) = delete;

  /// The threads run() uses, the caller's included.
  int threads() const { return static_cast<int>(workers_.size()) + 1; }

  /// Runs task(k) for every k in [0, threads()), task(0) on the calling thread, and returns when
  /// all have returned. The task must not throw. One run at a time (not reentrant).
  void run(const std::function<void(int)>& task);

 private:
  void loop(int k);

  std::vector<std::thread> workers_;
  const std::function<void(int)>* task_ = nullptr;  // published by generation_'s release
  bool stop_ = false;                               // likewise
  std::atomic<unsigned> generation_{0};             // one more per run and at destruction
  std::atomic<int> pending_{0};                     // workers still running the current task
};

}  // namespace vpm::detail
