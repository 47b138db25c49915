// vpm calibrate: the cluster size (min_cluster) at which the normals, each compared with the
// others, show at most a stated rate of false foci (vpm/calibration.hpp).
#include "cli.hpp"
#include "compare_options.hpp"
#include "vpm/calibration.hpp"
#include "vpm/error.hpp"
#include "vpm/format.hpp"
#include "vpm/json.hpp"

namespace {

int run(const vpm::cli::Command& self, const std::vector<std::string>& argv) {
  vpm::cli::Args args(argv, self);
  args.expect_positional(0, vpm::cli::synopsis(self));
  const auto out = args.get("-o");
  if (!out || !args.has("--normals") || !args.has("--feature"))
    throw vpm::InputError("needs -o, --normals and --feature; usage: " + vpm::cli::synopsis(self));
  if (args.has("--min-cluster"))
    throw vpm::InputError("option --min-cluster: not taken (it is what vpm calibrate finds)");
  vpm::CalibrationSettings s = vpm::cli::comparison_settings(args, true);
  s.rate = args.get_double("--rate", 1.0);
  s.calibrate_tfce = args.has("--tfce");
  if (s.calibrate_tfce && args.has("--peak"))
    throw vpm::InputError("options --tfce and --peak exclude each other (a TFCE focus has no peak rule)");
  if (!(s.rate >= 0)) throw vpm::InputError("option --rate: must be >= 0 false clusters per 10 normals");
  const std::optional<vpm::Covariates> cov = vpm::cli::read_participants(args, s);
  const vpm::ReferenceRecipe recipe = vpm::cli::reference_recipe(s, cov);
  const vpm::cli::LoadedReference loaded = vpm::cli::load_reference(args, recipe, cov, 4);
  const vpm::CanonicalElements& el = *loaded.elements;
  // each normal left out is read once more (its values, then taken out of the totals)
  const std::vector<std::string> left_out = vpm::cli::normal_paths(args, 1);
  const vpm::ClusterCalibration c = vpm::calibrate_min_cluster(
      el, loaded.sums, vpm::table_files(left_out, loaded.sums.definition(), recipe, &el, cov ? &*cov : nullptr), s);
  vpm::write_json_file(*out, vpm::to_json(c));
  if (c.min_cluster == 0)
    throw vpm::NumericalError(*out + ": no min_cluster keeps the normals at or under " + vpm::format_sig(s.rate) +
                              " false clusters per 10 normals (reached " + vpm::format_sig(c.rate_at(1 << 30)) +
                              " with clusters of any size: the --peak rule keeps small ones); lower --peak or raise --rate");
  const std::string peak = !s.calibrate_peak ? ""
                           : c.peak > 0 ? ", peak |z| " + vpm::format_sig(c.peak)
                                        : ", no peak level (a normal's peak |z| is infinite: the peak rule is off)";
  const std::string tfce = s.calibrate_tfce ? ", TFCE level " + vpm::format_sig(c.tfce_level) : "";
  vpm::cli::info("wrote " + *out + ": min_cluster " + std::to_string(c.min_cluster) + peak + tfce + " (" +
                 vpm::format_sig(c.rate_at(c.min_cluster)) + " false clusters per 10 normals, at most " +
                 vpm::format_sig(s.rate) + "; min_cluster 1: " + vpm::format_sig(c.rate_at(1)) + ") over " +
                 std::to_string(c.normals) + " normals left out in turn");
  return 0;
}

std::vector<vpm::cli::OptionSpec> rows() {
  std::vector<vpm::cli::OptionSpec> r = vpm::cli::comparison_option_rows(true);
  r.push_back({"--rate", "R", "false clusters allowed per 10 normals (default 1)"});
  r.push_back({"--tfce", "", "also the TFCE level (vpm compare --tfce-level) at which at most R normals in 10 show a focus", false, 0, false, true});
  r.push_back({"--normals", "A.h5,B.h5,...|@LIST", "the normals' subject tables (vpm sample), each left out in turn; at least 4", true, 0, true});
  r.push_back({"--reference", "SUMS.h5", "the sums of every normal (vpm reference; default: summed from --normals in a first pass)"});
  r.push_back({"--feature", "NAME", "the feature compared (a NAME of vpm sample --images)", true, 0, true});
  return r;
}

vpm::cli::Registrar reg({"calibrate", "--normals A.h5,B.h5,... --feature NAME -o CAL.json",
                         "the cluster size (and with --peak auto the peak level) at which the normals, each compared with the others, show at most R false foci per 10",
                         rows(), run});

}  // namespace
