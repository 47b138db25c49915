// Fuzz target for the landmark CSV reader (vpm register --landmarks/--targets), against a mesh
// of 8 vertices (ids 0..7 are valid). What reads is one finite point in the unit ball per line.
#include "fuzz_target.hpp"
#include "vpm/landmarks.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace vpm;
  static const Points vertices = [] {
    Points v(8, 3);
    for (int i = 0; i < 8; ++i) v.row(i) << (i & 1) - 0.5, (i >> 1 & 1) - 0.5, (i >> 2 & 1) - 0.5;
    return v;
  }();
  const std::string path = fuzz::write_scratch("landmarks.csv", fuzz::bytes(data, size));
  fuzz::expect_input_error_only([&] {
    const LandmarkFile f = read_landmarks_csv(path, vertices);
    fuzz::require(f.points.rows() == static_cast<Eigen::Index>(f.lines.size()), "one line number per landmark");
    fuzz::require(f.points.rows() > 0, "at least one landmark (an empty file is refused)");
    for (Eigen::Index i = 0; i < f.points.rows(); ++i)
      fuzz::require(f.points.row(i).allFinite() && f.points.row(i).norm() <= 1 + 1e-9, "landmarks in the unit ball");
  });
  return 0;
}
