// Limits (docs/robustness.md, "Limits"): work too large for the machine's memory is refused up
// front with the estimate (exit 2), and a malformed or hostile NIfTI header is refused before
// anything is allocated from it.
#include <catch2/catch.hpp>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <stdexcept>

#include "support/fixtures.hpp"
#include "support/kill.hpp"
#include "support/process.hpp"
#include "support/scratch.hpp"
#include "vpm/ball_map.hpp"
#include "vpm/config.hpp"
#include "vpm/error.hpp"
#include "vpm/image.hpp"
#include "vpm/io.hpp"
#include "vpm/memory.hpp"

using namespace vpm;
namespace fs = std::filesystem;

namespace {

std::string fresh_dir(const std::string& name) { return test::fresh_dir("limits_" + name); }

template <class Fn>
std::string input_error_of(Fn fn) {
  try {
    fn();
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no InputError)";
}

// A NIfTI-1 header (little-endian, single file "n+1", float32, 8x8x8, pixdim 1, no sform or
// qform, vox_offset 352) with `edit` applied, followed by `data_bytes` zero bytes.
struct N1 {
  unsigned char h[352] = {};
  void i16(int off, short v) { std::memcpy(h + off, &v, 2); }
  void i32(int off, int v) { std::memcpy(h + off, &v, 4); }
  void f32(int off, float v) { std::memcpy(h + off, &v, 4); }
  N1() {
    i32(0, 348);
    i16(40, 3);
    for (int d = 1; d <= 7; ++d) i16(40 + 2 * d, d <= 3 ? 8 : 1);
    i16(70, 16);  // DT_FLOAT32
    i16(72, 32);
    for (int d = 0; d < 8; ++d) f32(76 + 4 * d, 1.f);
    f32(108, 352.f);  // vox_offset
    std::memcpy(h + 344, "n+1\0", 4);
  }
  // field offsets of the NIfTI-1 header
  static constexpr int kDim = 40, kPixdim = 76, kVoxOffset = 108, kSlope = 112, kInter = 116, kQform = 252,
                       kSform = 254, kQuatern = 256, kSrow = 280, kDatatype = 70;
  void write(const std::string& path, size_t data_bytes) const {
    std::ofstream out(path, std::ios::binary);
    out.write(reinterpret_cast<const char*>(h), sizeof h);
    std::vector<char> zeros(data_bytes, 0);
    out.write(zeros.data(), std::streamsize(zeros.size()));
    out.close();
    if (!out) throw std::runtime_error(path + ": the test could not write its header (file system full?)");
  }
};

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
constexpr float kInf = std::numeric_limits<float>::infinity();

}  // namespace

TEST_CASE("limits: sizes parse with K/M/G/T suffixes and anything else is refused") {
  CHECK(parse_memory_size("123", "X") == 123);
  CHECK(parse_memory_size("512K", "X") == 512u * 1024);
  CHECK(parse_memory_size("1.5G", "X") == 3u * 512 * 1024 * 1024);
  CHECK(parse_memory_size("2tib", "X") == 2ull << 40);
  CHECK(parse_memory_size("64GB", "X") == 64ull << 30);
  for (const std::string bad : {"", "G", "-1G", "12Q", "nan", "1e30"})
    CHECK(input_error_of([&] { parse_memory_size(bad, "VPM_MAX_MEMORY"); }).find("VPM_MAX_MEMORY: '" + bad + "' is not a size") == 0);
  CHECK(format_bytes(1.5 * (1 << 30)) == "1.5 GiB");
}

TEST_CASE("limits: the measured memory budget is what the machine has free") {
  const MemoryBudget b = memory_budget();  // VPM_MAX_MEMORY is not set under ctest
  if (std::getenv("VPM_MAX_MEMORY")) {
    WARN("VPM_MAX_MEMORY is set: skipped");
    return;
  }
  REQUIRE(b.checked);
  std::ifstream in("/proc/meminfo");
  std::string key;
  unsigned long long kb = 0, total = 0;
  while (in >> key >> kb && key != "MemTotal:") in.ignore(256, '\n');
  total = kb * 1024;
  CHECK(b.bytes > 0);
  CHECK(b.bytes <= total);
  CHECK(b.resident > 0);
  CHECK((b.source == "MemAvailable" || b.source.rfind("cgroup ", 0) == 0));
}

TEST_CASE("limits: vpm map refuses a mesh too large for the memory up front, with the estimate, exit 2") {
  const std::string dir = fresh_dir("map"), in = dir + "/in.vtu", err = dir + "/err.txt";
  write_mesh(in, test::ball_mesh(6));  // 1,296 tets
  const double need = map_memory_estimate(1296);
  CHECK(need > map_memory_estimate(0));
  CHECK(map_memory_estimate(10'000'000) > 5e9);  // measured: 8.9 GB at 10M tets (docs/volume_map.md)
  const std::string vpm = VPM_BINARY;
  // a budget below the estimate: refused before any work, nothing written
  const int rc = test::run_status("VPM_MAX_MEMORY=" + std::to_string(long(need * 0.9)) + " " + vpm + " map " + in +
                                  " -o " + dir + "/out.vtu 2> " + err);
  CHECK(rc == kExitInput);
  const std::string m = test::slurp(err);
  INFO(m);
  CHECK(m.find("vpm map: error: " + in + ": too large for this machine's memory: needs about ") == 0);
  CHECK(m.find("vpm map on 1296 tets") != std::string::npos);
  CHECK(m.find("VPM_MAX_MEMORY=off") != std::string::npos);
  CHECK(!fs::exists(dir + "/out.vtu"));
  // a budget above it runs; "off" turns the check off; a bad value is a usage error
  CHECK(test::run_status("VPM_MAX_MEMORY=" + std::to_string(long(need * 1.1)) + " " + vpm + " initial-map " + in +
                         " -o " + dir + "/im.vtu 2> " + err) == 0);
  CHECK(test::run_status("VPM_MAX_MEMORY=off " + vpm + " initial-map " + in + " -o " + dir + "/im.vtu 2> " + err) == 0);
  CHECK(test::run_status("VPM_MAX_MEMORY=lots " + vpm + " map " + in + " -o " + dir + "/out.vtu 2> " + err) == kExitInput);
  CHECK(test::slurp(err).find("VPM_MAX_MEMORY: 'lots' is not a size") != std::string::npos);
}

TEST_CASE("limits: a mesh file larger than the memory is refused before it is read") {
  const std::string dir = fresh_dir("read"), in = dir + "/in.vtu";
  write_mesh(in, test::cube_mesh(8));
  const auto size = fs::file_size(in);
  const std::string vpm = VPM_BINARY;
  CHECK(test::run_status("VPM_MAX_MEMORY=" + std::to_string(size / 2) + " " + vpm + " stats " + in + " > /dev/null 2> " +
                         dir + "/err.txt") == kExitInput);
  CHECK(test::slurp(dir + "/err.txt").find(in + ": too large for this machine's memory") != std::string::npos);
}

TEST_CASE("limits: hostile NIfTI headers are refused before any allocation, naming the field") {
  if (!VPM_HAVE_NIFTI) {
    WARN("built without nifti_clib: skipped");
    return;
  }
  const std::string dir = fresh_dir("nifti");
  const size_t whole = 8 * 8 * 8 * 4;
  auto refused = [&](const std::string& name, const std::function<void(N1&)>& edit, size_t data_bytes = 8 * 8 * 8 * 4) {
    N1 h;
    edit(h);
    const std::string p = dir + "/" + name + ".nii";
    h.write(p, data_bytes);
    return input_error_of([&] { read_nifti(p); });
  };
  // the unedited header reads
  CHECK(refused("good", [](N1&) {}) == "(no InputError)");
  // dimensions
  CHECK(refused("dim0", [](N1& h) { h.i16(N1::kDim, 0); }).find("dim[0] = 0") != std::string::npos);
  CHECK(refused("dim0_8", [](N1& h) { h.i16(N1::kDim, 8); }).find("dim[0] = 8") != std::string::npos);
  CHECK(refused("dim2_zero", [](N1& h) { h.i16(N1::kDim + 4, 0); }).find("dim[2] = 0") != std::string::npos);
  CHECK(refused("dim1_negative", [](N1& h) { h.i16(N1::kDim + 2, -5); }).find("dim[1] = -5") != std::string::npos);
  CHECK(refused("huge", [](N1& h) { for (int d = 1; d <= 3; ++d) h.i16(N1::kDim + 2 * d, 30000); })
            .find("image too large (30000x30000x30000") != std::string::npos);
  // 2000 x 2000 x 500 float32 = 8 GB declared, 2 KB present: refused before allocating the 8 GB
  const std::string big = refused("declares_8gb", [](N1& h) {
    h.i16(N1::kDim + 2, 2000), h.i16(N1::kDim + 4, 2000), h.i16(N1::kDim + 6, 500);
  }, 2048);
  CHECK(big.find("truncated: the header declares 8000000352 bytes") != std::string::npos);
  CHECK(refused("complex", [](N1& h) { h.i16(N1::kDatatype, 32); }).find("unsupported data type 32") != std::string::npos);
  // voxel sizes, scale factors, affines
  CHECK(refused("pixdim_nan", [](N1& h) { h.f32(N1::kPixdim + 8, kNaN); }).find("pixdim[2] = nan (voxel size not finite)") !=
        std::string::npos);
  CHECK(refused("pixdim_inf", [](N1& h) { h.f32(N1::kPixdim + 12, kInf); }).find("pixdim[3] = inf") != std::string::npos);
  CHECK(refused("pixdim_zero", [](N1& h) { h.f32(N1::kPixdim + 4, 0.f); }).find("pixdim[1] = 0 (the voxel size must be positive") !=
        std::string::npos);
  CHECK(refused("slope_inf", [](N1& h) { h.f32(N1::kSlope, kInf); }).find("scl_slope = inf") != std::string::npos);
  CHECK(refused("inter_nan", [](N1& h) { h.f32(N1::kSlope, 2.f), h.f32(N1::kInter, kNaN); }).find("scl_inter = nan") !=
        std::string::npos);
  CHECK(refused("srow_nan", [](N1& h) {
    h.i16(N1::kSform, 1);
    for (int i = 0; i < 12; ++i) h.f32(N1::kSrow + 4 * i, i % 5 == 0 ? 1.f : 0.f);
    h.f32(N1::kSrow + 4 * 7, kNaN);
  }).find("srow_y[3] = nan (sform not finite)") != std::string::npos);
  CHECK(refused("quatern_inf", [](N1& h) { h.i16(N1::kQform, 1), h.f32(N1::kQuatern + 4, kInf); })
            .find("quatern_c = inf (qform not finite)") != std::string::npos);
  // the data offset
  CHECK(refused("offset_nan", [](N1& h) { h.f32(N1::kVoxOffset, kNaN); }).find("vox_offset = nan") != std::string::npos);
  CHECK(refused("offset_inside_header", [](N1& h) { h.f32(N1::kVoxOffset, 100.f); }).find("vox_offset = 100") !=
        std::string::npos);
  CHECK(refused("offset_past_end", [](N1& h) { h.f32(N1::kVoxOffset, 1e12f); }).find("vox_offset = 1e+12") !=
        std::string::npos);
  // NaN scl_slope means "no scaling" (nibabel writes it): read, values unscaled
  N1 nib;
  nib.f32(N1::kSlope, kNaN), nib.f32(N1::kInter, kNaN);
  nib.write(dir + "/nibabel.nii", whole);
  CHECK(read_nifti(dir + "/nibabel.nii").data == std::vector<float>(512, 0.f));
}

TEST_CASE("limits: a gzip NIfTI declaring more data than deflate can expand to is refused before reading it") {
  if (!VPM_HAVE_NIFTI) {
    WARN("built without nifti_clib: skipped");
    return;
  }
  const std::string dir = fresh_dir("nifti_gz");
  N1 h;  // 1000^3 float32 = 4 GB declared in a gzip file of a few hundred bytes
  for (int d = 1; d <= 3; ++d) h.i16(N1::kDim + 2 * d, 1000);
  h.write(dir + "/bomb.nii", 4096);
  REQUIRE(test::run_status("gzip -f " + dir + "/bomb.nii") == 0);
  const std::string m = input_error_of([&] { read_nifti(dir + "/bomb.nii.gz"); });
  CHECK(m.find(dir + "/bomb.nii.gz: data: the header declares 3.73 GiB (1000x1000x1000 voxels), more than this") == 0);
  CHECK(m.find("deflate expands at most 1032x") != std::string::npos);
  // a real 8x8x8 image under the memory budget reads; over VPM_MAX_MEMORY it is refused with the estimate
  N1 ok;
  ok.write(dir + "/ok.nii", 8 * 8 * 8 * 4);
  const std::string vpm = VPM_BINARY;
  CHECK(test::run_status("VPM_MAX_MEMORY=1K " + vpm + " mesh-image " + dir + "/ok.nii -o " + dir +
                         "/ok.vtu 2> " + dir + "/err.txt") == kExitInput);
  CHECK(test::slurp(dir + "/err.txt").find("ok.nii: too large for this machine's memory: needs about 4 KiB (8x8x8 voxels x (4 stored + 4) bytes)") !=
        std::string::npos);
}
