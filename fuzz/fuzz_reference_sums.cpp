// Fuzz target for the reference sums reader (vpm reference's output, read by vpm reference
// --merge, compare and calibrate --reference): the input is the file. Sums that read have one
// row of stride() values per element of their definition, counts within the normals, a name and
// a design row per normal.
#include "fuzz_target.hpp"
#include "vpm/reference_sums.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace vpm;
  const std::string path = fuzz::write_scratch("sums.h5", fuzz::bytes(data, size));
  fuzz::expect_input_error_only([&] {
    const ReferenceSums s = read_reference_sums(path);
    fuzz::require(s.design().size() == s.normals().size(), "a design row per normal");
    for (int e = 0; e < s.definition().elements(); ++e)
      fuzz::require(s.element(e)[0] >= 0 && s.element(e)[0] <= double(s.normals().size()), "counts within the normals");
  });
  return 0;
}
