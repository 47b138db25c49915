// A fixed set of host threads woken once per task set (see core/worker_pool.hpp): the workers
// wait on the generation counter and the caller on the count of workers still running, first
// spinning a little (the untangler calls again within microseconds, and a futex sleep and wake
// cost about as much as a small task), then asleep (C++20 atomic wait, a futex on Linux).
#include "core/worker_pool.hpp"

namespace vpm::detail {

namespace {

// About 20-50 microseconds of spinning before a wait sleeps.
constexpr int kSpins = 2000;

inline void cpu_relax() {
#if defined(__x86_64__) || defined(__i386__)
  __builtin_ia32_pause();
#endif
}

// Waits until `a` differs from `old`: spins first, then sleeps.
template <class T>
void wait_while(const std::atomic<T>& a, T old) {
  for (int k = 0; k < kSpins; ++k) {
    if (a.load(std::memory_order_acquire) != old) return;
    cpu_relax();
  }
  a.wait(old, std::memory_order_acquire);
}

}  // namespace

WorkerPool::WorkerPool(int threads) {
  for (int k = 1; k < threads; ++k) workers_.emplace_back([this, k] { loop(k); });
}

WorkerPool::~WorkerPool() {
  stop_ = true;
  generation_.fetch_add(1, std::memory_order_release);
  generation_.notify_all();
  for (auto& w : workers_) w.join();
}

void WorkerPool::run(const std::function<void(int)>& task) {
  if (workers_.empty()) {
    task(0);
    return;
  }
  task_ = &task;
  pending_.store(static_cast<int>(workers_.size()), std::memory_order_relaxed);
  generation_.fetch_add(1, std::memory_order_release);
  generation_.notify_all();
  task(0);
  for (int left = pending_.load(std::memory_order_acquire); left != 0; left = pending_.load(std::memory_order_acquire))
    wait_while(pending_, left);
}

void WorkerPool::loop(int k) {
  unsigned seen = 0;
  for (;;) {
    // the next generation cannot start before this worker has finished the last (run() waits
    // for every worker), so none is missed
    wait_while(generation_, seen);
    seen = generation_.load(std::memory_order_acquire);
    if (stop_) return;
    (*task_)(k);
    if (pending_.fetch_sub(1, std::memory_order_acq_rel) == 1) pending_.notify_one();
  }
}

}  // namespace vpm::detail
