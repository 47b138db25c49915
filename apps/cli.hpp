#pragma once
// The `vpm` program's plumbing: sub-commands register themselves (one apps/cmd_*.cpp each),
// main() parses nothing but the sub-command name and maps exceptions to exit codes.
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "vpm/error.hpp"

namespace vpm::cli {

/// Parsed arguments of one sub-command: positionals and --options.
class Args {
 public:
  /// `flags` lists options that take no value (e.g. "--quiet"); every other --option takes one.
  Args(std::vector<std::string> argv, std::vector<std::string> value_options,
       std::vector<std::string> flags);
  const std::vector<std::string>& positional() const { return positional_; }
  bool has(const std::string& opt) const { return values_.count(opt) > 0; }
  std::optional<std::string> get(const std::string& opt) const;
  std::string get(const std::string& opt, const std::string& fallback) const;
  double get_double(const std::string& opt, double fallback) const;  ///< InputError if not a number
  int get_int(const std::string& opt, int fallback) const;          ///< InputError if not an integer
  /// Exactly `n` positionals or InputError with `usage`.
  void expect_positional(size_t n, const std::string& usage) const;

 private:
  std::vector<std::string> positional_;
  std::map<std::string, std::string> values_;
};

/// Runs `parse` (a library parser of an option's value, e.g. parse_volume_map_method) and
/// prefixes an InputError it throws with "option FLAG: ", so the message names the flag.
template <class F>
auto parse_option(const std::string& flag, F&& parse) -> decltype(parse()) {
  try {
    return parse();
  } catch (const InputError& e) {
    throw InputError("option " + flag + ": " + e.what());
  }
}

struct Command {
  std::string name;
  std::string synopsis;  ///< one usage line
  int (*run)(const std::vector<std::string>& argv);
};

/// Registry filled by static Registrar objects in each cmd_*.cpp.
std::vector<Command>& commands();
struct Registrar {
  explicit Registrar(Command c) { commands().push_back(std::move(c)); }
};

/// Progress and verbosity shared by sub-commands (--quiet, --verbose).
struct Verbosity {
  bool quiet = false;
  bool verbose = false;
  bool terminal = false;  ///< stderr is a terminal: show progress
};
Verbosity& verbosity();
/// Prints to stderr unless quiet; progress lines only when stderr is a terminal or verbose.
void info(const std::string& line);
void progress(const std::string& line);

}  // namespace vpm::cli
