#include "cli.hpp"

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <iostream>

#include "vpm/error.hpp"

namespace vpm::cli {

Args::Args(std::vector<std::string> argv, std::vector<std::string> value_options,
           std::vector<std::string> flags) {
  flags.push_back("--quiet");
  flags.push_back("--verbose");
  for (size_t i = 0; i < argv.size(); ++i) {
    const std::string& a = argv[i];
    if (a.size() > 2 && a.rfind("--", 0) == 0) {
      std::string key = a, val;
      auto eq = a.find('=');
      if (eq != std::string::npos) {
        key = a.substr(0, eq);
        val = a.substr(eq + 1);
      }
      if (std::find(flags.begin(), flags.end(), key) != flags.end()) {
        values_[key] = "1";
      } else if (std::find(value_options.begin(), value_options.end(), key) != value_options.end()) {
        if (eq == std::string::npos) {
          if (i + 1 >= argv.size()) throw InputError("option " + key + " needs a value");
          val = argv[++i];
        }
        values_[key] = val;
      } else {
        throw InputError("unknown option " + key);
      }
    } else if (a == "-o") {
      if (i + 1 >= argv.size()) throw InputError("option -o needs a value");
      values_["-o"] = argv[++i];
    } else {
      positional_.push_back(a);
    }
  }
  verbosity().quiet = has("--quiet");
  verbosity().verbose = has("--verbose");
}

std::optional<std::string> Args::get(const std::string& opt) const {
  auto it = values_.find(opt);
  if (it == values_.end()) return std::nullopt;
  return it->second;
}

std::string Args::get(const std::string& opt, const std::string& fallback) const {
  auto v = get(opt);
  return v ? *v : fallback;
}

double Args::get_double(const std::string& opt, double fallback) const {
  auto v = get(opt);
  if (!v) return fallback;
  try {
    size_t end = 0;
    double x = std::stod(*v, &end);
    if (end == v->size()) return x;
  } catch (...) {
  }
  throw InputError("option " + opt + ": '" + *v + "' is not a number");
}

int Args::get_int(const std::string& opt, int fallback) const {
  auto v = get(opt);
  if (!v) return fallback;
  try {
    size_t end = 0;
    long x = std::stol(*v, &end);
    if (end == v->size() && x >= -2147483647L && x <= 2147483647L) return static_cast<int>(x);
  } catch (...) {
  }
  throw InputError("option " + opt + ": '" + *v + "' is not an integer");
}

void Args::expect_positional(size_t n, const std::string& usage) const {
  if (positional_.size() != n) throw InputError("usage: " + usage);
}

std::vector<Command>& commands() {
  static std::vector<Command> c;
  return c;
}

Verbosity& verbosity() {
  static Verbosity v{false, false, static_cast<bool>(::isatty(2))};
  return v;
}

void info(const std::string& line) {
  if (!verbosity().quiet) std::cerr << line << '\n';
}

void progress(const std::string& line) {
  if (verbosity().quiet) return;
  if (verbosity().verbose) std::cerr << line << '\n';
  else if (verbosity().terminal) std::cerr << '\r' << line << "\033[K" << std::flush;
}


}  // namespace vpm::cli
