// vpm elements -o ELEMENTS.tsv: the canonical volume elements of the ball (vpm/elements.hpp).
#include "cli.hpp"
#include "element_options.hpp"
#include "vpm/elements.hpp"
#include "vpm/format.hpp"

namespace {

int run(const vpm::cli::Command& self, const std::vector<std::string>& argv) {
  vpm::cli::Args args(argv, self);
  args.expect_positional(0, vpm::cli::synopsis(self));
  const auto out = args.get("-o");
  if (!out) throw vpm::InputError("missing -o ELEMENTS.tsv; usage: " + vpm::cli::synopsis(self));
  const vpm::ElementDefinition d = vpm::cli::element_definition(args);
  const vpm::CanonicalElements el(d);
  vpm::write_element_table(*out, el);
  const vpm::ElementVolumeStats st = el.volume_stats();
  vpm::cli::info("wrote " + *out + " and " + vpm::sidecar_path(*out) + ": " + std::to_string(el.size()) +
                 " elements (" + vpm::to_string(d.layout) + ": " + std::to_string(d.shells) + " shells, " +
                 std::to_string(el.shell_triangles(0)) + " to " + std::to_string(el.triangles()) + " triangles), volume min/mean " + vpm::strprintf("%.3f", st.min / st.mean) + ", max/mean " +
                 vpm::strprintf("%.3f", st.max / st.mean) + ", std " + vpm::pct(st.std_relative) + " of the mean");
  return 0;
}

vpm::cli::Registrar reg({"elements", "-o ELEMENTS.tsv", "the canonical volume elements of the ball and their table",
                         {{"--level", "L", "icosphere subdivisions: 20 x 4^L triangles (default 3)"},
                          {"--shells", "K", "equal-volume radial shells (default 8; layout shells)"},
                          {"--layout", "shells|graded", "shells: level L in each of K shells (default); graded: near-cubic elements, coarser levels inward, K from L"},
                          {"--samples", "S", "sample points per element (default 64)"}},
                         run});

}  // namespace
