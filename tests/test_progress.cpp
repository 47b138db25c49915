// Long work shows where it is and honours a time budget (docs/robustness.md): the Deadline of
// vpm/timing.hpp in the initial map, the volume map and the dense registration; `vpm map
// --max-seconds` (the map reached so far, "converged": false, exit 4); progress lines in logs.
#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "support/fixtures.hpp"
#include "support/process.hpp"
#include "support/shapes.hpp"
#include "vpm/device.hpp"
#include "vpm/error.hpp"
#include "vpm/initial_map.hpp"
#include "vpm/io.hpp"
#include "vpm/json.hpp"
#include "vpm/timing.hpp"
#include "vpm/volume_map.hpp"

using namespace vpm;
using vpm::test::run_status;
using vpm::test::slurp;
namespace fs = std::filesystem;

namespace {
std::string tmp(const std::string& name) { return std::string(VPM_TEST_TMP) + "/progress_" + name; }
const std::string kVpm = VPM_BINARY;

Deadline already_passed() {
  Deadline d;
  d.at = Clock::now() - std::chrono::seconds(1);
  return d;
}

size_t count(const std::string& text, const std::string& what) {
  size_t n = 0;
  for (size_t p = text.find(what); p != std::string::npos; p = text.find(what, p + 1)) ++n;
  return n;
}
}  // namespace

TEST_CASE("Deadline: none by default, passes, counts down") {
  CHECK_FALSE(Deadline{}.set());
  CHECK_FALSE(Deadline{}.passed());
  CHECK_FALSE(Deadline::in_seconds(0).set());
  CHECK_FALSE(Deadline::in_seconds(-1).set());
  const Deadline d = Deadline::in_seconds(100);
  CHECK(d.set());
  CHECK_FALSE(d.passed());
  CHECK(d.remaining() > 99);
  CHECK(d.remaining() <= 100);
  CHECK(already_passed().passed());
  CHECK(already_passed().remaining() == 0);
}

TEST_CASE("volume map: a spent budget stops the rounds with the map so far, and a distant one changes nothing") {
  const auto host = Device::host();
  const TetMesh in = test::ellipsoid_mesh(4);
  const InitialMapResult im = initial_map(*host, in);
  VolumeMapOptions o;
  Points free_run = im.ball;
  const VolumeMapResult full = volume_preserving_map(*host, im.mesh.vertices, im.mesh.tets, free_run, o);
  REQUIRE(!full.rounds.empty());

  o.deadline = already_passed();
  Points cut = im.ball;
  const VolumeMapResult r = volume_preserving_map(*host, im.mesh.vertices, im.mesh.tets, cut, o);
  CHECK(r.stop_reason == "time_budget");
  CHECK(r.rounds.empty());
  CHECK((cut - im.ball).cwiseAbs().maxCoeff() < 1e-12);  // only projected: the initial map is the result
  CHECK(r.final_folds == 0);

  o.deadline = Deadline::in_seconds(3600);
  Points later = im.ball;
  const VolumeMapResult same = volume_preserving_map(*host, im.mesh.vertices, im.mesh.tets, later, o);
  CHECK(same.stop_reason == full.stop_reason);
  CHECK(later == free_run);  // bit for bit: the checks do not change the arithmetic
}

TEST_CASE("initial map: a budget spent while folds remain fails and says so") {
  const auto host = Device::host();
  const TetMesh in = test::ellipsoid_mesh(8);  // slivers near the rim: the harmonic map folds
  InitialMapOptions opt;
  opt.deadline = already_passed();
  try {
    initial_map(*host, in, opt);
    FAIL("a folded map was returned");
  } catch (const NumericalError& e) {
    CHECK_THAT(e.what(), Catch::Contains("cut short by the time budget") && Catch::Contains("folded"));
  }
}

TEST_CASE("vpm map --max-seconds: the map reached is written, converged false, exit 4") {
  write_mesh(tmp("in.vtu"), test::ball_mesh(6));  // its harmonic map is fold-free: no untangling
  const std::string out = tmp("out.vtu"), report = tmp("report.json"), err = tmp("err.txt");
  fs::remove(out);
  // a budget spent before the rounds: the initial map (fold-free, far from the tolerance) is written
  CHECK(run_status(kVpm + " map " + tmp("in.vtu") + " -o " + out + " --max-seconds 0.000001 --report " + report +
                   " --quiet 2> " + err) == kExitNotConverged);
  CHECK(fs::exists(out));
  const Json j = Json::parse(slurp(report));
  CHECK_FALSE(j.find("converged")->boolean());
  CHECK(j.find("convergence")->find("reason")->string() == "time_budget");
  CHECK(j.find("final")->find("inverted_tets")->number() == 0);
  CHECK_THAT(slurp(err), Catch::Contains("vpm map: warning: not converged: the time budget (--max-seconds) ran out at "
                                         "vertex mean |r-1|") && Catch::Contains("exit status 4"));
  CHECK(read_mesh(out).num_tets() > 0);
  // --allow-partial: exit 0, the warning stays
  CHECK(run_status(kVpm + " map " + tmp("in.vtu") + " -o " + out + " --max-seconds 0.000001 --allow-partial --quiet 2> " +
                   err) == 0);
  CHECK_THAT(slurp(err), Catch::Contains("time budget"));
  // an ample budget: as without one
  CHECK(run_status(kVpm + " map " + tmp("in.vtu") + " -o " + out + " --max-seconds 600 --report " + report +
                   " --quiet 2> " + err) == 0);
  CHECK(Json::parse(slurp(report)).find("converged")->boolean());
  // a budget spent while the harmonic map is folded: no valid map, exit 3, nothing written
  write_mesh(tmp("folding.vtu"), test::ellipsoid_mesh(8));
  fs::remove(out);
  CHECK(run_status(kVpm + " map " + tmp("folding.vtu") + " -o " + out + " --max-seconds 0.000001 2> " + err) ==
        kExitNumerical);
  CHECK_FALSE(fs::exists(out));
  CHECK_THAT(slurp(err), Catch::Contains("cut short by the time budget"));
  // nonsense is refused naming the flag
  CHECK(run_status(kVpm + " map " + tmp("in.vtu") + " -o " + out + " --max-seconds 0 2> " + err) == kExitInput);
  CHECK_THAT(slurp(err), Catch::Contains("option --max-seconds: must be > 0"));
}

TEST_CASE("vpm map in a log: stage and round lines with seconds, none for a short run by default") {
  write_mesh(tmp("log_in.vtu"), test::ellipsoid_mesh(4));
  const std::string out = tmp("log_out.vtu"), log = tmp("log.txt");
  // every line (VPM_PROGRESS_SECONDS=0): the initial map's steps and every round, each stamped
  REQUIRE(run_status("VPM_PROGRESS_SECONDS=0 " + kVpm + " map " + tmp("log_in.vtu") + " -o " + out + " 2> " + log) == 0);
  const std::string text = slurp(log);
  INFO(text);
  for (const char* line : {"s] read ", "s] initial map: split: ", "s] initial map: sphere map: ",
                           "s] initial map: harmonic interior: ", "s] moser round 1/", "s] polish 1/"})
    CHECK(count(text, line) == 1);
  CHECK(text.find('\r') == std::string::npos);  // plain lines, no terminal rewriting
  // the default interval (10 s) prints nothing of a run this short but its result
  REQUIRE(run_status(kVpm + " map " + tmp("log_in.vtu") + " -o " + out + " 2> " + log) == 0);
  const std::string quiet = slurp(log);
  CHECK(quiet.find("round") == std::string::npos);
  CHECK_THAT(quiet, Catch::StartsWith("wrote "));
}

TEST_CASE("vpm map in a log: a step that runs on is named while it runs") {
  // one long Moser round (4,000 RK4 steps, seconds) and progress every 0.1 s: after 0.75 s
  // the watcher prints a "still working" line naming the last step reported
  write_mesh(tmp("long_in.vtu"), test::ellipsoid_mesh(10));
  const std::string log = tmp("long.txt");
  REQUIRE(run_status("VPM_PROGRESS_SECONDS=0.1 " + kVpm + " map " + tmp("long_in.vtu") + " -o " + tmp("long_out.vtu") +
                     " --rounds 1 --rk-steps 4000 2> " + log) == 0);
  const std::string text = slurp(log);
  INFO(text);
  CHECK(count(text, "] still working, ") >= 1);
}
