#pragma once
// Memory limits: how much memory this process may still take, and the check that refuses work
// too large for it up front (an InputError with the estimate, exit status 2) instead of letting
// the kernel's OOM killer end the process half way.
//
//   VPM_MAX_MEMORY=SIZE   use SIZE (bytes, or with a K/M/G/T suffix, powers of 1024) as the
//                         memory available instead of measuring it: lower it to share a node,
//                         raise it when the measure is too cautious (swap, a GPU host)
//   VPM_MAX_MEMORY=off    no check at all
//   unset                 measured: MemAvailable of /proc/meminfo, lowered to the headroom of
//                         the process's memory cgroup (v1 or v2, every level up to the root:
//                         limit minus usage, reclaimable file cache not counted as usage)
#include <cstdint>
#include <string>

namespace vpm {

/// The memory this process may still allocate, and where that number comes from.
struct MemoryBudget {
  bool checked = true;        ///< false with VPM_MAX_MEMORY=off (or nothing could be measured)
  std::uint64_t bytes = 0;    ///< available for new allocations
  std::string source;         ///< "VPM_MAX_MEMORY", "MemAvailable" or "cgroup <path>"
  std::uint64_t resident = 0; ///< this process's resident size now (already in use)
};

/// Reads VPM_MAX_MEMORY or measures (see the top of this header). InputError when
/// VPM_MAX_MEMORY is set to something that is not a size or "off".
MemoryBudget memory_budget();

/// Parses a size: "123", "512K", "1.5G", "2T" (case-insensitive, optional "B"/"iB"). InputError
/// naming `what` on anything else.
std::uint64_t parse_memory_size(const std::string& text, const std::string& what);

/// "1.23 GiB", "512 MiB" (powers of 1024, like the VPM_MAX_MEMORY suffixes; for messages).
std::string format_bytes(double bytes);

/// Refuses work whose whole-process peak is estimated at `peak_bytes`: throws InputError
/// "`what`: needs about P (`how`), only A available (source); set VPM_MAX_MEMORY=... to
/// override" when the part not yet resident exceeds the budget. `how` says how P was estimated
/// (e.g. "1,100,000 tets x 960 bytes").
void require_memory(double peak_bytes, const std::string& what, const std::string& how);

}  // namespace vpm
