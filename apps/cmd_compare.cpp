// vpm compare: a patient's subject table against the normals' (vpm/statistics.hpp), optionally
// mapped back to the patient's native space (vpm/map_back.hpp).
#include <optional>
#include <sstream>

#include "cli.hpp"
#include "vpm/error.hpp"
#include "vpm/io.hpp"
#include "vpm/map_back.hpp"
#include "vpm/statistics.hpp"

namespace {

std::vector<std::string> comma_list(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  std::string item;
  while (std::getline(ss, item, ','))
    if (!item.empty()) out.push_back(item);
  return out;
}

// "<out without .tsv><suffix>"
std::string beside(const std::string& tsv, const std::string& suffix) {
  const std::string side = vpm::sidecar_path(tsv);
  return side.substr(0, side.size() - 5) + suffix;
}

vpm::CompareOptions compare_options(const vpm::cli::Args& args) {
  vpm::CompareOptions o;
  o.threshold = args.get_double("--threshold", o.threshold);
  if (!(o.threshold > 0)) throw vpm::InputError("option --threshold: must be positive");
  o.fdr_q = args.get_double("--fdr", 0);
  if (o.fdr_q < 0 || o.fdr_q >= 1) throw vpm::InputError("option --fdr: must be in (0, 1)");
  o.min_cluster = args.get_int("--min-cluster", o.min_cluster);
  o.extend = args.get_double("--extend", 0);
  if (o.extend < 0) throw vpm::InputError("option --extend: must be positive (or 0: off)");
  o.test = vpm::cli::parse_option("--test", [&] { return vpm::parse_single_case_test(args.get("--test", "z")); });
  o.peak = args.get_double("--peak", 0);
  if (o.peak < 0) throw vpm::InputError("option --peak: must be positive (or 0: off)");
  if (o.min_cluster < 1) throw vpm::InputError("option --min-cluster: must be >= 1");
  const std::string sign = args.get("--sign", "both");
  if (sign == "both") o.sign = 0;
  else if (sign == "hyper") o.sign = 1;
  else if (sign == "hypo") o.sign = -1;
  else throw vpm::InputError("option --sign: '" + sign + "' is not one of both, hyper, hypo");
  return o;
}

// --mesh / --image: the result on the patient's native mesh (.vtu) and image grid (NIfTI).
void map_back(const vpm::cli::Args& args, const std::string& out, const vpm::CanonicalElements& el,
              const vpm::Comparison& c) {
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
    vpm::write_native_foci(beside(out, "_foci.tsv"), vpm::native_foci(foci, c, labels ? &*labels : nullptr));
  }
}

int run(const vpm::cli::Command& self, const std::vector<std::string>& argv) {
  vpm::cli::Args args(argv, self);
  args.expect_positional(0, "usage: " + vpm::cli::synopsis(self));
  const auto out = args.get("-o");
  const auto normals_arg = args.get("--normals");
  const auto patient_path = args.get("--patient");
  const auto feature = args.get("--feature");
  if (!out || !normals_arg || !patient_path || !feature)
    throw vpm::InputError("needs -o, --normals, --patient and --feature; usage: " + vpm::cli::synopsis(self));
  const vpm::Normalisation norm = vpm::cli::parse_option(
      "--normalisation", [&] { return vpm::parse_normalisation(args.get("--normalisation", "proportional")); });
  const vpm::CompareOptions opt = compare_options(args);
  if (args.has("--image") && !args.has("--mesh"))
    throw vpm::InputError("option --image needs --mesh (the patient's registered mesh)");
  if (args.has("--labels") && !args.has("--image")) throw vpm::InputError("option --labels needs --image");
  const std::vector<std::string> normal_paths = comma_list(*normals_arg);
  std::vector<vpm::ElementTable> normals;
  for (const std::string& p : normal_paths) normals.push_back(vpm::read_subject_table(p));
  const int smoothing = args.get_int("--smooth", 0);
  if (smoothing < 0 || smoothing > 8) throw vpm::InputError("option --smooth: must be in 0..8");
  if (normals.size() < 3) throw vpm::InputError("option --normals: needs at least 3 tables, got " + std::to_string(normals.size()));
  const vpm::CanonicalElements el(normals[0].definition);
  const vpm::Reference ref = vpm::build_reference(el, normals, normal_paths, *feature, norm, smoothing);
  vpm::ElementTable patient = vpm::read_subject_table(*patient_path);
  patient.subject = *patient_path;
  const vpm::Comparison c = vpm::compare_to_reference(el, ref, patient, opt);
  map_back(args, *out, el, c);  // first: OUT.tsv, written last, marks a complete run
  vpm::write_comparison(*out, el, ref, normal_paths, *patient_path, opt, c);
  vpm::cli::info("wrote " + *out + ": " + std::to_string(c.clusters.size()) + " foci (|z| >= " +
                 std::to_string(c.threshold_used) + ", clusters of >= " + std::to_string(opt.min_cluster) +
                 " elements) against " + std::to_string(ref.subjects) + " normals");
  return 0;
}

vpm::cli::Registrar reg(
    {"compare", "--normals A.tsv,B.tsv,... --patient P.tsv --feature NAME -o OUT.tsv",
     "a patient's element table against the normals: z-scores, foci, and both on the patient's brain",
     {{"--normalisation", "proportional|none", "per-subject scaling to the global mean (default proportional)"},
      {"--threshold", "Z", "|z| of a focus element (default 3)"},
      {"--fdr", "Q", "Benjamini-Hochberg false discovery rate instead of --threshold"},
      {"--min-cluster", "C", "foci are clusters of at least C adjacent elements (default 3)"},
      {"--smooth", "R", "average every subject's feature over R rings of adjacent elements first (default 0)"},
      {"--extend", "Z2", "grow each focus into adjacent elements with |z| >= Z2 (hysteresis; default off)"},
      {"--test", "z|crawford-howell", "plain z, or Crawford-Howell's t for one case against n normals as the equivalent z (default z)"},
      {"--peak", "ZP", "a cluster smaller than --min-cluster is a focus too when its peak |z| >= ZP (default off)"},
      {"--sign", "both|hyper|hypo", "increases, decreases or both (default both)"},
      {"--mesh", "REGISTERED.vtu", "the patient's registered mesh: writes OUT_native.vtu with fields z, focus"},
      {"--image", "IMAGE.nii[.gz]", "with --mesh: OUT_z.nii.gz, OUT_foci.nii.gz on this image's grid and the foci table OUT_foci.tsv (mm^3, centroid)"},
      {"--labels", "ATLAS.nii[.gz]", "with --image: the patient's atlas labels; OUT_foci.tsv names each focus's main region"},
      {"--normals", "A.tsv,B.tsv,...", "the normals' subject tables (vpm sample), at least 3", true, 0, true},
      {"--patient", "P.tsv", "the patient's subject table", true, 0, true},
      {"--feature", "NAME", "the feature compared (a NAME of vpm sample --images)", true, 0, true}},
     run});

}  // namespace
