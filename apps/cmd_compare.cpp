// vpm compare: a patient's subject table against the normals' (vpm/statistics.hpp), optionally
// mapped back to the patient's native space (vpm/map_back.hpp).
#include <map>
#include <optional>
#include <sstream>

#include "cli.hpp"
#include "compare_options.hpp"
#include "vpm/calibration.hpp"
#include "vpm/covariates.hpp"
#include "vpm/json.hpp"
#include "vpm/error.hpp"
#include "vpm/format.hpp"
#include "vpm/io.hpp"
#include "vpm/label_names.hpp"
#include "vpm/map_back.hpp"
#include "vpm/statistics.hpp"

namespace {

// "<out without .tsv><suffix>"
std::string beside(const std::string& tsv, const std::string& suffix) {
  const std::string side = vpm::sidecar_path(tsv);
  return side.substr(0, side.size() - 5) + suffix;
}

// --min-cluster-from CAL.json: the min_cluster (and peak level, when calibrated) a calibration of
// these normals found (vpm calibrate), refused when it was made with other options.
// A TFCE calibration sets the TFCE level (and `rule` keeps its null for the foci's p-values).
vpm::CompareOptions options_with_calibration(const vpm::cli::Args& args, const vpm::CalibrationSettings& s,
                                             const std::vector<std::string>& normals, vpm::CalibratedRule& rule) {
  vpm::CompareOptions o = s.compare;
  const auto from = args.get("--min-cluster-from");
  if (!from) return o;
  if (args.has("--min-cluster")) throw vpm::InputError("options --min-cluster and --min-cluster-from exclude each other");
  rule = vpm::calibrated_rule(vpm::read_json_file(*from), s, normals, *from);
  o.min_cluster = rule.min_cluster;
  o.peak = rule.peak;
  if (rule.tfce_level > 0) {
    if (args.has("--tfce-level"))
      throw vpm::InputError("option --tfce-level: " + *from + " is a TFCE calibration; it sets the level");
    o.tfce_level = rule.tfce_level;
  }
  return o;
}

// --mesh / --image: the result on the patient's native mesh (.vtu) and image grid (NIfTI);
// `names` the --label-names table (read before the comparison: a bad one stops it first).
void map_back(const vpm::cli::Args& args, const std::string& out, const vpm::CanonicalElements& el,
              const vpm::Comparison& c, const std::optional<std::map<int, std::string>>& names) {
  const auto mesh_path = args.get("--mesh");
  if (!mesh_path) return;

  const vpm::TetMesh reg = vpm::read_mesh(*mesh_path);
  std::vector<double> focus(c.cluster.begin(), c.cluster.end());
  vpm::write_mesh(beside(out, "_native.vtu"), vpm::native_mesh_with_values(reg, el, {c.z, focus}, {"z", "focus"}));
  if (const auto image_path = args.get("--image")) {
    const vpm::Image grid = vpm::read_image(*image_path);
    vpm::write_nifti(beside(out, "_z.nii.gz"), vpm::native_volume(reg, el, c.z, grid));
    const vpm::Image foci = vpm::native_volume(reg, el, focus, grid);
    vpm::write_nifti(beside(out, "_foci.nii.gz"), foci);
    std::optional<vpm::Image> labels;
    if (const auto labels_path = args.get("--labels")) labels = vpm::read_image(*labels_path);
    vpm::write_native_foci(beside(out, "_foci.tsv"),
                           vpm::native_foci(foci, c, labels ? &*labels : nullptr, names ? &*names : nullptr));
  }
}

int run(const vpm::cli::Command& self, const std::vector<std::string>& argv) {
  vpm::cli::Args args(argv, self);
  args.expect_positional(0, vpm::cli::synopsis(self));
  const auto out = args.get("-o");
  const auto patient_path = args.get("--patient");
  if (!out || (!args.has("--normals") && !args.has("--reference")) || !patient_path || !args.has("--feature"))
    throw vpm::InputError("needs -o, --normals (or --reference), --patient and --feature; usage: " + vpm::cli::synopsis(self));
  if (args.has("--normals") && args.has("--reference"))
    throw vpm::InputError("options --normals and --reference exclude each other (the reference's sums name its normals)");
  const vpm::CalibrationSettings settings = vpm::cli::comparison_settings(args);
  if (args.has("--image") && !args.has("--mesh"))
    throw vpm::InputError("option --image needs --mesh (the patient's registered mesh)");
  if (args.has("--labels") && !args.has("--image")) throw vpm::InputError("option --labels needs --image");
  if (args.has("--label-names") && !args.has("--labels"))
    throw vpm::InputError("option --label-names needs --labels (the atlas whose regions it names)");
  std::optional<std::map<int, std::string>> names;
  if (const auto names_path = args.get("--label-names")) names = vpm::read_label_names(*names_path);
  const std::optional<vpm::Covariates> cov = vpm::cli::read_participants(args, settings);
  const vpm::cli::LoadedReference loaded =
      vpm::cli::load_reference(args, vpm::cli::reference_recipe(settings, cov), cov, 3);
  const vpm::CanonicalElements& el = *loaded.elements;
  vpm::CalibratedRule rule;
  const vpm::CompareOptions opt = options_with_calibration(args, settings, loaded.sums.normals(), rule);
  const vpm::Reference ref = loaded.sums.reference(&el, settings.shrinkage);
  vpm::ElementTable patient = vpm::read_subject_table(*patient_path);
  const std::vector<double> row = cov ? vpm::covariate_row(*cov, patient.subject, *patient_path) : std::vector<double>{};
  patient.subject = *patient_path;
  vpm::Comparison c = vpm::compare_to_reference(el, ref, patient, opt, row);
  vpm::family_p_values(c, rule);
  map_back(args, *out, el, c, names);  // first: OUT.tsv, written last, marks a complete run
  vpm::write_comparison(*out, el, ref, loaded.sums.normals(), *patient_path, opt, c);
  const std::string rule_text = opt.tfce_level > 0 ? "TFCE score >= " + vpm::format_sig(opt.tfce_level)
                                                    : "|z| >= " + std::to_string(c.threshold_used) + ", clusters of >= " +
                                                          std::to_string(opt.min_cluster) + " elements";
  vpm::cli::info("wrote " + *out + ": " + std::to_string(c.clusters.size()) + " foci (" + rule_text + ") against " +
                 std::to_string(ref.subjects) + " normals");
  return 0;
}

// The shared comparison rows, then --min-cluster or --min-cluster-from, then `rest`.
std::vector<vpm::cli::OptionSpec> with_shared_rows(std::vector<vpm::cli::OptionSpec> rest) {
  std::vector<vpm::cli::OptionSpec> rows = vpm::cli::comparison_option_rows();
  rows.insert(rows.begin() + 3,
              {{"--min-cluster", "C", "foci are clusters of at least C adjacent elements (default 3)", false, 1},
               {"--min-cluster-from", "CAL.json", "the min_cluster (and peak level) a calibration of these normals found (vpm calibrate)", false, 1}});
  rows.push_back({"--tfce-level", "T", "threshold-free cluster enhancement: foci are the connected elements whose TFCE score reaches T (a calibration with --tfce sets it; default off)", false, 0, false, true});
  rows.insert(rows.end(), rest.begin(), rest.end());
  return rows;
}

vpm::cli::Registrar reg(
    {"compare", "--patient P.h5 --feature NAME -o OUT.tsv",
     "a patient's element table against the normals: z-scores, foci, and both on the patient's brain",
     with_shared_rows({
      {"--mesh", "REGISTERED.vtu", "the patient's registered mesh: writes OUT_native.vtu with fields z, focus"},
      {"--image", "IMAGE.nii[.gz]", "with --mesh: OUT_z.nii.gz, OUT_foci.nii.gz on this image's grid and the foci table OUT_foci.tsv (mm^3, centroid)"},
      {"--labels", "ATLAS.nii[.gz]", "with --image: the patient's atlas labels; OUT_foci.tsv gives each focus's main region"},
      {"--label-names", "NAMES.txt", "with --labels: its region names for OUT_foci.tsv (AAL's aal.nii.txt or a FreeSurfer colour table)"},
      {"--normals", "A.h5,B.h5,...|@LIST", "the normals' subject tables (vpm sample), at least 3, summed in one pass", true, 2},
      {"--reference", "SUMS.h5", "the normals' sums written by vpm reference instead", true, 2},
      {"--patient", "P.h5", "the patient's subject table", true, 0, true},
      {"--feature", "NAME", "the feature compared (a NAME of vpm sample --images)", true, 0, true}}),
     run});

}  // namespace
