#pragma once
// The `vpm` program's plumbing: sub-commands register themselves (one apps/cmd_*.cpp each),
// main() parses nothing but the sub-command name and maps exceptions to exit codes.
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "vpm/ball_map.hpp"
#include "vpm/error.hpp"
#include "vpm/timing.hpp"

namespace vpm::cli {

struct Command;

/// Parsed arguments of one sub-command: positionals and --options.
class Args {
 public:
  /// Parses `argv` by the command's option table (options with an empty value are flags;
  /// --quiet and --verbose are always accepted).
  Args(std::vector<std::string> argv, const Command& command);
  const std::vector<std::string>& positional() const { return positional_; }
  bool has(const std::string& opt) const { return values_.count(opt) > 0; }
  /// The options and flags given, by name.
  std::vector<std::string> given() const {
    std::vector<std::string> names;
    for (const auto& kv : values_) names.push_back(kv.first);
    return names;
  }
  std::optional<std::string> get(const std::string& opt) const;
  std::string get(const std::string& opt, const std::string& fallback) const;
  double get_double(const std::string& opt, double fallback) const;  ///< InputError if not a number
  int get_int(const std::string& opt, int fallback) const;          ///< InputError if not an integer
  /// Exactly `n` positionals or InputError with `usage`.
  void expect_positional(size_t n, const std::string& usage) const;

 private:
  /// `flags` lists options that take no value; every other --option in `value_options` takes one.
  Args(std::vector<std::string> argv, std::vector<std::string> value_options, std::vector<std::string> flags);
  std::vector<std::string> positional_;
  std::map<std::string, std::string> values_;
};

/// The MESH operand and -o OUT of a mesh-to-mesh command, both checked to be mesh files by
/// extension (InputError naming the file, or the usage when either is missing).
struct MeshInOut {
  std::string in, out;
};
MeshInOut mesh_in_out(const Args& args, const Command& command);

/// After an output was written: a warning line on stderr when `reached` missed `tolerance`
/// ("vpm CMD: warning: not converged: WHAT REACHED > tolerance TOL (REASON); ..."), and the exit
/// status: kExitNotConverged when it missed by more than 2x and !allow_partial, else 0.
/// `format` prints a value (e.g. vpm::pct).
int convergence_status(const std::string& command, const std::string& what, double reached, double tolerance,
                       const std::string& reason, bool allow_partial, std::string (*format)(double));
/// The same for a ball map (vpm/ball_map.hpp MapConvergence; 0 when it was not checked). A map
/// that the time budget stopped short of its tolerance exits 4 (unless allow_partial) however
/// close it came.
int convergence_status(const std::string& command, const MapConvergence& convergence, bool allow_partial);
/// --max-seconds S: a Deadline S seconds after `start` (none without the option; InputError
/// for S <= 0 or not a number).
Deadline time_budget(const Args& args, Clock::time_point start);
/// After an output was written although the time budget stopped the work: a warning naming
/// `reached` (what was done), exit kExitNotConverged unless allow_partial.
int time_budget_status(const std::string& command, const std::string& reached, bool allow_partial);

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

/// One option of a command. The table of a command's options is the single source of its
/// parsing (Args), its synopsis and its --help text; docs/cli.md's command synopsis is checked
/// against `vpm --help` by tests/test_cli.cpp.
struct OptionSpec {
  std::string flag;         ///< "--rounds"
  std::string value;        ///< placeholder of its value ("R", "moser|paper|vsem"); empty: a flag
  std::string help;         ///< one line: what it does, its default
  bool required = false;    ///< shown without brackets; the command checks its presence
  int group = 0;            ///< consecutive options with the same non-zero group are alternatives
  bool hidden = false;      ///< accepted and listed by --help, left out of the synopsis
  /// A setting for experiments and benchmarks (the presets and defaults cover what users need):
  /// accepted, left out of the synopsis and of --help, listed by `vpm CMD --help --expert`.
  bool expert = false;
};

struct Command {
  std::string name;      ///< "map"
  std::string operands;  ///< "MESH -o OUT"
  std::string summary;   ///< one line for `vpm --help`
  std::vector<OptionSpec> options;
  int (*run)(const Command& self, const std::vector<std::string>& argv);
  std::string program = "vpm";  ///< the program the synopsis names (a benchmark's own, with no NAME)
};

/// "vpm NAME OPERANDS [--flag VALUE] [--a A | --b B] ..." from the command's table.
std::string synopsis(const Command& c);
/// The synopsis, the summary and the options (and --quiet, --verbose), wrapped at 100 columns:
/// the expert ones only with `expert` (otherwise one line says how many there are).
std::string help_text(const Command& c, bool expert = false);

/// `command` with the options named in `flags` marked expert (OptionSpec::expert); a flag the
/// table lacks is a programming error (std::logic_error).
Command with_expert(Command command, const std::vector<std::string>& flags);

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
/// Prints a line to stderr unless quiet.
void info(const std::string& line);
/// Shows where long work is (apps/progress.cpp; docs/robustness.md): on a terminal one line
/// rewritten in place; in a log (stderr not a terminal) plain lines, at most one every
/// VPM_PROGRESS_SECONDS (default 10; 0: every line), and a "still working" line naming the
/// last step reported when 3 such intervals (at least 0.75 s) pass without a new line; --verbose: every line;
/// --quiet: none. Lines carry the seconds since the command started.
void progress(const std::string& line);

}  // namespace vpm::cli
