#pragma once
// Number formatting for messages and tables: the one home for it in the library, the program
// and the benchmarks.
#include <cstdio>
#include <sstream>
#include <string>

namespace vpm {

/// `v` with `significant` significant digits, as an ostream prints it ("0.0123", "1e-08").
inline std::string format_sig(double v, int significant = 4) {
  std::ostringstream s;
  s.precision(significant);
  s << v;
  return s.str();
}

/// A fraction as a percentage with two decimals: pct(0.0123) == "1.23 %".
inline std::string pct(double fraction) {
  char b[32];
  std::snprintf(b, sizeof b, "%.2f %%", 100 * fraction);
  return b;
}

/// printf into a std::string (at most 255 characters; for numbers in messages and tables).
template <class... Args>
std::string strprintf(const char* format, Args... args) {
  char b[256];
  std::snprintf(b, sizeof b, format, args...);
  return b;
}

}  // namespace vpm
