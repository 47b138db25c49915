#pragma once
// Small helpers the benchmark programs share.
#include <algorithm>
#include <string>
#include <vector>

#include "vpm/error.hpp"

namespace vpm::bench {

/// The median (mean of the middle two for an even count); 0 for none.
inline double median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/// "100000,400000" -> {100000, 400000}; empty items are skipped ("" = none).
inline std::vector<long> parse_sizes(const std::string& s) {
  std::vector<long> out;
  size_t p = 0;
  while (p <= s.size()) {
    const size_t q = std::min(s.find(',', p), s.size());
    if (q > p) out.push_back(std::stol(s.substr(p, q - p)));
    p = q + 1;
  }
  return out;
}

/// The options of a benchmark over generated sizes and given files:
/// [--sizes N,N,...] [--repeats R] [--json FILE] [FILE ...].
struct SizedRun {
  std::vector<long> sizes;
  int repeats = 3;
  std::string json;
  std::vector<std::string> files;
};

/// Parses argv over `defaults`; InputError(usage) on anything else.
inline SizedRun parse_sized_run(int argc, char** argv, SizedRun defaults, const std::string& usage) {
  SizedRun r = std::move(defaults);
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const bool has_value = i + 1 < argc;
    if (a == "--sizes" && has_value) r.sizes = parse_sizes(argv[++i]);
    else if (a == "--repeats" && has_value) r.repeats = std::max(1, std::stoi(argv[++i]));
    else if (a == "--json" && has_value) r.json = argv[++i];
    else if (!a.empty() && a[0] != '-') r.files.push_back(a);
    else throw InputError(usage);
  }
  return r;
}

}  // namespace vpm::bench
