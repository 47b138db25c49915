#include "cli.hpp"

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <iostream>
#include <sstream>
#include <stdexcept>

#include "vpm/error.hpp"
#include "vpm/format.hpp"
#include "vpm/io.hpp"

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

namespace {
std::vector<std::string> option_flags(const Command& c, bool with_value) {
  std::vector<std::string> out;
  for (const OptionSpec& o : c.options)
    if (o.value.empty() != with_value) out.push_back(o.flag);
  return out;
}
std::string option_text(const OptionSpec& o) { return o.value.empty() ? o.flag : o.flag + " " + o.value; }
}  // namespace

Args::Args(std::vector<std::string> argv, const Command& command)
    : Args(std::move(argv), option_flags(command, true), option_flags(command, false)) {}

std::string synopsis(const Command& c) {
  std::string s = c.name.empty() ? c.program : c.program + " " + c.name;
  if (!c.operands.empty()) s += " " + c.operands;
  for (size_t i = 0; i < c.options.size(); ++i) {
    const OptionSpec& o = c.options[i];
    if (o.hidden || o.expert) continue;
    std::string item = option_text(o);
    while (o.group != 0 && i + 1 < c.options.size() && c.options[i + 1].group == o.group)
      item += " | " + option_text(c.options[++i]);
    s += o.required ? " " + item : " [" + item + "]";
  }
  return s;
}

namespace {
// `text` wrapped at 100 columns between words, continuation lines indented by `indent`; the
// first line starts at column `indent` too.
std::string wrapped(const std::string& text, size_t indent) {
  constexpr size_t kColumns = 100;
  std::string out, word;
  size_t column = indent;
  std::istringstream words(text);
  bool first = true;
  while (words >> word) {
    if (!first && column + 1 + word.size() > kColumns) {
      out += "\n" + std::string(indent, ' ');
      column = indent;
    } else if (!first) {
      out += ' ';
      ++column;
    }
    out += word;
    column += word.size();
    first = false;
  }
  return out;
}

// "  FLAG VALUE   help..." wrapped at 100 columns, continuation lines under the help's first column.
std::string option_lines(const OptionSpec& o, size_t width) {
  const std::string t = option_text(o);
  return "  " + t + std::string(width + 2 - t.size(), ' ') + wrapped(o.help, width + 4) + "\n";
}

// The synopsis wrapped at 100 columns before an optional item ("[..." or "(...") or a flag
// ("--..."; never between a flag and its value), continuation lines indented.
std::string wrapped_synopsis(const std::string& text) {
  constexpr size_t kColumns = 100;
  std::vector<std::string> items(1);
  int depth = 0;
  for (char ch : text) {
    depth += (ch == '[' || ch == '(') - (ch == ']' || ch == ')');
    if (ch == ' ' && depth == 0)
      items.emplace_back();
    else
      items.back() += ch;
  }
  std::string out, line;
  for (const std::string& item : items) {
    const bool breakable = item[0] == '[' || item[0] == '(' || item.rfind("--", 0) == 0;
    if (!line.empty() && breakable && line.size() + 1 + item.size() > kColumns) {
      out += line + "\n";
      line = "      " + item;
    } else {
      line += (line.empty() ? "" : " ") + item;
    }
  }
  return out + line + "\n";
}
}  // namespace

std::string help_text(const Command& c, bool expert) {
  std::string s = wrapped_synopsis("usage: " + synopsis(c)) + wrapped(c.summary, 0) + "\n";
  size_t width = 0, experts = 0;
  for (const OptionSpec& o : c.options)
    if (!o.expert || expert) width = std::max(width, option_text(o).size());
  width = std::min<size_t>(width, 30);
  if (!c.options.empty()) s += "options:\n";
  for (const OptionSpec& o : c.options) {
    experts += o.expert;
    if (!o.expert) s += option_lines(o, std::max(width, option_text(o).size()));
  }
  if (expert && experts > 0) {
    s += "expert options (experiments and benchmarks; the defaults and presets cover the rest):\n";
    for (const OptionSpec& o : c.options)
      if (o.expert) s += option_lines(o, std::max(width, option_text(o).size()));
  } else if (experts > 0) {
    s += std::to_string(experts) + " expert options: vpm " + c.name + " --help --expert\n";
  }
  s += "every command also takes --quiet (no messages) and --verbose (progress lines)\n";
  return s;
}

MeshInOut mesh_in_out(const Args& args, const Command& command) {
  const std::string usage = synopsis(command);
  args.expect_positional(1, usage);
  MeshInOut io;
  io.in = args.positional()[0];
  const auto out = args.get("-o");
  if (!out) throw InputError("missing -o OUT; usage: " + usage);
  io.out = *out;
  if (!is_mesh_path(io.in)) throw InputError(io.in + ": unknown mesh file extension");
  if (!is_mesh_path(io.out)) throw InputError(io.out + ": unknown mesh file extension for the output");
  return io;
}

int convergence_status(const std::string& command, const std::string& what, double reached, double tolerance,
                       const std::string& reason, bool allow_partial, std::string (*format)(double)) {
  if (reached <= tolerance) return kExitOk;
  const bool fail = reached > 2 * tolerance && !allow_partial;
  std::fprintf(stderr, "vpm %s: warning: not converged: %s %s > tolerance %s (%s); the output was written%s\n",
               command.c_str(), what.c_str(), format(reached).c_str(), format(tolerance).c_str(), reason.c_str(),
               fail ? "; exit status 4 (--allow-partial: 0)" : "");
  return fail ? kExitNotConverged : kExitOk;
}

int convergence_status(const std::string& command, const MapConvergence& c, bool allow_partial) {
  if (!c.checked) return kExitOk;
  if (c.reason == "time_budget" && c.reached > c.tolerance)
    return time_budget_status(command, "vertex mean |r-1| " + pct(c.reached) + " > tolerance " + pct(c.tolerance),
                              allow_partial);
  // the limbed shapes whose rounds stall at mesh-image's default density map 1.5 to 3 times
  // closer at five times the tets (docs/shapes.md, "Finer meshes for thin parts")
  const std::string hint = c.reason == "stalled" ? "; thin parts often map closer on a finer mesh: docs/shapes.md" : "";
  return convergence_status(command, "vertex mean |r-1|", c.reached, c.tolerance, "rounds stopped: " + c.reason + hint,
                            allow_partial, [](double v) { return pct(v); });
}

Deadline time_budget(const Args& args, Clock::time_point start) {
  if (!args.has("--max-seconds")) return {};
  const double s = args.get_double("--max-seconds", 0);
  if (!(s > 0) || s >= 1e9) throw InputError("option --max-seconds: must be > 0 and < 1e9");
  Deadline d;
  d.at = start + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s));
  return d;
}

int time_budget_status(const std::string& command, const std::string& reached, bool allow_partial) {
  std::fprintf(stderr, "vpm %s: warning: not converged: the time budget (--max-seconds) ran out at %s; the output "
               "was written%s\n", command.c_str(), reached.c_str(), allow_partial ? "" : "; exit status 4 (--allow-partial: 0)");
  return allow_partial ? kExitOk : kExitNotConverged;
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

Command with_expert(Command command, const std::vector<std::string>& flags) {
  for (const std::string& flag : flags) {
    auto it = std::find_if(command.options.begin(), command.options.end(),
                           [&](const OptionSpec& o) { return o.flag == flag; });
    if (it == command.options.end()) throw std::logic_error("vpm " + command.name + ": no option " + flag);
    it->expert = true;
  }
  return command;
}

std::vector<Command>& commands() {
  static std::vector<Command> c;
  return c;
}


}  // namespace vpm::cli
