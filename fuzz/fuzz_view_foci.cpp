// Fuzz target for the foci table the collective view reads (vpm compare's OUT_foci.tsv), against
// a comparison with two foci.
#include "collective/cohort_view_detail.hpp"
#include "fuzz_target.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace vpm;
  static const Comparison comparison = [] {
    Comparison c;
    c.clusters.resize(2);
    c.clusters[0].id = 1, c.clusters[0].peak_element = 4;
    c.clusters[1].id = 2, c.clusters[1].peak_element = 9;
    return c;
  }();
  const std::string path = fuzz::write_scratch("compare_foci.tsv", fuzz::bytes(data, size));
  fuzz::expect_input_error_only([&] { detail::read_view_foci(path, comparison); });
  return 0;
}
