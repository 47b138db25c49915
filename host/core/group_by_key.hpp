#pragma once
// Private helper: items grouped by key in CSR form, filled on all host threads.
#include <algorithm>
#include <cstddef>
#include <vector>

#include "core/parallel.hpp"

namespace vpm::detail {

/// Groups the items 0..m-1 by key (keys 0..num_keys-1; an item may have several keys, or a key
/// twice): start (num_keys + 1) gets each key's first slot, items each key's items in ascending
/// order, exactly as one serial pass over the items would list them. for_keys(item, visit)
/// calls visit(key) once per key of the item, the same keys in the same order both times it is
/// called for an item. A counting sort over contiguous item chunks, one per host thread (one
/// chunk below 65,536 items): chunk c's items go after chunks 0..c-1's in every key. Items is
/// any vector of int (resize then every slot written, so an uninitialising allocator works).
template <class ForKeys, class Items>
void group_by_key(int m, size_t num_keys, ForKeys for_keys, std::vector<int>& start, Items& items) {
  const int chunks = m < 65536 ? 1 : host_threads();
  const int per = m > 0 ? (m + chunks - 1) / chunks : 0;
  std::vector<int> count(static_cast<size_t>(chunks) * num_keys, 0);
  auto each = [&](int c, auto&& visit) {
    for (int t = c * per, e = std::min(m, (c + 1) * per); t < e; ++t) for_keys(t, [&](size_t key) { visit(key, t); });
  };
  parallel_for(chunks, 1, [&](int c0, int c1) {
    for (int c = c0; c < c1; ++c) {
      int* n = &count[static_cast<size_t>(c) * num_keys];
      each(c, [&](size_t key, int) { ++n[key]; });
    }
  });
  start.assign(num_keys + 1, 0);
  int total = 0;
  for (size_t key = 0; key < num_keys; ++key) {  // count becomes each chunk's first slot for the key
    start[key] = total;
    for (int c = 0; c < chunks; ++c) {
      int& n = count[static_cast<size_t>(c) * num_keys + key];
      const int here = n;
      n = total;
      total += here;
    }
  }
  start[num_keys] = total;
  items.clear();
  items.resize(static_cast<size_t>(total));
  parallel_for(chunks, 1, [&](int c0, int c1) {
    for (int c = c0; c < c1; ++c) {
      int* slot = &count[static_cast<size_t>(c) * num_keys];
      each(c, [&](size_t key, int t) { items[static_cast<size_t>(slot[key]++)] = t; });
    }
  });
}

}  // namespace vpm::detail
