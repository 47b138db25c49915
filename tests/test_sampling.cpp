// Per-element sampling (vpm/sampling.hpp): pull-back through a mapped mesh is exact for an
// affine native map, element statistics of a linear image are exact, label fractions, the table
// and `vpm sample`.
#include <catch2/catch.hpp>
#include <algorithm>
#include <cmath>
#include <string>

#include "support/fixtures.hpp"
#include "support/process.hpp"
#include "vpm/elements.hpp"
#include "vpm/error.hpp"
#include "vpm/image.hpp"
#include "vpm/io.hpp"
#include "vpm/sampling.hpp"

using namespace vpm;

namespace {

const Eigen::Matrix3d kA = (Eigen::Matrix3d() << 30, 4, 0, -3, 40, 2, 1, 0, 25).finished();
const Eigen::Vector3d kT(5, -3, 10);

Eigen::Vector3d to_native(const Eigen::Vector3d& x) { return kA * x + kT; }
double linear_value(const Eigen::Vector3d& w) { return 0.5 * w.x() - 0.2 * w.y() + 0.1 * w.z() + 100; }

// A 2.5 mm grid covering the native solid, holding linear_value (or labels by the sign of x - t.x).
Image native_image(bool labels) {
  Image im;
  im.dims = {52, 52, 40};
  im.spacing = {2.5, 2.5, 2.5};
  im.affine.setIdentity();
  im.affine.topLeftCorner<3, 3>() *= 2.5;
  im.affine.topRightCorner<3, 1>() = Eigen::Vector3d(-60, -70, -25);
  im.data.resize(im.size());
  for (int k = 0; k < im.dims[2]; ++k)
    for (int j = 0; j < im.dims[1]; ++j)
      for (int i = 0; i < im.dims[0]; ++i) {
        const Eigen::Vector3d w = im.to_world(Eigen::Vector3d(i, j, k));
        im.data[im.index(i, j, k)] = labels ? (w.x() > kT.x() ? 1.0f : 2.0f) : static_cast<float>(linear_value(w));
      }
  im.path = labels ? "labels.nii" : "linear.nii";
  return im;
}

TetMesh mapped_ball() {
  TetMesh m = test::ball_mesh(10);
  FieldValues native(m.num_vertices(), 3);
  for (int i = 0; i < m.num_vertices(); ++i) native.row(i) = to_native(m.vertices.row(i).transpose()).transpose();
  m.set_point_field("original_position", native);
  return m;
}

ElementDefinition small_definition() {
  ElementDefinition d;
  d.level = 2;
  d.shells = 4;
  d.samples = 16;
  return d;
}

}  // namespace

TEST_CASE("sampling: pull-back is exact for an affine native map, element statistics of a linear image") {
  const TetMesh m = mapped_ball();
  const CanonicalElements el(small_definition());
  const Points pos = pull_back_samples(el, m.vertices, m.tets, m.find_point_field("original_position")->values);
  REQUIRE(pos.rows() == el.samples().rows());
  const Image im = native_image(false);
  const ElementFeature f = sample_feature(el, pos, im, "lin");
  CHECK(f.name == "lin");
  CHECK(f.source == "linear.nii");
  const int S = el.definition().samples;
  int checked = 0;
  for (int e = 0; e < el.size(); ++e) {
    if (el.shell_of(e) == el.definition().shells - 1) continue;  // outer shell: the inscribed-mesh gap
    double sum = 0, sum2 = 0;
    for (int s = 0; s < S; ++s) {
      const Eigen::Vector3d x = el.samples().row(static_cast<Eigen::Index>(e) * S + s).transpose();
      const Eigen::Vector3d p = pos.row(static_cast<Eigen::Index>(e) * S + s).transpose();
      REQUIRE((p - to_native(x)).norm() < 1e-9);
      const double v = linear_value(to_native(x));
      sum += v;
      sum2 += v * v;
    }
    const double mean = sum / S;
    CHECK(f.count[e] == S);
    CHECK(f.mean[e] == Approx(mean).epsilon(1e-6));
    CHECK(f.std[e] == Approx(std::sqrt(std::max(0.0, sum2 / S - mean * mean))).margin(1e-3));
    ++checked;
  }
  CHECK(checked == el.size() * 3 / 4);
  // outside the image grid nothing is counted
  Image small = im;
  small.affine.topRightCorner<3, 1>() += Eigen::Vector3d(1000, 0, 0);
  const ElementFeature none = sample_feature(el, pos, small, "far");
  CHECK(*std::max_element(none.count.begin(), none.count.end()) == 0);
}

TEST_CASE("sampling: label fractions per element add up to one and follow the labels") {
  const TetMesh m = mapped_ball();
  const CanonicalElements el(small_definition());
  const Points pos = pull_back_samples(el, m.vertices, m.tets, m.find_point_field("original_position")->values);
  const ElementLabels lab = sample_label_fractions(el, pos, native_image(true));
  REQUIRE(lab.labels == std::vector<int>{1, 2});
  const int S = el.definition().samples;
  for (int e = 0; e < el.size(); ++e) {
    CHECK(lab.fraction[0][e] + lab.fraction[1][e] == Approx(1.0));
    int right = 0;  // samples whose native x lies right of the label boundary
    for (int s = 0; s < S; ++s) right += pos(static_cast<Eigen::Index>(e) * S + s, 0) > kT.x() + 1.25;
    int left = 0;
    for (int s = 0; s < S; ++s) left += pos(static_cast<Eigen::Index>(e) * S + s, 0) < kT.x() - 1.25;
    CHECK(lab.fraction[0][e] >= double(right) / S - 1e-12);  // nearest voxel: exact away from the boundary
    CHECK(lab.fraction[1][e] >= double(left) / S - 1e-12);
  }
}

TEST_CASE("vpm sample writes the subject table and its sidecar, bad input exits 2") {
  const std::string dir = VPM_TEST_TMP;
  const TetMesh m = mapped_ball();
  write_mesh(dir + "/sampling_ball.vtu", m);
  write_nifti(dir + "/sampling_lin.nii.gz", native_image(false));
  write_nifti(dir + "/sampling_lab.nii.gz", native_image(true));
  const std::string vpm = VPM_BINARY;
  const std::string tsv = dir + "/sampling_table.tsv";
  REQUIRE(test::run_status(vpm + " sample " + dir + "/sampling_ball.vtu -o " + tsv + " --images lin=" + dir +
                           "/sampling_lin.nii.gz --labels " + dir + "/sampling_lab.nii.gz --level 1 --shells 2" +
                           " --samples 8 --subject sub-01 --quiet") == 0);
  const std::string text = test::slurp(tsv);
  CHECK_THAT(text, Catch::StartsWith("element\tshell\ttriangle\tsamples\tlin_mean\tlin_std\tlin_count\tlabel_1\tlabel_2\n"));
  CHECK(std::count(text.begin(), text.end(), '\n') == 1 + 80 * 2);
  const Json side = Json::parse(test::slurp(dir + "/sampling_table.json"));
  CHECK(side.find("subject")->string() == "sub-01");
  CHECK(side.find("definition")->find("samples")->number() == 8);
  CHECK(side.find("features")->size() == 1);
  // a mesh without original_position, nothing to sample, a bad feature name: exit 2, no table
  TetMesh plain = test::ball_mesh(3);
  write_mesh(dir + "/sampling_plain.vtu", plain);
  const std::string err = dir + "/sampling.err";
  CHECK(test::run_status(vpm + " sample " + dir + "/sampling_plain.vtu -o " + dir + "/no.tsv --images a=" + dir +
                         "/sampling_lin.nii.gz 2> " + err) == 2);
  CHECK_THAT(test::slurp(err), Catch::Contains("original_position"));
  CHECK(test::run_status(vpm + " sample " + dir + "/sampling_ball.vtu -o " + dir + "/no.tsv 2> " + err) == 2);
  CHECK(test::run_status(vpm + " sample " + dir + "/sampling_ball.vtu -o " + dir + "/no.tsv --images a-b=x.nii 2> " +
                         err) == 2);
  CHECK_THAT(test::slurp(err), Catch::Contains("feature name 'a-b'"));
  CHECK(test::run_status("test -e " + dir + "/no.tsv") == 1);  // no table written
}
