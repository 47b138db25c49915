#pragma once
// Private helper: split [0, n) into one contiguous chunk per host thread (at most 16) and run
// body(begin, end) on each; runs inline when n < min_parallel or only one thread exists.
#include <algorithm>
#include <thread>
#include <vector>

namespace vpm::detail {

/// The number of host threads parallel_for uses: the hardware's, at most 16.
inline int host_threads() { return std::clamp(static_cast<int>(std::thread::hardware_concurrency()), 1, 16); }

template <class Body>
void parallel_for(int n, int min_parallel, Body body) {
  const int threads = host_threads();
  if (threads == 1 || n < min_parallel) {
    if (n > 0) body(0, n);
    return;
  }
  const int chunk = (n + threads - 1) / threads;
  std::vector<std::thread> pool;
  for (int t = 0; t < threads; ++t) {
    const int b = t * chunk, e = std::min(n, b + chunk);
    if (b < e) pool.emplace_back(body, b, e);
  }
  for (auto& th : pool) th.join();
}

}  // namespace vpm::detail
