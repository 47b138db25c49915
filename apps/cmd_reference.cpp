// vpm reference: the normals' sufficient statistics in one streaming pass, or the merge of several
// such sums (vpm/reference_sums.hpp): a cluster builds a reference as a map-reduce.
#include <sstream>

#include "cli.hpp"
#include "compare_options.hpp"
#include "vpm/error.hpp"
#include "vpm/reference_sums.hpp"

namespace {

// --merge A.h5,B.h5,...: the sums read and added in the order given.
vpm::ReferenceSums merged(const std::string& list) {
  std::vector<std::string> paths;
  std::stringstream ss(list);
  std::string item;
  while (std::getline(ss, item, ','))
    if (!item.empty()) paths.push_back(item);
  if (paths.empty()) throw vpm::InputError("option --merge: names no sums");
  vpm::ReferenceSums sums = vpm::read_reference_sums(paths[0]);
  for (size_t i = 1; i < paths.size(); ++i) {
    try {
      sums.merge(vpm::read_reference_sums(paths[i]));
    } catch (const vpm::InputError& e) {
      throw vpm::InputError(paths[i] + " into " + paths[0] + ": " + e.what());
    }
    vpm::cli::progress("merged " + std::to_string(i + 1) + " of " + std::to_string(paths.size()) + " sums");
  }
  return sums;
}

int run(const vpm::cli::Command& self, const std::vector<std::string>& argv) {
  vpm::cli::Args args(argv, self);
  args.expect_positional(0, vpm::cli::synopsis(self));
  const auto out = args.get("-o");
  if (!out) throw vpm::InputError("missing -o SUMS.h5; usage: " + vpm::cli::synopsis(self));
  if (args.has("--merge") == args.has("--normals"))
    throw vpm::InputError("give either --normals (sum tables) or --merge (add sums); usage: " + vpm::cli::synopsis(self));
  vpm::ReferenceSums sums = [&] {
    if (const auto list = args.get("--merge")) {
      for (const char* recipe_flag : {"--feature", "--normalisation", "--smooth", "--image-covariate", "--covariates", "--participants"})
        if (args.has(recipe_flag))
          throw vpm::InputError(std::string("option ") + recipe_flag + ": not taken with --merge (the sums carry their recipe)");
      return merged(*list);
    }
    if (!args.has("--feature")) throw vpm::InputError("needs --feature; usage: " + vpm::cli::synopsis(self));
    const vpm::CalibrationSettings s = vpm::cli::comparison_settings(args);
    const std::optional<vpm::Covariates> cov = vpm::cli::read_participants(args, s);
    return std::move(vpm::cli::load_reference(args, vpm::cli::reference_recipe(s, cov), cov, 1).sums);
  }();
  vpm::write_reference_sums(*out, sums);
  vpm::cli::info("wrote " + *out + ": the sums of " + std::to_string(sums.normals().size()) + " normals' " +
                 sums.recipe().feature + " over " + std::to_string(sums.definition().elements()) + " elements (" +
                 std::to_string(sums.stride()) + " values each)");
  return 0;
}

vpm::cli::Registrar reg(
    {"reference", "-o SUMS.h5",
     "the normals' reference as sums that merge: one streaming pass over their tables, or the merge of sums of disjoint groups",
     {{"--normals", "A.h5,B.h5,...|@LIST", "the normals' subject tables (vpm sample) to sum", true, 1},
      {"--merge", "A.h5,B.h5,...", "sums of disjoint groups of normals (vpm reference) to add", true, 1},
      {"--feature", "NAME", "the feature (a NAME of vpm sample --images)"},
      {"--normalisation", "proportional|none", "per-subject scaling to the global mean (default proportional)"},
      {"--smooth", "R", "average every subject's feature over R rings of adjacent elements first (default 0)"},
      {"--image-covariate", "NAME", "sum the subjects' own feature NAME per element too, a covariate of the model"},
      {"--covariates", "NAME,...", "sum the participant covariates of the model (e.g. age,sex)"},
      {"--participants", "TABLE.tsv", "with --covariates: the table with participant_id and those columns"}},
     run});

}  // namespace
