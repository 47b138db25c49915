// vpm view RESULTS -o PAGE.html: the cohort's coordinated table of brains as one web page
// (vpm/cohort_view.hpp reads the cohort, vpm/view_page.hpp writes the page; docs/view.md).
#include "cli.hpp"
#include "vpm/cohort_view.hpp"
#include "vpm/format.hpp"
#include "vpm/timing.hpp"
#include "vpm/view_page.hpp"

namespace {

int run(const vpm::cli::Command& self, const std::vector<std::string>& argv) {
  vpm::cli::Args args(argv, self);
  args.expect_positional(1, vpm::cli::synopsis(self));
  const auto out = args.get("-o");
  if (!out) throw vpm::InputError("missing -o PAGE.html; usage: " + vpm::cli::synopsis(self));
  if (!vpm::view_page_available())
    throw vpm::InputError("this vpm was built without the browser view (web/ needs Node.js and its npm packages at "
                          "build time): run scripts/setup.sh, then rebuild");
  vpm::CohortViewOptions opt;
  opt.feature = args.get("--feature", "");
  opt.template_mesh = args.get("--template", "");
  opt.label_names = args.get("--label-names", "");
  opt.title = args.get("--title", "");
  opt.max_slice_voxels = args.get_int("--max-slice-voxels", static_cast<int>(opt.max_slice_voxels));
  if (opt.max_slice_voxels < 1000) throw vpm::InputError("option --max-slice-voxels: must be >= 1000");
  opt.max_display_level = args.get_int("--display-level", opt.max_display_level);
  if (opt.max_display_level < 0 || opt.max_display_level > 7)
    throw vpm::InputError("option --display-level: must be 0..7");
  vpm::ViewPageOptions page;
  page.data = vpm::cli::parse_option("--data", [&] { return vpm::parse_view_data(args.get("--data", "auto")); });
  const auto t0 = vpm::Clock::now();
  const vpm::CohortView view = vpm::load_cohort_view(args.positional()[0], opt);
  const vpm::ViewPageStats st = vpm::write_view_page(*out, view, page);
  int patients = 0;
  for (const auto& s : view.subjects) patients += s.patient;
  vpm::cli::info("wrote " + *out + ": " + std::to_string(patients) + " patients, " +
                 std::to_string(view.subjects.size() - patients) + " normals, " + std::to_string(view.features.size()) +
                 " feature(s), " + vpm::strprintf("%.1f MB", st.bytes / 1e6) + " (data " +
                 vpm::strprintf("%.1f MB", st.data_bytes / 1e6) + " in " + std::to_string(st.chunks) + " chunks" +
                 (st.data_dir.empty() ? std::string(" inside the page") : ", the folder " + st.data_dir + " beside it") + "), " +
                 vpm::strprintf("%.1f s", vpm::seconds_since(t0)) + "; open it in a browser");
  return 0;
}

vpm::cli::Registrar reg(
    {"view", "RESULTS -o PAGE.html", "the cohort's coordinated table of brains as a web page (one file, or a page and its data folder)",
     {{"--feature", "NAME", "only this feature (default: every feature compared)"},
      {"--template", "TEMPLATE.vtu", "the template's ball mesh naming atlas regions (default RESULTS/template/template_ball.vtu)"},
      {"--label-names", "NAMES.txt", "region names: AAL's table (lines 'id name', e.g. mricron's aal.nii.txt) or a FreeSurfer colour table (FreeSurferColorLUT.txt)"},
      {"--title", "TEXT", "the page's title"},
      {"--display-level", "L", "tables of a finer level are drawn at level L, each element the mean of the finer ones inside it (default 5)"},
      {"--max-slice-voxels", "N", "patients' images are subsampled to at most N voxels for slices (default 400000)"},
      {"--data", "auto|file|folder", "the data inside the page, or in PAGE_data/ beside it, read a row at a time (default auto: a folder above 120 subjects or about 100 MB of data)"}},
     run});

}  // namespace
