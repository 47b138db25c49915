// The collective view's data (vpm/cohort_view.hpp) and page (vpm/view_page.hpp): canonical
// surfaces pulled back exactly through affine maps, display triangles assigned to elements, the
// page's manifest and binary buffer read back as the browser reads them, and bad results folders.
#include <catch2/catch.hpp>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "support/fixtures.hpp"
#include "support/process.hpp"
#include "vpm/cohort_view.hpp"
#include "vpm/error.hpp"
#include "vpm/icosphere.hpp"
#include "vpm/json.hpp"
#include "vpm/view_page.hpp"

using namespace vpm;

namespace {

// An affine "registered" mesh: ball vertices, original_position = A x + b.
TetMesh affine_registered(const Eigen::Matrix3d& A, const Eigen::Vector3d& b) {
  TetMesh m = test::ball_mesh(12);
  Points native = (m.vertices * A.transpose()).rowwise() + b.transpose();
  m.set_point_field("original_position", native);
  return m;
}

std::string between(const std::string& text, const std::string& open, const std::string& close) {
  const size_t a = text.find(open);
  REQUIRE(a != std::string::npos);
  const size_t b = text.find(close, a + open.size());
  REQUIRE(b != std::string::npos);
  return text.substr(a + open.size(), b - a - open.size());
}

std::string unbase64(const std::string& in) {
  std::string out;
  int val = 0, bits = -8;
  for (char c : in) {
    const char* A = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    const char* p = std::strchr(A, c);
    if (!p || c == '\0') continue;
    val = (val << 6) + static_cast<int>(p - A);
    bits += 6;
    if (bits >= 0) {
      out.push_back(static_cast<char>((val >> bits) & 0xFF));
      bits -= 8;
    }
  }
  return out;
}

}  // namespace

TEST_CASE("shells' middle radii halve their volumes, display triangles split elements in four") {
  const CanonicalElements el(ElementDefinition{2, 5, 4});
  const std::vector<double> r = shell_mid_radii(el);
  REQUIRE(r.size() == 5);
  for (int k = 0; k < 5; ++k) {
    CHECK(std::pow(r[k], 3) == Approx(0.5 * (std::pow(el.radius(k), 3) + std::pow(el.radius(k + 1), 3))));
    CHECK(r[k] > el.radius(k));
    CHECK(r[k] < el.radius(k + 1));
  }
  const TriSurface display = icosphere(3);
  const std::vector<int> owner = display_triangle_elements(el, display);
  std::vector<int> count(el.triangles(), 0);
  for (int t : owner) ++count.at(t);
  for (int c : count) CHECK(c == 4);
}

TEST_CASE("canonical surfaces and element centres are pulled back exactly through an affine map") {
  const CanonicalElements el(ElementDefinition{1, 4, 4});
  Eigen::Matrix3d A;
  A << 60, 5, 0, -3, 75, 4, 2, 0, 55;
  const Eigen::Vector3d b(1, -20, 12);
  const TetMesh reg = affine_registered(A, b);
  const TriSurface display = icosphere(2);
  const std::vector<float> native = native_shell_surfaces(el, display, reg);
  const std::vector<double> radii = shell_mid_radii(el);
  const Eigen::Index V = display.vertices.rows();
  REQUIRE(native.size() == static_cast<size_t>(4 * V * 3));
  double worst = 0;
  for (int k = 0; k < 3; ++k)  // the outer shell's middle radius may fall in the sphere gap
    for (Eigen::Index v = 0; v < V; ++v) {
      const Eigen::Vector3d want = A * (display.vertices.row(v).transpose() * radii[k]) + b;
      for (int c = 0; c < 3; ++c) worst = std::max(worst, std::abs(native[3 * (k * V + v) + c] - want[c]));
    }
  CHECK(worst < 1e-3);  // float storage of ~100 mm values
  const std::vector<float> centres = native_element_centres(el, reg);
  REQUIRE(centres.size() == static_cast<size_t>(el.size() * 3));
  // an element's centre lies in that element: carried back by the inverse map
  const Eigen::Matrix3d Ai = A.inverse();
  for (int e = 0; e < el.triangles() * 3; ++e) {
    const Eigen::Vector3d x(centres[3 * e], centres[3 * e + 1], centres[3 * e + 2]);
    CHECK(el.element_of(Ai * (x - b)) == e);
  }
}

TEST_CASE("the page carries the manifest and the arrays the browser reads") {
  if (!view_page_available()) {
    CHECK_THROWS_AS(write_view_page(VPM_TEST_TMP "/view.html", CohortView{}), InputError);
    return;
  }
  const CanonicalElements el(ElementDefinition{1, 2, 4});
  CohortView v;
  v.title = "test </script> cohort";
  v.definition = el.definition();
  v.mid_radii = shell_mid_radii(el);
  v.display = icosphere(2);
  v.display_triangle_element = display_triangle_elements(el, v.display);
  v.features.push_back({"pet", Normalisation::proportional, 0, {}, 3, std::vector<float>(el.size(), 1.0f),
                        std::vector<float>(el.size(), 0.1f)});
  const TetMesh reg = affine_registered(Eigen::Matrix3d::Identity() * 70, Eigen::Vector3d(0, 0, 0));
  for (int s = 0; s < 2; ++s) {
    ViewSubject sub;
    sub.id = s ? "sub-N01" : "sub-P01";
    sub.patient = s == 0;
    sub.native = native_shell_surfaces(el, v.display, reg);
    std::vector<float> z(el.size());
    for (int e = 0; e < el.size(); ++e) z[e] = static_cast<float>(e % 7) - 3.0f + 0.25f * s;
    sub.values["pet"] = std::vector<float>(el.size(), 1.0f);
    sub.z["pet"] = z;
    if (sub.patient) {
      sub.foci_count["pet"] = 2;
      sub.centres = native_element_centres(el, reg);
    }
    v.subjects.push_back(sub);
  }
  const std::string path = VPM_TEST_TMP "/view.html";
  const ViewPageStats st = write_view_page(path, v);
  const std::string page = test::slurp(path);
  CHECK(st.bytes == static_cast<long long>(page.size()));
  CHECK(page.find("test </script> cohort") == std::string::npos);  // escaped inside the script
  const Json m = Json::parse(between(page, "<script id=\"vpm-manifest\" type=\"application/json\">", "</script>"));
  CHECK(m.find("format")->string() == "vpm-view-1");
  CHECK(m.find("title")->string() == "test </script> cohort");
  CHECK(m.find("subjects")->size() == 2);
  const std::string blob = unbase64(between(page, "<script id=\"vpm-buffers\" type=\"application/octet-stream\">", "</script>"));
  CHECK(static_cast<long long>(blob.size()) == st.data_bytes);
  const Json& n01 = m.find("subjects")->at(1);
  CHECK(n01.find("group")->string() == "normal");
  const Json* buf = m.find("buffers")->find(n01.find("z")->find("pet")->string());
  REQUIRE(buf);
  CHECK(buf->find("type")->string() == "q16");  // 16-bit codes: base + step * code
  const size_t off = static_cast<size_t>(buf->find("offset")->number());
  CHECK(off % 8 == 0);
  std::vector<std::uint16_t> code(el.size());
  std::memcpy(code.data(), blob.data() + off, code.size() * 2);
  const double base = buf->find("base")->number(), step = buf->find("step")->number();
  CHECK(step == Approx(6.0 / 65534));  // z spans -2.75 .. 3.25
  for (int e = 0; e < el.size(); ++e) CHECK(std::abs(base + step * code[e] - v.subjects[1].z["pet"][e]) <= 0.51 * step);
  // NaN is code 65535; a constant array decodes exactly
  CohortView w = v;
  w.subjects[1].z["pet"][3] = std::nanf("");
  write_view_page(path + ".nan.html", w);
  const std::string page2 = test::slurp(path + ".nan.html");
  const Json m2 = Json::parse(between(page2, "<script id=\"vpm-manifest\" type=\"application/json\">", "</script>"));
  const std::string blob2 = unbase64(between(page2, "<script id=\"vpm-buffers\" type=\"application/octet-stream\">", "</script>"));
  const Json* b2 = m2.find("buffers")->find(m2.find("subjects")->at(1).find("z")->find("pet")->string());
  std::uint16_t c3 = 0;
  std::memcpy(&c3, blob2.data() + static_cast<size_t>(b2->find("offset")->number()) + 6, 2);
  CHECK(c3 == 65535);
  const Json* vb = m.find("buffers")->find(n01.find("values")->find("pet")->string());
  CHECK(vb->find("base")->number() == 1.0);  // all 1.0: base 1, codes 0
  // native positions quantised to 16 bits: within half a step of the floats
  const Json& nat = *m.find("subjects")->at(0).find("native");
  const Json* nb = m.find("buffers")->find(nat.find("buffer")->string());
  std::vector<std::int16_t> q(v.subjects[0].native.size());
  std::memcpy(q.data(), blob.data() + static_cast<size_t>(nb->find("offset")->number()), q.size() * 2);
  double worst = 0;
  for (size_t i = 0; i < q.size(); ++i)
    worst = std::max(worst, std::abs(nat.find("offset")->at(i % 3).number() + q[i] * nat.find("scale")->number() -
                                     v.subjects[0].native[i]));
  CHECK(worst <= 0.51 * nat.find("scale")->number() + 1e-6);
  CHECK(m.find("subjects")->at(0).find("foci")->find("pet")->number() == 2);
}

TEST_CASE("normals' z-scores are against the other normals") {
  const std::vector<std::vector<double>> x = {{1.0, 5.0}, {2.0, 5.0}, {3.0, 5.0}, {4.0, 5.0}, {10.0, 5.0}};
  const auto z = leave_one_out_z(x);
  // normal 4 (10) against {1, 2, 3, 4}: mean 2.5, sample std sqrt(5/3)
  CHECK(z[4][0] == Approx((10.0 - 2.5) / std::sqrt(5.0 / 3.0)));
  // normal 0 (1) against {2, 3, 4, 10}: mean 4.75, squared deviations 38.75, sample std sqrt(38.75/3)
  CHECK(z[0][0] == Approx((1.0 - 4.75) / std::sqrt(38.75 / 3.0)));
  CHECK(std::isnan(z[2][1]));  // no spread among the others
  CHECK(std::isnan(leave_one_out_z({{1.0}, {2.0}, {3.0}})[0][0]));  // too few normals
}

TEST_CASE("a results folder without comparisons is refused naming it") {
  const std::string dir = VPM_TEST_TMP "/view_empty";
  std::filesystem::create_directories(dir + "/compare");
  try {
    load_cohort_view(dir);
    FAIL("no error");
  } catch (const InputError& e) {
    CHECK(std::string(e.what()).find("view_empty/compare: no comparison") != std::string::npos);
  }
  CHECK_THROWS_AS(load_cohort_view(VPM_TEST_TMP "/no_such_results"), InputError);
  // a comparison's sidecar without its options is named, not dereferenced
  {
    std::ofstream(dir + "/compare/sub-P01_pet.json")
        << R"({"reference": {"feature": "pet", "tables": []}, "patient": ")" << dir
        << R"(/compare/sub-P01_pet.json", "options": {}, "result": {"clusters": []}})";
  }
  try {
    load_cohort_view(dir);
    FAIL("no error");
  } catch (const InputError& e) {
    CHECK(std::string(e.what()).find("sub-P01_pet.json: no 'normalisation'") != std::string::npos);
  }
  std::filesystem::remove(dir + "/compare/sub-P01_pet.json");
  CHECK(test::run_status(std::string(VPM_BINARY) + " view " + dir + " -o " + dir + "/x.html 2>/dev/null") == 2);
  CHECK(!std::filesystem::exists(dir + "/x.html"));
}
