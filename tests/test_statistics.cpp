// Cohort statistics (vpm/statistics.hpp): subject tables round-trip, the reference, z-scores,
// planted foci found as clusters, definitions never mixed, the result mapped back, `vpm compare`.
#include <catch2/catch.hpp>
#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <random>
#include <set>
#include <string>

#include "collective/distributions.hpp"
#include "support/elements.hpp"
#include "support/fixtures.hpp"
#include "support/process.hpp"
#include "vpm/calibration.hpp"
#include "vpm/error.hpp"
#include "vpm/image.hpp"
#include "vpm/io.hpp"
#include "vpm/map_back.hpp"
#include "vpm/statistics.hpp"

using namespace vpm;

namespace {

ElementDefinition def() { return test::small_elements(); }
using test::planted_focus;

// A subject: feature "pet" ~ N(100, 5) * global factor, plus `bump` on the elements of `focus`.
ElementTable subject(unsigned seed, double factor, const std::set<int>& focus = {}, double bump = 0) {
  const CanonicalElements el(def());
  ElementTable t;
  t.definition = def();
  t.subject = "sub-" + std::to_string(seed);
  ElementFeature f;
  f.name = "pet";
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(100, 5);
  for (int e = 0; e < el.size(); ++e) {
    f.mean.push_back(factor * (g(rng) + (focus.count(e) ? bump : 0)));
    f.std.push_back(1);
    f.count.push_back(8);
  }
  t.features.push_back(f);
  return t;
}

}  // namespace

TEST_CASE("statistics: planted foci are found as one cluster, proportional scaling removes global factors") {
  const CanonicalElements el(def());
  std::vector<ElementTable> normals;
  std::vector<std::string> names;
  for (unsigned i = 0; i < 30; ++i) {
    normals.push_back(subject(i + 1, 0.8 + 0.02 * i));  // global uptake differs by subject
    names.push_back("n" + std::to_string(i));
  }
  const Reference ref = build_reference(normals, names, "pet", Normalisation::proportional);
  CHECK(ref.subjects == 30);
  const std::set<int> focus = planted_focus(el, el.id(1, 17));
  REQUIRE(focus.size() == 4);
  const ElementTable patient = subject(999, 1.3, focus, 60);  // +60 % in the focus, another global factor
  const Comparison c = compare_to_reference(el, ref, patient);
  REQUIRE(c.clusters.size() >= 1);
  const FocusCluster& f = c.clusters[0];
  CHECK(f.sign == 1);
  CHECK(std::set<int>(f.elements.begin(), f.elements.end()) == focus);
  CHECK(focus.count(f.peak_element) == 1);
  double vol = 0;
  for (int e : focus) vol += el.volume(e);
  CHECK(f.volume == Approx(vol));
  for (int e = 0; e < el.size(); ++e) CHECK((c.cluster[e] == 1) == (focus.count(e) == 1));
  // without normalisation the subjects' global factors (0.8-1.38) inflate the reference spread
  const Reference raw = build_reference(normals, names, "pet", Normalisation::none);
  double cv_raw = 0, cv_prop = 0;
  for (int e = 0; e < el.size(); ++e) {
    cv_raw += raw.std[e] / raw.mean[e] / el.size();
    cv_prop += ref.std[e] / ref.mean[e] / el.size();
  }
  CHECK(cv_raw > 2.5 * cv_prop);
  // a single outlier is no focus with clusters of >= 3; it is with >= 1
  ElementTable lone = subject(998, 1.0, {el.id(0, 3)}, 80);
  CompareOptions o;
  const Comparison c3 = compare_to_reference(el, ref, lone, o);
  CHECK(c3.cluster[el.id(0, 3)] == 0);
  o.min_cluster = 1;
  const Comparison c1 = compare_to_reference(el, ref, lone, o);
  REQUIRE(!c1.clusters.empty());
  CHECK(c1.cluster[el.id(0, 3)] != 0);
  // FDR: the threshold adapts, the planted focus is still found
  o = {};
  o.fdr_q = 0.05;
  const Comparison cf = compare_to_reference(el, ref, patient, o);
  CHECK(cf.threshold_used > 2);
  REQUIRE(!cf.clusters.empty());
  CHECK(std::set<int>(cf.clusters[0].elements.begin(), cf.clusters[0].elements.end()) == focus);
}

TEST_CASE("statistics: tables with another element definition are refused, subject tables round-trip") {
  std::vector<ElementTable> normals = {subject(1, 1), subject(2, 1), subject(3, 1)};
  normals[2].definition.samples = 16;
  CHECK_THROWS_WITH(build_reference(normals, {"a.tsv", "b.tsv", "c.tsv"}, "pet", Normalisation::none),
                    Catch::Contains("c.tsv") && Catch::Contains("definition differs"));
  CHECK_THROWS_AS(build_reference({subject(1, 1), subject(2, 1)}, {"a", "b"}, "pet", Normalisation::none), InputError);
  CHECK_THROWS_WITH(normalised_feature(subject(1, 1), "fdg", Normalisation::none), Catch::Contains("no feature 'fdg'"));
  const std::string path = std::string(VPM_TEST_TMP) + "/stats_sub.tsv";
  const ElementTable t = subject(5, 1.1);
  write_subject_table(path, t);
  const ElementTable r = read_subject_table(path);
  CHECK(r.definition == t.definition);
  REQUIRE(r.features.size() == 1);
  for (size_t e = 0; e < t.features[0].mean.size(); ++e) CHECK(r.features[0].mean[e] == Approx(t.features[0].mean[e]).epsilon(1e-9));
  // a truncated table is refused with its file and line
  const std::string text = test::slurp(path);
  const std::string cut = std::string(VPM_TEST_TMP) + "/stats_cut.tsv";
  { std::ofstream(cut) << text.substr(0, text.size() / 2); }
  { std::ofstream(std::string(VPM_TEST_TMP) + "/stats_cut.json") << test::slurp(std::string(VPM_TEST_TMP) + "/stats_sub.json"); }
  CHECK_THROWS_WITH(read_subject_table(cut), Catch::Contains("stats_cut.tsv"));
}

TEST_CASE("statistics: the result mapped back onto the native mesh and image grid") {
  TetMesh reg = test::ball_mesh(6);
  FieldValues native = reg.vertices * 50.0;  // native space: the ball scaled to 50 mm
  reg.set_point_field("original_position", native);
  const CanonicalElements el(def());
  std::vector<double> values(el.size());
  for (int e = 0; e < el.size(); ++e) values[e] = el.shell_of(e);  // the shell index
  const TetMesh m = native_mesh_with_values(reg, el, {values}, {"shell"});
  CHECK(m.vertices.isApprox(native));
  const Field* cf = m.find_cell_field("shell");
  REQUIRE(cf);
  for (int t = 0; t < m.num_tets(); ++t) {
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    for (int k = 0; k < 4; ++k) c += 0.25 * reg.vertices.row(reg.tets(t, k)).transpose();
    CHECK(cf->values(t, 0) == el.shell_of(el.element_of(c)));
  }
  Image grid;
  grid.dims = {21, 21, 21};
  grid.spacing = {5, 5, 5};
  grid.affine.setIdentity();
  grid.affine.topLeftCorner<3, 3>() *= 5;
  grid.affine.topRightCorner<3, 1>() = Eigen::Vector3d(-50, -50, -50);
  grid.data.assign(grid.size(), 0);
  const Image z = native_volume(reg, el, values, grid, -1.0f);
  CHECK(z.at(10, 10, 10) == 0.0f);   // the centre: shell 0
  CHECK(z.at(0, 0, 0) == -1.0f);     // a corner outside the ball
  CHECK(z.at(19, 10, 10) == 2.0f);   // 45 mm out: the outer shell (r^3 = 0.73 > 2/3)
}

TEST_CASE("statistics: native foci table: voxel volume, centroid, peak and main atlas region") {
  // a 2 mm grid with two clusters: a 3x3x3 block of id 1 and a 2-voxel bar of id 2
  Image foci;
  foci.dims = {10, 10, 10};
  foci.affine.setIdentity();
  foci.affine.topLeftCorner<3, 3>() *= 2;
  foci.affine.topRightCorner<3, 1>() = Eigen::Vector3d(-10, -10, -10);
  foci.data.assign(foci.size(), 0);
  for (int k = 2; k < 5; ++k)
    for (int j = 2; j < 5; ++j)
      for (int i = 2; i < 5; ++i) foci.data[foci.index(i, j, k)] = 1;
  foci.data[foci.index(7, 7, 7)] = foci.data[foci.index(8, 7, 7)] = 2;
  Comparison c;
  c.clusters.resize(3);
  c.clusters[0].id = 1;
  c.clusters[0].peak_z = -5;
  c.clusters[1].id = 2;
  c.clusters[1].peak_z = -4;
  c.clusters[2].id = 3;  // a cluster with no voxel on this grid
  // labels on a 1 mm grid over the same space: 7 on x < -3 mm, 9 elsewhere
  Image labels;
  labels.dims = {20, 20, 20};
  labels.affine.setIdentity();
  labels.affine.topRightCorner<3, 1>() = Eigen::Vector3d(-10, -10, -10);
  labels.data.assign(labels.size(), 9);
  for (int k = 0; k < 20; ++k)
    for (int j = 0; j < 20; ++j)
      for (int i = 0; i < 7; ++i) labels.data[labels.index(i, j, k)] = 7;
  const std::vector<NativeFocus> f = native_foci(foci, c, &labels);
  REQUIRE(f.size() == 3);
  CHECK(f[0].voxels == 27);
  CHECK(f[0].volume_mm3 == Approx(27 * 8));
  CHECK((f[0].centroid - Eigen::Vector3d(-4, -4, -4)).norm() < 1e-12);  // voxel 3 -> -10 + 6 mm
  CHECK(f[0].peak_z == -5);
  CHECK(f[0].label == 7);  // x = -6, -4 (label 7) and -2 (label 9): 18 of 27
  CHECK(f[0].label_fraction == Approx(18.0 / 27));
  CHECK(f[1].voxels == 2);
  CHECK((f[1].centroid - Eigen::Vector3d(5, 4, 4)).norm() < 1e-12);
  CHECK(f[1].label == 9);
  CHECK(f[1].label_fraction == 1.0);
  CHECK(f[2].voxels == 0);
  CHECK(std::isnan(f[2].centroid(0)));
  CHECK(native_foci(foci, c)[0].label == 0);  // no label image
  // region names from a label table (9 unlisted), the p-values carried; the TSV's last columns
  c.clusters[0].p_family = 1.0 / 16;
  const std::map<int, std::string> names{{7, "Caudate\tL"}, {3, "Thalamus_L"}};
  const std::vector<NativeFocus> named = native_foci(foci, c, &labels, &names);
  CHECK(named[0].region == "Caudate\tL");
  CHECK(named[1].region.empty());
  CHECK(named[0].p_family == 1.0 / 16);
  CHECK(named[1].p_family == -1);
  const std::string tsv = std::string(VPM_TEST_TMP) + "/native_foci.tsv";
  write_native_foci(tsv, named);
  std::ifstream in(tsv);
  std::string header, first, second;
  std::getline(in, header), std::getline(in, first), std::getline(in, second);
  CHECK(header.substr(header.rfind("label_fraction")) == "label_fraction\tregion\tp_family");
  CHECK(first.substr(first.find("\tCaudate")) == "\tCaudate L\t0.0625");  // a tab in a name: a space
  CHECK(second.substr(second.size() - 4) == "\t\tNA");
}

TEST_CASE("statistics: options out of range are refused by the library by name, the command line names the flag") {
  const CanonicalElements el(def());
  const std::vector<ElementTable> normals = {subject(1, 1), subject(2, 1), subject(3, 1)};
  const Reference ref = build_reference(normals, {"a", "b", "c"}, "pet", Normalisation::proportional);
  const ElementTable patient = subject(4, 1);
  const auto refused = [&](auto change) {
    CompareOptions o;
    change(o);
    const auto bad = compare_option_error(o);
    REQUIRE(bad);
    CHECK_THROWS_WITH(compare_to_reference(el, ref, patient, o), Catch::Contains("compare options: " + bad->field));
    return bad->field;
  };
  CHECK(refused([](CompareOptions& o) { o.threshold = 0; }) == "threshold");
  CHECK(refused([](CompareOptions& o) { o.fdr_q = 1; }) == "fdr_q");
  CHECK(refused([](CompareOptions& o) { o.min_cluster = 0; }) == "min_cluster");
  CHECK(refused([](CompareOptions& o) { o.extend = -1; }) == "extend");
  CHECK(refused([](CompareOptions& o) { o.relative_extent = std::nan(""); }) == "relative_extent");
  CHECK(refused([](CompareOptions& o) { o.relative_extent = 1.5; }) == "relative_extent");
  CHECK(refused([](CompareOptions& o) { o.peak = -2; }) == "peak");
  CHECK(refused([](CompareOptions& o) { o.sign = 2; }) == "sign");
  CompareOptions edge;
  edge.relative_extent = 1;
  CHECK(!compare_option_error(edge));
  CHECK_NOTHROW(compare_to_reference(el, ref, patient, edge));
  // the command line words the same check with its flags, exit 2 before reading any table
  const std::string vpm = VPM_BINARY, err = std::string(VPM_TEST_TMP) + "/cmp_range_err.txt";
  for (const auto& [flag, value] : std::vector<std::pair<std::string, std::string>>{
           {"--relative-extent", "1.5"}, {"--fdr", "1"}, {"--min-cluster", "0"}}) {
    CHECK(test::run_status(vpm + " compare --normals a.tsv,b.tsv,c.tsv --patient p.tsv --feature pet -o x.tsv " + flag +
                           " " + value + " 2> " + err) == 2);
    CHECK_THAT(test::slurp(err), Catch::Contains("option " + flag + ":"));
  }
}

TEST_CASE("vpm compare writes z, foci and the patient's native maps, refuses mixed definitions") {
  const std::string dir = std::string(VPM_TEST_TMP) + "/cmp_";
  const CanonicalElements el(def());
  std::string normals;
  for (unsigned i = 0; i < 5; ++i) {
    write_subject_table(dir + "n" + std::to_string(i) + ".tsv", subject(10 + i, 1.0));
    normals += (i ? "," : "") + dir + "n" + std::to_string(i) + ".tsv";
  }
  const std::set<int> focus = planted_focus(el, el.id(2, 40));
  write_subject_table(dir + "p.tsv", subject(77, 1.0, focus, 80));
  TetMesh reg = test::ball_mesh(6);
  reg.set_point_field("original_position", FieldValues(reg.vertices * 50.0));
  write_mesh(dir + "reg.vtu", reg);
  Image grid;
  grid.dims = {11, 11, 11};
  grid.spacing = {10, 10, 10};
  grid.affine.setIdentity();
  grid.affine.topLeftCorner<3, 3>() *= 10;
  grid.affine.topRightCorner<3, 1>() = Eigen::Vector3d(-50, -50, -50);
  grid.data.assign(grid.size(), 1.0f);
  write_nifti(dir + "grid.nii.gz", grid);
  const std::string vpm = VPM_BINARY;
  REQUIRE(test::run_status(vpm + " compare --normals " + normals + " --patient " + dir + "p.tsv --feature pet -o " +
                           dir + "out.tsv --mesh " + dir + "reg.vtu --image " + dir + "grid.nii.gz --quiet") == 0);
  const std::string text = test::slurp(dir + "out.tsv");
  CHECK_THAT(text, Catch::StartsWith("element\tshell\ttriangle\tpatient\treference_mean\treference_std\tz\tcluster\n"));
  const Json side = Json::parse(test::slurp(dir + "out.json"));
  CHECK(side.find("reference")->find("subjects")->number() == 5);
  REQUIRE(side.find("result")->find("clusters")->size() >= 1);
  CHECK(side.find("result")->find("clusters")->at(0).find("elements")->number() >= 4);  // 5 normals: noisy stds
  const TetMesh native = read_mesh(dir + "out_native.vtu");
  CHECK(native.find_point_field("z"));
  CHECK(native.find_cell_field("focus"));
  const Image z = read_nifti(dir + "out_z.nii.gz");
  CHECK(z.dims == grid.dims);
  CHECK(read_nifti(dir + "out_foci.nii.gz").dims == grid.dims);
  CHECK_THAT(test::slurp(dir + "out_foci.tsv"), Catch::StartsWith("focus\tvoxels\tvolume_mm3\tcentroid_x"));
  CHECK(test::run_status(vpm + " compare --normals " + normals + " --patient " + dir + "p.tsv --feature pet -o " +
                         dir + "lab.tsv --labels " + dir + "grid.nii.gz --quiet 2> /dev/null") == 2);
  // a 2 mm grid as its own atlas (label 1 everywhere) with AAL-style names: each focus's region named
  Image fine = grid;
  fine.dims = {51, 51, 51};
  fine.spacing = {2, 2, 2};
  fine.affine.topLeftCorner<3, 3>() = 2 * Eigen::Matrix3d::Identity();
  fine.data.assign(fine.size(), 1.0f);
  write_nifti(dir + "fine.nii.gz", fine);
  {
    std::ofstream names(dir + "names.txt");
    names << "1 Whole_Grid 1001\n2 Other 1002\n";
  }
  const std::string mapped = vpm + " compare --normals " + normals + " --patient " + dir + "p.tsv --feature pet --mesh " +
                             dir + "reg.vtu --image " + dir + "fine.nii.gz --labels " + dir + "fine.nii.gz --quiet";
  REQUIRE(test::run_status(mapped + " --label-names " + dir + "names.txt -o " + dir + "named.tsv") == 0);
  const std::string named = test::slurp(dir + "named_foci.tsv");
  CHECK_THAT(named, Catch::Contains("\t1\t1\tWhole_Grid\tNA\n"));  // label 1, all of it; no calibration: NA
  // names without an atlas, or a table that is not one: exit 2 naming it, before anything is written
  const std::string nerr = dir + "names_err.txt";
  CHECK(test::run_status(vpm + " compare --normals " + normals + " --patient " + dir + "p.tsv --feature pet -o " + dir +
                         "nolab.tsv --label-names " + dir + "names.txt 2> " + nerr) == 2);
  CHECK_THAT(test::slurp(nerr), Catch::Contains("--label-names needs --labels"));
  {
    std::ofstream names(dir + "bad_names.txt");
    names << "1 Whole_Grid 1001\none Other\n";
  }
  CHECK(test::run_status(mapped + " --label-names " + dir + "bad_names.txt -o " + dir + "badnames.tsv 2> " + nerr) == 2);
  CHECK_THAT(test::slurp(nerr), Catch::Contains("bad_names.txt:2"));
  CHECK(test::run_status("test -e " + dir + "badnames_native.vtu") == 1);
  // another element definition among the normals: exit 2, nothing written
  ElementTable other = subject(3, 1.0);
  write_subject_table(dir + "other.tsv", other);
  ElementDefinition d2 = def();
  d2.samples = 16;
  other.definition = d2;
  write_subject_table(dir + "other.tsv", other);
  const std::string err = dir + "err.txt";
  CHECK(test::run_status(vpm + " compare --normals " + normals + "," + dir + "other.tsv --patient " + dir +
                         "p.tsv --feature pet -o " + dir + "bad.tsv 2> " + err) == 2);
  CHECK_THAT(test::slurp(err), Catch::Contains("other.tsv") && Catch::Contains("definition differs"));
  CHECK(test::run_status("test -e " + dir + "bad.tsv") == 1);
}

TEST_CASE("statistics: hysteresis grows foci from their core, peaks keep small foci, smoothing averages over adjacent elements") {
  const CanonicalElements el(def());
  std::vector<ElementTable> normals;
  std::vector<std::string> names;
  for (unsigned i = 0; i < 20; ++i) {
    normals.push_back(subject(i + 1, 1.0));
    names.push_back("n" + std::to_string(i));
  }
  const Reference ref = build_reference(normals, names, "pet", Normalisation::none);
  // a patient with exact z: a core of 4 elements at -4, its other neighbours at -2.7, and an
  // unrelated group of 4 at -2.7 (below the cut everywhere)
  const std::set<int> core = planted_focus(el, el.id(1, 17)), lonely = planted_focus(el, el.id(1, 150));
  std::set<int> ring;
  for (int e : core)
    for (int n : el.neighbours(e))
      if (!core.count(n)) ring.insert(n);
  for (int e : lonely) REQUIRE((!core.count(e) && !ring.count(e)));
  ElementTable patient = normals[0];
  for (int e = 0; e < el.size(); ++e) {
    const double z = core.count(e) ? -4 : ring.count(e) || lonely.count(e) ? -2.7 : 0;
    patient.features[0].mean[e] = ref.mean[e] + z * ref.std[e];
  }
  CompareOptions o;
  const Comparison plain = compare_to_reference(el, ref, patient, o);
  REQUIRE(plain.clusters.size() == 1);
  CHECK(std::set<int>(plain.clusters[0].elements.begin(), plain.clusters[0].elements.end()) == core);
  o.extend = 2.5;
  const Comparison grown = compare_to_reference(el, ref, patient, o);
  REQUIRE(grown.clusters.size() == 1);
  std::set<int> both = core;
  both.insert(ring.begin(), ring.end());
  CHECK(std::set<int>(grown.clusters[0].elements.begin(), grown.clusters[0].elements.end()) == both);
  CHECK(grown.clusters[0].candidates == static_cast<int>(core.size()));
  CHECK(plain.clusters[0].candidates == static_cast<int>(core.size()));
  for (int e : lonely) CHECK(grown.cluster[e] == 0);
  o.min_cluster = 5;  // counts only the core's elements at or beyond the cut
  CHECK(compare_to_reference(el, ref, patient, o).clusters.empty());
  // peak or extent: the small cluster is a focus when its peak reaches --peak, not below
  o.peak = 4.5;
  CHECK(compare_to_reference(el, ref, patient, o).clusters.empty());
  o.peak = 3.9;
  const Comparison peaked = compare_to_reference(el, ref, patient, o);
  REQUIRE(peaked.clusters.size() == 1);
  CHECK(peaked.clusters[0].elements.size() == both.size());
  CHECK(peaked.clusters[0].peak_z == Approx(-4));
  o.peak = 0;

  std::vector<double> flat(el.size(), 2.0), spike(el.size(), 0.0);
  flat[5] = std::nan("");
  for (double v : smooth_over_elements(el, flat, 2)) CHECK((std::isnan(v) || v == Approx(2.0)));
  CHECK(std::isnan(smooth_over_elements(el, flat, 1)[5]));
  const int e0 = el.id(1, 40);
  spike[e0] = 1;
  const std::vector<double> s1 = smooth_over_elements(el, spike, 1), s2 = smooth_over_elements(el, spike, 2);
  double w = el.volume(e0);
  for (int n : el.neighbours(e0)) w += el.volume(n);
  CHECK(s1[e0] == Approx(el.volume(e0) / w));
  for (int n : el.neighbours(e0)) CHECK(s1[n] > 0);
  // an element two steps away: reached by two rings, not by one
  const auto nb0 = el.neighbours(e0);
  int far = -1;
  for (int n : el.neighbours(nb0[0]))
    if (n != e0 && std::find(nb0.begin(), nb0.end(), n) == nb0.end()) far = n;
  REQUIRE(far >= 0);
  CHECK(s1[far] == 0);
  CHECK(s2[far] > 0);
  // a smoothed reference has a smaller spread (independent noise averaged) and says so
  const Reference smooth = build_reference(el, normals, names, "pet", Normalisation::none, 1);
  CHECK(smooth.smoothing == 1);
  double ratio = 0;
  for (int e = 0; e < el.size(); ++e) ratio += smooth.std[e] / ref.std[e] / el.size();
  CHECK(ratio < 0.75);
  CHECK_THROWS_AS(build_reference(el, normals, names, "pet", Normalisation::none, -1), InputError);
}

TEST_CASE("statistics: Crawford-Howell's test gives the z of the same tail probability as t with n - 1 dof") {
  const CanonicalElements el(def());
  std::vector<ElementTable> normals;
  std::vector<std::string> names;
  for (unsigned i = 0; i < 10; ++i) {
    normals.push_back(subject(i + 1, 1.0));
    names.push_back("n" + std::to_string(i));
  }
  const Reference ref = build_reference(normals, names, "pet", Normalisation::none);
  for (int c : ref.count) CHECK(c == 10);
  // t(9) = -2.262157 has lower tail 0.025 (tables), i.e. z = -1.959964; t(9) = 3.249836 has
  // upper tail 0.005, z = 2.575829
  const double inflate = std::sqrt(11.0 / 10.0);
  ElementTable patient = normals[0];
  for (int e = 0; e < el.size(); ++e)
    patient.features[0].mean[e] = ref.mean[e] + (e % 2 ? -2.262157163 : 3.249835542) * inflate * ref.std[e];
  CompareOptions o;
  o.test = SingleCaseTest::crawford_howell;
  const Comparison ch = compare_to_reference(el, ref, patient, o);
  o.test = SingleCaseTest::z;
  const Comparison plain = compare_to_reference(el, ref, patient, o);
  for (int e = 0; e < el.size(); ++e) {
    CHECK(ch.z[e] == Approx(e % 2 ? -1.959964 : 2.575829).epsilon(1e-5));
    CHECK(std::abs(plain.z[e]) > std::abs(ch.z[e]));
  }
  // far tails stay finite; more normals bring it to the plain z
  patient.features[0].mean[0] = ref.mean[0] - 1e6 * ref.std[0];
  o.test = SingleCaseTest::crawford_howell;
  const double far = compare_to_reference(el, ref, patient, o).z[0];
  CHECK(std::isfinite(far));
  CHECK(far == Approx(-14.9958).epsilon(1e-4));  // SciPy: norm.ppf(t.cdf(-1e6 / sqrt(1.1), 9))
  for (unsigned i = 10; i < 400; ++i) {
    normals.push_back(subject(i + 1, 1.0));
    names.push_back("n" + std::to_string(i));
  }
  const Reference big = build_reference(normals, names, "pet", Normalisation::none);
  patient.features[0].mean[1] = big.mean[1] - 3 * big.std[1];
  CHECK(compare_to_reference(el, big, patient, o).z[1] == Approx(-3).epsilon(0.01));
  CHECK_THROWS_AS(parse_single_case_test("student"), InputError);
}

TEST_CASE("statistics: incomplete beta, Student's t tail and the normal quantile against reference values") {
  // values from SciPy (special.betainc, stats.t.cdf, stats.norm.ppf)
  CHECK(detail::incomplete_beta(2, 3, 0.5) == Approx(0.6875).epsilon(1e-13));
  CHECK(detail::incomplete_beta(0.7, 12.5, 0.03) == Approx(0.4784873835616079).epsilon(1e-12));
  CHECK(detail::student_t_tail(-2.262157163, 9) == Approx(0.024999999991754306).epsilon(1e-11));
  CHECK(detail::student_t_tail(2.262157163, 9) == Approx(0.024999999991754306).epsilon(1e-11));
  CHECK(detail::student_t_tail(-50, 3) == Approx(8.808576020635976e-06).epsilon(1e-10));
  CHECK(detail::student_t_tail(-1, 400) == Approx(0.15895752821875708).epsilon(1e-11));
  CHECK(detail::normal_lower_quantile(0.025) == Approx(-1.9599639845400545).epsilon(1e-13));
  CHECK(detail::normal_lower_quantile(8.808576020635976e-06) == Approx(-4.293130332795124).epsilon(1e-12));
  CHECK(detail::normal_lower_quantile(1e-300) == Approx(-37.0470962993612).epsilon(1e-9));
  CHECK(detail::normal_lower_quantile(0.5) == Approx(0).margin(1e-15));
  CHECK(std::isfinite(detail::normal_lower_quantile(0.0)));
}

namespace {

// Eight normals with their global factors varied, and their paths in messages.
std::vector<ElementTable> eight_normals(std::vector<std::string>& names) {
  std::vector<ElementTable> out;
  names.clear();
  for (unsigned i = 0; i < 8; ++i) {
    out.push_back(subject(200 + i, 0.9 + 0.03 * i));
    names.push_back("n" + std::to_string(i));
  }
  return out;
}

}  // namespace

TEST_CASE("calibration: one pass at min_cluster 1 counts the false clusters every min_cluster keeps") {
  const CanonicalElements el(def());
  std::vector<std::string> names;
  const std::vector<ElementTable> normals = eight_normals(names);
  CalibrationSettings s;
  s.feature = "pet";
  s.compare.threshold = 1.8;  // low: many small false clusters in the normals
  s.compare.extend = 1.2;
  s.rate = 2;
  const ClusterCalibration cal = calibrate_min_cluster(el, normals, names, s);
  REQUIRE(cal.normals == 8);
  REQUIRE(cal.false_clusters.size() >= 3);
  CHECK(cal.false_clusters.front() > cal.false_clusters.back());
  CHECK(cal.false_clusters.back() == 0);
  // each count equals the direct comparisons at that min_cluster
  for (int m : {1, 2, 3, static_cast<int>(cal.false_clusters.size())}) {
    int direct = 0;
    for (size_t i = 0; i < normals.size(); ++i) {
      std::vector<ElementTable> others;
      std::vector<std::string> other_names;
      for (size_t j = 0; j < normals.size(); ++j)
        if (j != i) {
          others.push_back(normals[j]);
          other_names.push_back(names[j]);
        }
      CompareOptions o = s.compare;
      o.min_cluster = m;
      const Reference ref = build_reference(el, others, other_names, "pet", s.normalisation, 0);
      direct += static_cast<int>(compare_to_reference(el, ref, normals[i], o).clusters.size());
    }
    INFO("min_cluster " << m);
    CHECK(cal.false_clusters[static_cast<size_t>(m - 1)] == direct);
  }
  // the smallest size at or under the rate
  REQUIRE(cal.min_cluster >= 1);
  CHECK(cal.rate_at(cal.min_cluster) <= s.rate);
  if (cal.min_cluster > 1) CHECK(cal.rate_at(cal.min_cluster - 1) > s.rate);
  // the JSON gives it back, for the same settings and normals only
  const Json j = to_json(cal);
  CHECK(calibrated_rule(j, s, names, "cal.json").min_cluster == cal.min_cluster);
  std::vector<std::string> shuffled(names.rbegin(), names.rend());
  CHECK(calibrated_rule(j, s, shuffled, "cal.json").min_cluster == cal.min_cluster);
  CalibrationSettings other = s;
  other.compare.threshold = 2;
  CHECK_THROWS_WITH(calibrated_rule(j, other, names, "cal.json"),
                    Catch::StartsWith("cal.json: calibrated with options.threshold 1.8"));
  CHECK_THROWS_WITH(calibrated_rule(j, s, {names.begin(), names.end() - 1}, "cal.json"),
                    Catch::Contains("calibrated on other normals"));
  CHECK_THROWS_WITH(calibrated_rule(Json::parse("{\"feature\": \"pet\"}"), s, names, "cal.json"),
                    Catch::Contains("not a calibration"));
  // a peak rule that keeps clusters of every size: no min_cluster reaches the rate
  CalibrationSettings peaky = s;
  peaky.compare.peak = 1.9;
  peaky.rate = 0;
  const ClusterCalibration none = calibrate_min_cluster(el, normals, names, peaky);
  CHECK(none.min_cluster == 0);
  CHECK_THROWS_WITH(calibrated_rule(to_json(none), peaky, names, "cal.json"), Catch::Contains("no min_cluster"));
  // three normals are too few to leave one out
  CHECK_THROWS_AS(calibrate_min_cluster(el, {normals.begin(), normals.begin() + 3}, {names.begin(), names.begin() + 3}, s),
                  InputError);
}

TEST_CASE("vpm calibrate writes the calibration and vpm compare --min-cluster-from applies it") {
  const std::string dir = std::string(VPM_TEST_TMP) + "/cal_";
  std::vector<std::string> names;
  const std::vector<ElementTable> normals = eight_normals(names);
  std::string list;
  for (size_t i = 0; i < normals.size(); ++i) {
    write_subject_table(dir + names[i] + ".tsv", normals[i]);
    list += (i ? "," : "") + dir + names[i] + ".tsv";
  }
  write_subject_table(dir + "p.tsv", subject(77, 1.0));
  const std::string vpm = VPM_BINARY, opts = " --feature pet --threshold 1.8 --extend 1.2 --sign hypo --quiet";
  REQUIRE(test::run_status(vpm + " calibrate --normals " + list + opts + " --rate 2 -o " + dir + "cal.json") == 0);
  const Json cal = Json::parse(test::slurp(dir + "cal.json"));
  const int m = static_cast<int>(cal.find("min_cluster")->number());
  CHECK(m >= 1);
  CHECK(cal.find("normals")->number() == 8);
  REQUIRE(test::run_status(vpm + " compare --normals " + list + " --patient " + dir + "p.tsv" + opts +
                           " --min-cluster-from " + dir + "cal.json -o " + dir + "out.tsv") == 0);
  const Json side = Json::parse(test::slurp(dir + "out.json"));
  CHECK(side.find("options")->find("min_cluster")->number() == m);
  const std::string err = dir + "err.txt";
  // other options than the calibration's, both cluster options, too few normals: exit 2 with the reason
  CHECK(test::run_status(vpm + " compare --normals " + list + " --patient " + dir + "p.tsv" + opts +
                         " --threshold 2.5 --min-cluster-from " + dir + "cal.json -o " + dir + "bad.tsv 2> " + err) == 2);
  CHECK_THAT(test::slurp(err), Catch::Contains("cal.json: calibrated with options.threshold"));
  CHECK(test::run_status(vpm + " compare --normals " + list + " --patient " + dir + "p.tsv" + opts +
                         " --min-cluster 4 --min-cluster-from " + dir + "cal.json -o " + dir + "bad.tsv 2> " + err) == 2);
  CHECK_THAT(test::slurp(err), Catch::Contains("exclude each other"));
  CHECK(test::run_status("test -e " + dir + "bad.tsv") == 1);
  const std::string three = dir + names[0] + ".tsv," + dir + names[1] + ".tsv," + dir + names[2] + ".tsv";
  CHECK(test::run_status(vpm + " calibrate --normals " + three + opts + " -o " + dir + "c3.json 2> " + err) == 2);
  CHECK_THAT(test::slurp(err), Catch::Contains("at least 4"));
}

TEST_CASE("statistics: the spread shrunk across adjacent elements, recorded in the comparison") {
  const CanonicalElements el(def());
  std::vector<std::string> names;
  const std::vector<ElementTable> normals = eight_normals(names);
  const Reference plain = build_reference(el, normals, names, "pet", Normalisation::proportional, 0);
  const Reference none = build_reference(el, normals, names, "pet", Normalisation::proportional, 0, 0.0);
  CHECK(none.std == plain.std);
  const Reference full = build_reference(el, normals, names, "pet", Normalisation::proportional, 0, 1.0);
  const Reference half = build_reference(el, normals, names, "pet", Normalisation::proportional, 0, 0.5);
  CHECK(full.mean == plain.mean);
  for (int e : {0, 17, el.size() / 2, el.size() - 1}) {
    double sum = plain.std[e] * plain.std[e];
    int k = 1;
    for (int nb : el.neighbours(e)) {
      sum += plain.std[nb] * plain.std[nb];
      ++k;
    }
    CHECK(full.std[e] == Approx(std::sqrt(sum / k)).epsilon(1e-14));
    CHECK(half.std[e] * half.std[e] ==
          Approx(0.5 * plain.std[e] * plain.std[e] + 0.5 * full.std[e] * full.std[e]).epsilon(1e-12));
  }
  // pooled spreads vary less between elements than the raw ones
  const auto spread = [](const std::vector<double>& v) {
    const auto [lo, hi] = std::minmax_element(v.begin(), v.end());
    return *hi - *lo;
  };
  CHECK(spread(full.std) < spread(plain.std));
  CHECK_THROWS_AS(build_reference(el, normals, names, "pet", Normalisation::proportional, 0, 1.5), InputError);
  CHECK_THROWS_AS(build_reference(el, normals, names, "pet", Normalisation::proportional, 0, -0.1), InputError);
  // vpm compare --shrink records it; a calibration made without it is refused
  const std::string dir = std::string(VPM_TEST_TMP) + "/shrink_";
  std::string list;
  for (size_t i = 0; i < normals.size(); ++i) {
    write_subject_table(dir + names[i] + ".tsv", normals[i]);
    list += (i ? "," : "") + dir + names[i] + ".tsv";
  }
  write_subject_table(dir + "p.tsv", subject(77, 1.0));
  const std::string vpm = VPM_BINARY, base = " --feature pet --normals " + list + " --quiet";
  REQUIRE(test::run_status(vpm + " compare --patient " + dir + "p.tsv --shrink 0.8" + base + " -o " + dir + "out.tsv") == 0);
  CHECK(Json::parse(test::slurp(dir + "out.json")).find("reference")->find("shrinkage")->number() == 0.8);
  REQUIRE(test::run_status(vpm + " calibrate" + base + " -o " + dir + "cal.json") == 0);
  CHECK(test::run_status(vpm + " compare --patient " + dir + "p.tsv --shrink 0.8 --min-cluster-from " + dir +
                         "cal.json" + base + " -o " + dir + "bad.tsv 2> " + dir + "err.txt") == 2);
  CHECK_THAT(test::slurp(dir + "err.txt"), Catch::Contains("calibrated with shrinkage 0"));
  CHECK(test::run_status(vpm + " compare --patient " + dir + "p.tsv --shrink 2" + base + " -o " + dir + "bad.tsv 2> /dev/null") == 2);
}
