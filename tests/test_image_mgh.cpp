// FreeSurfer MGH/MGZ volumes read by vpm (host/image/image_mgh.cpp) and label tables in AAL's
// and FreeSurfer's formats (host/collective/label_names.cpp). Files from nibabel are compared in
// tests/python/test_inputs.py; here: hand-made headers, hostile ones included.
#include <algorithm>
#include <zlib.h>

#include <catch2/catch.hpp>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include "vpm/error.hpp"
#include "vpm/image.hpp"
#include "vpm/label_names.hpp"

namespace {

void put32(std::vector<unsigned char>& b, std::uint32_t v) {
  for (int s = 24; s >= 0; s -= 8) b.push_back(static_cast<unsigned char>(v >> s));
}
void putf(std::vector<unsigned char>& b, float f) {
  std::uint32_t u;
  std::memcpy(&u, &f, 4);
  put32(b, u);
}

// An MGH file: dims, type 3 (float) unless given, RAS valid, voxel values v = i + 10 j + 100 k.
std::vector<unsigned char> mgh(int nx, int ny, int nz, int frames = 1, int version = 1, size_t keep_voxels = ~size_t(0)) {
  std::vector<unsigned char> b;
  put32(b, version);
  for (int d : {nx, ny, nz, frames}) put32(b, static_cast<std::uint32_t>(d));
  put32(b, 3);  // float
  put32(b, 0);  // dof
  b.push_back(0), b.push_back(1);  // goodRASflag
  for (float d : {2.0f, 1.0f, 3.0f}) putf(b, d);
  for (float c : {-1.f, 0.f, 0.f, 0.f, 0.f, -1.f, 0.f, 1.f, 0.f}) putf(b, c);  // LIA, as FreeSurfer's conformed volumes
  for (float c : {5.f, -7.f, 11.f}) putf(b, c);
  b.resize(284, 0);
  // the first keep_voxels voxels only (not a loop over a hostile header's 2^93 voxels)
  const size_t total = nx > 0 && ny > 0 && nz > 0 ? size_t(nx) * size_t(ny) * size_t(nz) : 0;  // wraps for the hostile sizes, whose keep_voxels is 0
  for (size_t n = 0; n < std::min(total, keep_voxels); ++n) {
    const size_t i = n % size_t(nx), j = n / size_t(nx) % size_t(ny), k = n / (size_t(nx) * size_t(ny));
    putf(b, static_cast<float>(i + 10 * j + 100 * k));
  }
  return b;
}

std::string write(const std::string& name, const std::vector<unsigned char>& bytes, bool gzip) {
  const std::string path = std::string(VPM_TEST_TMP) + "/" + name;
  if (gzip) {
    gzFile f = gzopen(path.c_str(), "wb");
    gzwrite(f, bytes.data(), static_cast<unsigned>(bytes.size()));
    gzclose(f);
  } else {
    std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(bytes.data()), bytes.size());
  }
  return path;
}

std::string text(const std::string& name, const std::string& body) {
  const std::string path = std::string(VPM_TEST_TMP) + "/" + name;
  std::ofstream(path) << body;
  return path;
}

}  // namespace

TEST_CASE("MGH and MGZ volumes: values, voxel-to-RAS affine as FreeSurfer computes it") {
  for (bool gz : {false, true}) {
    const vpm::Image img = vpm::read_image(write(gz ? "a.mgz" : "a.mgh", mgh(4, 3, 2), gz));
    CHECK(img.dims == std::array<int, 3>{4, 3, 2});
    CHECK(img.at(3, 2, 1) == 123.0f);
    CHECK(img.at(1, 0, 0) == 1.0f);
    CHECK(img.affine_source == "mgh");
    // columns Mdc_j * delta_j; translation c - M dims / 2
    Eigen::Matrix3d m;
    m << -2, 0, 0, 0, 0, 3, 0, -1, 0;
    CHECK((img.affine.topLeftCorner<3, 3>() - m).norm() < 1e-12);
    const Eigen::Vector3d t = Eigen::Vector3d(5, -7, 11) - m * Eigen::Vector3d(2, 1.5, 1);
    CHECK((img.affine.topRightCorner<3, 1>() - t).norm() < 1e-6);
    CHECK(img.spacing[0] == Approx(2));
    CHECK(img.spacing[2] == Approx(3));
  }
  CHECK(vpm::is_mgh_path("x/brainmask.MGZ"));
  CHECK(!vpm::is_mgh_path("x/brain.nii.gz"));
}

TEST_CASE("MGH: hostile and broken headers are refused before anything of their size is allocated") {
  auto fails_with = [](const std::string& path, const std::string& part) {
    try {
      vpm::read_image(path);
      FAIL("no error for " + path);
    } catch (const vpm::InputError& e) {
      INFO(e.what());
      CHECK(std::string(e.what()).find(part) != std::string::npos);
      CHECK(std::string(e.what()).find(path) == 0);
    }
  };
  fails_with(write("trunc.mgz", mgh(4, 3, 2, 1, 1, 5), true), "truncated");
  fails_with(write("short.mgh", std::vector<unsigned char>(100, 0), false), "shorter than the 284-byte");
  fails_with(write("v2.mgh", mgh(2, 2, 2, 1, 2), false), "not an MGH volume");
  fails_with(write("frames.mgz", mgh(2, 2, 2, 3), true), "3 frames");
  // 2^31-1 cubed claimed by a 300-byte file: refused by its size, no allocation
  fails_with(write("huge.mgz", mgh(0x7fffffff, 0x7fffffff, 0x7fffffff, 1, 1, 0), true), "more than vpm reads");
  // 400^3 floats (256 MB) claimed by a few hundred bytes: the reader grows only with what it read
  fails_with(write("huge2.mgz", mgh(400, 400, 400, 1, 1, 0), true), "truncated");
  // more than the memory allows: refused before reading, with the estimate
  setenv("VPM_MAX_MEMORY", "100M", 1);
  fails_with(write("big.mgz", mgh(400, 400, 400, 1, 1, 0), true), "needs about");
  unsetenv("VPM_MAX_MEMORY");
  fails_with(write("negative.mgh", mgh(-4, 3, 2, 1, 1, 0), false), "dimension 1");
  fails_with(std::string(VPM_TEST_TMP) + "/missing.mgz", "cannot be opened");
}

TEST_CASE("Label tables: AAL's text file and a FreeSurfer colour table") {
  const auto aal = vpm::read_label_table(text("aal.txt", "1 Precentral_L 2001\n71 Caudate_L 7001\n\n"));
  CHECK(aal.format == "aal");
  CHECK(aal.names.at(71) == "Caudate_L");
  CHECK(aal.colours.empty());
  const auto fs = vpm::read_label_table(text("lut.txt",
      "#$Id: FreeSurferColorLUT.txt\n\n#No. Label Name:                R   G   B   A\n"
      "0   Unknown                     0   0   0   0\n"
      "17  Left-Hippocampus          220 216  20   0\n"
      "  # an indented comment\n"
      "1035 ctx-lh-insula            255 192  32   0\n"));
  CHECK(fs.format == "freesurfer");
  CHECK(fs.names.at(17) == "Left-Hippocampus");
  CHECK(fs.names.at(1035) == "ctx-lh-insula");
  CHECK(fs.colours.at(17) == std::array<int, 4>{220, 216, 20, 0});
  CHECK(vpm::read_label_names(text("lut2.txt", "10 Left-Thalamus 0 118 14 0\n")).at(10) == "Left-Thalamus");
  CHECK_THROWS_WITH(vpm::read_label_table(text("bad1.txt", "17 Left-Hippocampus 220 216 20 0\nx Caudate\n")),
                    Catch::Contains("bad1.txt:2: label id 'x' is not an integer"));
  CHECK_THROWS_WITH(vpm::read_label_table(text("bad2.txt", "17 Left-Hippocampus 220 316 20 0\n")),
                    Catch::Contains("bad2.txt:1: colour value '316'"));
  CHECK_THROWS_WITH(vpm::read_label_table(text("bad3.txt", "17 A 1 2 3 4\n18 B\n")),
                    Catch::Contains("bad3.txt:2: no colour"));
  CHECK_THROWS_WITH(vpm::read_label_table(text("bad4.txt", "17 A\n17 B\n")), Catch::Contains("listed twice"));
  CHECK_THROWS_WITH(vpm::read_label_table(text("bad5.txt", "# nothing\n")), Catch::Contains("no label names"));
}
