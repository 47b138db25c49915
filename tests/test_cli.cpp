// The `vpm` program's plumbing (apps/cli.*): option tables, --help, docs/cli.md's synopsis, exit
// codes of bad usage. The end-to-end runs of each command live with the module they exercise
// (test_volume_map: vpm map; test_io: convert, stats; test_registration: register;
// test_mesh_image: mesh-image; test_collective: demo).
#include <catch2/catch.hpp>
#include <string>

#include "support/process.hpp"
#include "vpm/config.hpp"

using vpm::test::run_status;
using vpm::test::slurp;

namespace {
const std::string kVpm = VPM_BINARY;
const char* kCommands[] = {"map", "register", "mesh-image", "initial-map", "stats", "convert", "devices", "demo", "elements", "sample", "compare"};
std::string tmp(const std::string& name) { return std::string(VPM_TEST_TMP) + "/cli_" + name; }
}  // namespace

TEST_CASE("cli: vpm CMD --help prints the synopsis, every option and exits 0") {
  for (const char* c : kCommands) {
    INFO(c);
    const std::string out = tmp(std::string("help_") + c + ".txt");
    REQUIRE(run_status(kVpm + " " + c + " --help > " + out + " 2>/dev/null") == 0);
    const std::string text = slurp(out);
    CHECK_THAT(text, Catch::StartsWith(std::string("usage: vpm ") + c));
    CHECK_THAT(text, Catch::Contains("--quiet") && Catch::Contains("--verbose"));
  }
  const std::string text = slurp(tmp("help_map.txt"));
  for (const char* flag : {"--rounds R", "--tolerance T", "--method moser|paper|vsem", "--boundary slide|fixed",
                           "--solver cg|paper", "--preconditioner auto|jacobi|amg", "--rk-steps N", "--report REPORT.json"})
    CHECK_THAT(text, Catch::Contains(flag));
  // an option listed only in --help (left out of the synopsis) is still documented
  REQUIRE(run_status(kVpm + " register --help > " + tmp("reg.txt")) == 0);
  CHECK_THAT(slurp(tmp("reg.txt")), Catch::Contains("--boundary-samples N"));
}

TEST_CASE("cli: docs/cli.md's command synopsis is what `vpm --help` prints") {
  const std::string script = std::string(VPM_SOURCE_DIR) + "/scripts/readme_synopsis.py";
  const std::string readme = std::string(VPM_SOURCE_DIR) + "/docs/cli.md";
  CHECK(run_status("python3 " + script + " " + kVpm + " --check " + readme + " 2> " + tmp("readme.err")) == 0);
  INFO(slurp(tmp("readme.err")));
  // and the check notices a difference
  const std::string changed = tmp("cli.md");
  REQUIRE(run_status("sed 's/--rk-steps N/--rk-steps K/' " + readme + " > " + changed) == 0);
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
  CHECK(run_status(kVpm + " map in.vtu -o out.vtu --method fast 2> " + err) == 2);
  CHECK_THAT(slurp(err), Catch::Contains("option --method: volume map method 'fast' is not one of moser, paper, vsem"));
  CHECK(run_status(kVpm + " no-such-command 2> " + err) == 2);
  CHECK(run_status(kVpm + " > " + tmp("usage.txt") + " 2>&1") == 2);  // no command: usage, exit 2
  CHECK_THAT(slurp(tmp("usage.txt")), Catch::Contains("vpm map MESH -o OUT"));
  const std::string ver = tmp("version.txt");
  CHECK(run_status(kVpm + " --version > " + ver) == 0);
  CHECK(slurp(ver) == std::string("vpm ") + VPM_VERSION + "\n");
}
