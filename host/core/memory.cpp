#include "vpm/memory.hpp"

#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <optional>
#include <sstream>
#include <vector>

#include "vpm/error.hpp"
#include "vpm/format.hpp"

namespace vpm {

namespace {

std::optional<std::uint64_t> read_number(const std::filesystem::path& file) {
  std::ifstream in(file);
  std::string word;
  if (!(in >> word) || word == "max") return std::nullopt;
  try {
    return std::stoull(word);
  } catch (...) {
    return std::nullopt;
  }
}

// "key value" lines (memory.stat): the value of `key`, 0 when absent.
std::uint64_t stat_value(const std::filesystem::path& file, const std::string& key) {
  std::ifstream in(file);
  std::string k;
  std::uint64_t v = 0;
  while (in >> k >> v)
    if (k == key) return v;
  return 0;
}

std::optional<std::uint64_t> mem_available() {
  std::ifstream in("/proc/meminfo");
  std::string key, unit;
  std::uint64_t kb = 0;
  while (in >> key >> kb) {
    std::getline(in, unit);
    if (key == "MemAvailable:") return kb * 1024;
  }
  return std::nullopt;
}

// Headroom of one cgroup folder (v2 memory.max / v1 memory.limit_in_bytes), nullopt if unlimited.
std::optional<std::uint64_t> cgroup_headroom(const std::filesystem::path& dir, bool v2) {
  const auto limit = read_number(dir / (v2 ? "memory.max" : "memory.limit_in_bytes"));
  if (!limit || *limit >= (std::uint64_t(1) << 60)) return std::nullopt;  // v1 "unlimited" is ~2^63
  const auto usage = read_number(dir / (v2 ? "memory.current" : "memory.usage_in_bytes")).value_or(0);
  const std::uint64_t cache = stat_value(dir / "memory.stat", v2 ? "inactive_file" : "total_inactive_file");
  const std::uint64_t used = usage > cache ? usage - cache : 0;
  return *limit > used ? *limit - used : 0;
}

// The smallest headroom over the process's memory cgroup and its ancestors; `where` its folder.
std::optional<std::uint64_t> cgroup_available(std::string& where) {
  std::ifstream in("/proc/self/cgroup");
  std::string line;
  std::optional<std::uint64_t> best;
  while (std::getline(in, line)) {  // "0::/path" (v2) or "4:memory:/path" (v1)
    const auto a = line.find(':'), b = line.find(':', a + 1);
    if (a == std::string::npos || b == std::string::npos) continue;
    const std::string controllers = line.substr(a + 1, b - a - 1);
    const bool v2 = controllers.empty();
    if (!v2 && controllers.find("memory") == std::string::npos) continue;
    const std::filesystem::path root = v2 ? "/sys/fs/cgroup" : "/sys/fs/cgroup/memory";
    for (std::filesystem::path rel = line.substr(b + 1);; rel = rel.parent_path()) {
      const std::filesystem::path dir = root / rel.relative_path();
      if (const auto h = cgroup_headroom(dir, v2); h && (!best || *h < *best)) best = h, where = dir.string();
      if (rel == rel.parent_path() || rel.empty()) break;
    }
  }
  return best;
}

std::uint64_t resident_bytes() {
  std::ifstream in("/proc/self/statm");
  std::uint64_t size = 0, resident = 0;
  in >> size >> resident;
  return resident * static_cast<std::uint64_t>(::sysconf(_SC_PAGESIZE));
}

}  // namespace

std::uint64_t parse_memory_size(const std::string& text, const std::string& what) {
  size_t end = 0;
  double v = -1;
  try {
    v = std::stod(text, &end);
  } catch (...) {
    end = 0;
  }
  std::string unit = text.substr(end);
  for (auto& c : unit) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  if (unit.size() > 1 && unit.back() == 'B') unit.pop_back();
  if (unit.size() > 1 && unit.back() == 'I') unit.pop_back();
  const std::string units = "KMGT";
  double scale = 1;
  if (unit.size() == 1 && units.find(unit[0]) != std::string::npos) scale = std::pow(1024.0, double(units.find(unit[0]) + 1));
  else if (!unit.empty() && unit != "B") end = 0;
  if (end == 0 || !(v >= 0) || !std::isfinite(v * scale) || v * scale > 1.8e19)
    throw InputError(what + ": '" + text + "' is not a size (bytes, or a number with K, M, G or T), nor 'off'");
  return static_cast<std::uint64_t>(v * scale);
}

std::string format_bytes(double bytes) {
  const char* units[] = {"bytes", "KiB", "MiB", "GiB", "TiB"};
  int u = 0;
  while (bytes >= 1024 && u < 4) bytes /= 1024, ++u;
  return u == 0 ? strprintf("%.0f bytes", bytes) : strprintf("%.3g %s", bytes, units[u]);
}

MemoryBudget memory_budget() {
  MemoryBudget b;
  b.resident = resident_bytes();
  if (const char* env = std::getenv("VPM_MAX_MEMORY"); env && *env) {
    const std::string v = env;
    if (v == "off" || v == "OFF") {
      b.checked = false;
      b.source = "VPM_MAX_MEMORY=off";
      return b;
    }
    b.bytes = parse_memory_size(v, "VPM_MAX_MEMORY");
    b.source = "VPM_MAX_MEMORY";
    return b;
  }
  const auto avail = mem_available();
  std::string where;
  const auto cg = cgroup_available(where);
  if (!avail && !cg) {
    b.checked = false;
    b.source = "not measurable (no /proc/meminfo)";
    return b;
  }
  if (cg && (!avail || *cg < *avail)) {
    b.bytes = *cg;
    b.source = "cgroup " + where;
  } else {
    b.bytes = *avail;
    b.source = "MemAvailable";
  }
  return b;
}

void require_memory(double peak_bytes, const std::string& what, const std::string& how) {
  const MemoryBudget b = memory_budget();
  if (!b.checked) return;
  // VPM_MAX_MEMORY caps the whole process; a measured budget is what is free besides us.
  const bool whole = b.source == "VPM_MAX_MEMORY";
  const double need = whole ? peak_bytes : std::max(0.0, peak_bytes - double(b.resident));
  if (need <= double(b.bytes)) return;
  throw InputError(what + ": too large for this machine's memory: needs about " + format_bytes(peak_bytes) + " (" +
                   how + "), " + (whole ? "VPM_MAX_MEMORY allows " : "only ") + format_bytes(double(b.bytes)) +
                   (whole ? "" : " available (" + b.source + ")") +
                   "; refused before starting. Set VPM_MAX_MEMORY=SIZE (e.g. 64G) or VPM_MAX_MEMORY=off to override");
}

}  // namespace vpm
