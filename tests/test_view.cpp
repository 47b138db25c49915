// The collective view's data (vpm/cohort_view.hpp) and page (vpm/view_page.hpp): canonical
// surfaces pulled back exactly through affine maps, display triangles assigned to elements, the
// page's manifest and binary chunks read back as the browser reads them (embedded, or in a data
// folder), and bad results folders.
#include <catch2/catch.hpp>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>

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

namespace {

/// Chunk `name` of an embedded page, decoded.
std::string chunk_of(const std::string& page, const std::string& name) {
  return unbase64(between(page, "<script type=\"application/octet-stream\" id=\"vpm-chunk-" + name + "\">", "</script>"));
}

/// Buffer `name` of the manifest as an array of T, read from its chunk.
template <class T>
std::vector<T> buffer_of(const Json& m, const std::string& name, const std::function<std::string(const std::string&)>& chunk) {
  const Json* b = m.find("buffers")->find(name);
  REQUIRE(b);
  const size_t off = static_cast<size_t>(b->find("offset")->number());
  CHECK(off % 8 == 0);
  const std::string blob = chunk(b->find("chunk")->string());
  std::vector<T> out(static_cast<size_t>(b->find("length")->number()));
  REQUIRE(off + out.size() * sizeof(T) <= blob.size());
  std::memcpy(out.data(), blob.data() + off, out.size() * sizeof(T));
  return out;
}

/// A patient (z from e % 7 - 3, a focus reaching shells 0 and 1, slices of a file) and a normal.
CohortView two_subjects(const CanonicalElements& el) {
  CohortView v;
  v.title = "test </script> cohort & co";
  v.definition = el.definition();
  v.mid_radii = shell_mid_radii(el);
  v.display = icosphere(2);
  v.display_triangle_element = display_triangle_elements(el, v.display);
  v.features.push_back({"pet", Normalisation::proportional, 0, 0, {}, "", {}, 3, std::vector<float>(el.size(), 1.0f),
                        std::vector<float>(el.size(), 0.1f), std::vector<int>(el.size(), 3)});
  for (int s = 0; s < 2; ++s) {
    const TetMesh reg = affine_registered(Eigen::Matrix3d::Identity() * (70 + 5 * s), Eigen::Vector3d(3 * s, 0, 0));
    ViewSubject sub;
    sub.id = s ? "sub-N01" : "sub-P01";
    sub.patient = s == 0;
    sub.native = native_shell_surfaces(el, v.display, reg);
    sub.values["pet"] = std::vector<float>(el.size(), 1.0f);
    if (sub.patient) {
      std::vector<float> z(el.size());
      for (int e = 0; e < el.size(); ++e) z[e] = static_cast<float>(e % 7) - 3.0f;
      sub.z["pet"] = z;
      sub.foci_count["pet"] = 1;
      sub.cluster["pet"].assign(el.size(), 0);
      for (int e : {3, 10, 20, el.triangles() + 5, el.triangles() + 6}) sub.cluster["pet"][e] = 1;  // shells 0 and 1
      ViewFocus f;
      f.id = 1;
      f.peak_element = 3;
      sub.foci["pet"] = {f};
      sub.centres = native_element_centres(el, reg);
      ViewSlices sl;
      sl.dims = {2, 2, 2};
      sl.source = VPM_TEST_TMP "/images/sub-P01_pet.nii.gz";
      sl.image.assign(8, 7);
      sl.z.assign(8, 0);
      sub.slices["pet"] = sl;
    }
    v.subjects.push_back(sub);
  }
  return v;
}

}  // namespace

TEST_CASE("the page carries the manifest and the chunks of data the browser reads") {
  if (!view_page_available()) {
    CHECK_THROWS_AS(write_view_page(VPM_TEST_TMP "/view.html", CohortView{}), InputError);
    return;
  }
  const CanonicalElements el(ElementDefinition{1, 2, 4});
  const CohortView v = two_subjects(el);
  const std::string path = VPM_TEST_TMP "/view.html";
  const ViewPageStats st = write_view_page(path, v);
  const std::string page = test::slurp(path);
  CHECK(st.bytes == static_cast<long long>(page.size()));
  CHECK(st.data_dir.empty());
  CHECK(page.find("test </script> cohort") == std::string::npos);  // escaped inside the script
  CHECK(page.find("<title>test &lt;/script&gt; cohort &amp; co</title>") != std::string::npos);
  const Json m = Json::parse(between(page, "<script id=\"vpm-manifest\" type=\"application/json\">", "</script>"));
  const auto chunk = [&](const std::string& name) { return chunk_of(page, name); };
  CHECK(m.find("format")->string() == "vpm-view-2");
  CHECK(m.find("layout")->string() == "file");
  CHECK(m.find("title")->string() == "test </script> cohort & co");
  REQUIRE(m.find("subjects")->size() == 2);
  long long bytes = 0;
  for (const char* c : {"base", "rows-000", "detail-000"}) bytes += static_cast<long long>(chunk(c).size());
  CHECK(bytes == st.data_bytes);
  const Json& p01 = m.find("subjects")->at(0);
  const Json& n01 = m.find("subjects")->at(1);
  CHECK(n01.find("group")->string() == "normal");
  CHECK(!n01.find("z"));  // a normal's z is the page's (leave-one-out from the reference)
  CHECK(buffer_of<std::uint16_t>(m, m.find("reference")->find("pet")->find("count")->string(), chunk)[5] == 3);
  // z as 16-bit codes: base + step * code, within half a step
  const Json* zb = m.find("buffers")->find(p01.find("z")->find("pet")->string());
  CHECK(zb->find("type")->string() == "q16");
  const double base = zb->find("base")->number(), step = zb->find("step")->number();
  CHECK(step == Approx(6.0 / 65534));  // z spans -3 .. 3
  const auto code = buffer_of<std::uint16_t>(m, p01.find("z")->find("pet")->string(), chunk);
  for (int e = 0; e < el.size(); ++e) CHECK(std::abs(base + step * code[e] - v.subjects[0].z.at("pet")[e]) <= 0.51 * step);
  // shapes: the normals' mean shape plus 8-bit differences, within half a step of the floats
  const auto mean = buffer_of<float>(m, m.find("mean_shape")->string(), chunk);
  for (size_t s = 0; s < 2; ++s) {
    const Json& nat = *m.find("subjects")->at(s).find("native");
    const auto q = buffer_of<std::int8_t>(m, nat.find("buffer")->string(), chunk);
    double worst = 0;
    for (size_t i = 0; i < q.size(); ++i)
      worst = std::max(worst, std::abs(nat.find("centre")->at(i % 3).number() + mean[i] + q[i] * nat.find("scale")->number() -
                                       v.subjects[s].native[i]));
    CHECK(worst <= 0.51 * nat.find("scale")->number() + 1e-4);
  }
  // the focus faces from the shell where it is widest, on the element of the largest |z| there:
  // elements 3, 10 and 20 (z 0, 0, 3) on shell 0 against 85 and 86 (z -2 and -1) on shell 1
  const Json& focus = p01.find("foci_table")->find("pet")->at(0);
  CHECK(focus.find("face_element")->number() == 20);
  // the image is named relative to the page, never by its absolute path
  CHECK(p01.find("slices")->find("pet")->find("image_source")->string() == "images/sub-P01_pet.nii.gz");
  CHECK(page.find(VPM_TEST_TMP "/images") == std::string::npos);
  // NaN is code 65535
  CohortView w = v;
  w.subjects[0].z["pet"][3] = std::nanf("");
  write_view_page(path + ".nan.html", w);
  const std::string page2 = test::slurp(path + ".nan.html");
  const Json m2 = Json::parse(between(page2, "<script id=\"vpm-manifest\" type=\"application/json\">", "</script>"));
  const auto c2 = buffer_of<std::uint16_t>(m2, m2.find("subjects")->at(0).find("z")->find("pet")->string(),
                                           [&](const std::string& n) { return chunk_of(page2, n); });
  CHECK(c2[3] == 65535);
}

TEST_CASE("view data auto: a folder above the subject count or the estimated data") {
  if (!view_page_available()) return;
  namespace fs = std::filesystem;
  const CanonicalElements el(ElementDefinition{1, 2, 4});
  const CohortView v = two_subjects(el);
  const std::string dir = VPM_TEST_TMP "/view_auto";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const long long est = estimated_view_bytes(v);
  ViewPageOptions o;
  o.folder_above_bytes = est;
  const ViewPageStats file = write_view_page(dir + "/a.html", v, o);
  CHECK(file.data_dir.empty());
  CHECK(est <= file.data_bytes);  // the subjects' arrays, as encoded: never more than all the data
  // ... and most of it once the subjects outweigh the display sphere and the reference
  CohortView many = v;
  for (int i = 2; i < 40; ++i) {
    many.subjects.push_back(v.subjects[1]);
    many.subjects.back().id = "sub-N" + std::to_string(i + 10);
  }
  ViewPageOptions m;
  m.data = ViewData::embedded;
  const ViewPageStats big = write_view_page(dir + "/many.html", many, m);
  CHECK(estimated_view_bytes(many) <= big.data_bytes);
  CHECK(estimated_view_bytes(many) > 0.7 * big.data_bytes);
  o.folder_above_bytes = est - 1;
  CHECK(write_view_page(dir + "/b.html", v, o).data_dir == dir + "/b_data");
  o.folder_above_bytes = 100LL << 20;
  o.folder_above = 1;
  CHECK(write_view_page(dir + "/c.html", v, o).data_dir == dir + "/c_data");
}

TEST_CASE("a large cohort's page reads its data from a folder beside it") {
  if (!view_page_available()) return;
  namespace fs = std::filesystem;
  const CanonicalElements el(ElementDefinition{1, 2, 4});
  const CohortView v = two_subjects(el);
  const std::string dir = VPM_TEST_TMP "/view_folder";
  fs::remove_all(dir);
  fs::create_directories(dir);
  ViewPageOptions o;
  o.data = ViewData::folder;
  o.column_elements = 100;
  const ViewPageStats st = write_view_page(dir + "/cohort.html", v, o);
  CHECK(st.data_dir == dir + "/cohort_data");
  const std::string page = test::slurp(dir + "/cohort.html");
  CHECK(page.find("id=\"vpm-chunk-") == std::string::npos);
  const Json m = Json::parse(between(page, "<script id=\"vpm-manifest\" type=\"application/json\">", "</script>"));
  CHECK(m.find("layout")->string() == "folder");
  CHECK(m.find("data_dir")->string() == "cohort_data");
  const auto chunk = [&](const std::string& name) {  // each file names the hash of its content, as the manifest does
    const std::string text = test::slurp(dir + "/cohort_data/" + name + ".js");
    const std::string hash = m.find("chunks")->find(name)->find("hash")->string();
    CHECK(text.rfind("vpmChunk(\"" + hash + "\",\"" + name + "\",\"", 0) == 0);
    const std::string bytes = unbase64(between(text, "\",\"" + name + "\",\"", "\");"));
    CHECK(bytes.size() == static_cast<size_t>(m.find("chunks")->find(name)->find("bytes")->number()));
    return bytes;
  };
  // the normals' values by element: one column per element of the chunk, a normal per entry
  const Json& cols = *m.find("columns")->find("pet");
  CHECK(cols.find("buffers")->size() == static_cast<size_t>((el.size() + 99) / 100));
  CHECK(cols.find("normals")->at(0).number() == 1);
  const auto c0 = buffer_of<std::uint16_t>(m, cols.find("buffers")->at(0).string(), chunk);
  CHECK(c0.size() == 100);
  const Json& q = *m.find("features")->at(0).find("value_q");
  CHECK(q.find("base")->number() + q.find("step")->number() * c0[42] == Approx(1.0));
  // written again: the folder is replaced whole (a chunk file of the old one is gone); a folder
  // holding other files is left alone and refused
  std::ofstream(dir + "/cohort_data/rows-999.js") << "old";
  const std::string rows = test::slurp(dir + "/cohort_data/rows-000.js");
  write_view_page(dir + "/cohort.html", v, o);
  CHECK(test::slurp(dir + "/cohort.html") == page);  // the same data, the same files, byte for byte
  CHECK(test::slurp(dir + "/cohort_data/rows-000.js") == rows);
  CHECK(!fs::exists(dir + "/cohort_data/rows-999.js"));
  CHECK(fs::exists(dir + "/cohort_data/base.js"));
  CHECK(!fs::exists(dir + "/cohort_data.old"));
  fs::create_directories(dir + "/cohort_data.tmp");
  std::ofstream(dir + "/cohort_data.tmp/notes.txt") << "mine";
  CHECK_THROWS_AS(write_view_page(dir + "/cohort.html", v, o), InputError);
  CHECK(fs::exists(dir + "/cohort_data.tmp/notes.txt"));
  fs::remove_all(dir + "/cohort_data.tmp");
  std::ofstream(dir + "/cohort_data/notes.txt") << "mine";  // refused before anything is written
  CHECK_THROWS_AS(write_view_page(dir + "/cohort.html", v, o), InputError);
  CHECK(test::slurp(dir + "/cohort.html") == page);
  CHECK(fs::exists(dir + "/cohort_data/notes.txt"));
  CHECK(!fs::exists(dir + "/cohort_data.tmp"));
  // one file instead: the page's earlier folder goes with it (unless it holds other files)
  fs::remove(dir + "/cohort_data/notes.txt");
  o.data = ViewData::embedded;
  write_view_page(dir + "/cohort.html", v, o);
  CHECK(!fs::exists(dir + "/cohort_data"));
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
