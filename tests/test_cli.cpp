// The `vpm` program's plumbing (apps/cli.*): option tables, --help, docs/cli.md's synopsis, exit
// codes of bad usage. The end-to-end runs of each command live with the module they exercise
// (test_volume_map: vpm map; test_io: convert, stats; test_registration: register;
// test_mesh_image: mesh-image; test_collective: demo).
#include <catch2/catch.hpp>
#include <algorithm>
#include <string>
#include <utility>

#include "support/process.hpp"
#include "vpm/config.hpp"

using vpm::test::run_status;
using vpm::test::slurp;

namespace {
const std::string kVpm = VPM_BINARY;
const char* kCommands[] = {"map", "register", "mesh-image", "initial-map", "stats", "convert", "devices", "demo", "elements", "sample", "compare"};
std::string tmp(const std::string& name) { return std::string(VPM_TEST_TMP) + "/cli_" + name; }
}  // namespace

// Lines of `text` and the widest of them.
std::pair<int, size_t> extent(const std::string& text) {
  int lines = 0;
  size_t widest = 0, start = 0;
  for (size_t end; (end = text.find('\n', start)) != std::string::npos; start = end + 1, ++lines)
    widest = std::max(widest, end - start);
  return {lines, widest};
}

TEST_CASE("cli: vpm CMD --help prints the synopsis and the options on one screen, and exits 0") {
  for (const char* c : kCommands) {
    INFO(c);
    const std::string out = tmp(std::string("help_") + c + ".txt");
    REQUIRE(run_status(kVpm + " " + c + " --help > " + out + " 2>/dev/null") == 0);
    const std::string text = slurp(out);
    CHECK_THAT(text, Catch::StartsWith(std::string("usage: vpm ") + c));
    CHECK_THAT(text, Catch::Contains("--quiet") && Catch::Contains("--verbose"));
    const auto [lines, widest] = extent(text);
    CHECK(lines <= 45);  // one screen
    CHECK(widest <= 100);
  }
  const std::string text = slurp(tmp("help_map.txt"));
  for (const char* flag : {"--rounds R", "--tolerance T", "--boundary slide|fixed", "--report REPORT.json"})
    CHECK_THAT(text, Catch::Contains(flag));
  CHECK_THAT(text, !Catch::Contains("--rk-steps"));  // an expert option
  // an option left out of the synopsis is still listed; expert ones only with --expert
  const std::string reg = slurp(tmp("help_register.txt"));
  CHECK_THAT(reg, Catch::Contains("--dense-force labels|image|both") && Catch::Contains("--preset"));
  CHECK_THAT(reg, !Catch::Contains("--flow-boundary-samples") && !Catch::Contains("--dense-ridge"));
  CHECK_THAT(reg, Catch::Contains("expert options: vpm register --help --expert"));
  REQUIRE(run_status(kVpm + " register --help --expert > " + tmp("reg.txt")) == 0);
  const std::string expert = slurp(tmp("reg.txt"));
  CHECK_THAT(expert, Catch::Contains("--flow-boundary-samples N") && Catch::Contains("--dense-ridge R") &&
                         Catch::Contains("--template TEMPLATE.vtu"));
  CHECK(extent(expert).second <= 100);
  // expert options stay accepted
  CHECK(run_status(kVpm + " register m.vtu -o o.vtu --template t.vtu --dense-ridge 0.5 --flow-boundary-samples 10 2> " +
                   tmp("reg.err")) == 2);
  CHECK_THAT(slurp(tmp("reg.err")), Catch::Contains("m.vtu") && !Catch::Contains("unknown option"));
}

TEST_CASE("cli: docs/cli.md's command synopsis is what `vpm --help` prints") {
  const std::string script = std::string(VPM_SOURCE_DIR) + "/scripts/readme_synopsis.py";
  const std::string readme = std::string(VPM_SOURCE_DIR) + "/docs/cli.md";
  CHECK(run_status("python3 " + script + " " + kVpm + " --check " + readme + " 2> " + tmp("readme.err")) == 0);
  INFO(slurp(tmp("readme.err")));
  // and the check notices a difference
  const std::string changed = tmp("cli.md");
  REQUIRE(run_status("sed 's/--tolerance T/--tolerance X/' " + readme + " > " + changed) == 0);
  CHECK(run_status("python3 " + script + " " + kVpm + " --check " + changed + " 2>/dev/null") == 1);
}

TEST_CASE("cli: the stage pages' options tables are what `vpm CMD --help --expert` lists") {
  const std::string script = std::string(VPM_SOURCE_DIR) + "/scripts/doc_options.py";
  CHECK(run_status("python3 " + script + " " + kVpm + " --check 2> " + tmp("options.err")) == 0);
  INFO(slurp(tmp("options.err")));
  // and the check notices a table that lost a row
  const std::string page = std::string(VPM_SOURCE_DIR) + "/docs/register.md";
  const std::string changed = tmp("register.md");
  REQUIRE(run_status("grep -v 'dense-ridge' " + page + " > " + changed) == 0);
  CHECK(run_status("python3 " + script + " " + kVpm + " --check " + changed + " 2>/dev/null") == 1);
}

TEST_CASE("cli: bad usage exits 2 with one line naming the problem") {
  const std::string err = tmp("err.txt");
  CHECK(run_status(kVpm + " map --no-such-option 2> " + err) == 2);
  CHECK_THAT(slurp(err), Catch::Contains("unknown option --no-such-option"));
  CHECK(run_status(kVpm + " map in.vtu -o out.vtu --rounds 2> " + err) == 2);
  CHECK_THAT(slurp(err), Catch::Contains("option --rounds needs a value"));
  CHECK(run_status(kVpm + " map in.vtu -o out.vtu --rounds two 2> " + err) == 2);
  CHECK_THAT(slurp(err), Catch::Contains("--rounds") && Catch::Contains("not an integer"));
  CHECK(run_status(kVpm + " map in.vtu -o out.vtu --boundary fast 2> " + err) == 2);
  CHECK_THAT(slurp(err), Catch::Contains("option --boundary: volume map boundary 'fast' is not one of auto, slide, fixed"));
  CHECK(run_status(kVpm + " no-such-command 2> " + err) == 2);
  CHECK(run_status(kVpm + " > " + tmp("usage.txt") + " 2>&1") == 2);  // no command: usage, exit 2
  CHECK_THAT(slurp(tmp("usage.txt")), Catch::Contains("vpm map MESH|SURFACE -o OUT"));
  const std::string ver = tmp("version.txt");
  CHECK(run_status(kVpm + " --version > " + ver) == 0);
  CHECK(slurp(ver) == std::string("vpm ") + VPM_VERSION + "\n");
}
