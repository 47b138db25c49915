// Fuzz target for the HDF5 subject table reader (vpm sample's default output, read by vpm
// reference, compare, calibrate and view): the input is the file. A table that reads has one
// value per element of its definition in every column it holds, counts within the samples.
#include "fuzz_target.hpp"
#include "vpm/sampling.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace vpm;
  const std::string path = fuzz::write_scratch("table.h5", fuzz::bytes(data, size));
  fuzz::expect_input_error_only([&] {
    const ElementTable t = read_subject_table(path);
    const size_t n = static_cast<size_t>(t.definition.elements());
    for (const ElementFeature& f : t.features) {
      fuzz::require(f.mean.size() == n && f.std.size() == n && f.count.size() == n, "one feature value per element");
      for (int c : f.count) fuzz::require(c >= 0 && c <= t.definition.samples, "counts within the samples");
    }
    for (const ElementLabels& l : t.label_images) {
      fuzz::require(l.fraction.size() == l.labels.size(), "one fraction column per label");
      for (const auto& column : l.fraction) fuzz::require(column.size() == n, "one label fraction per element");
    }
  });
  return 0;
}
