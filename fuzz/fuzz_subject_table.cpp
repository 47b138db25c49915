// Fuzz target for the subject table reader (vpm sample's TSV and its JSON sidecar, read by vpm
// compare and vpm view): the input holds the TSV, the kSplit line and the sidecar. A table that
// reads has one value per element of its definition in every column.
#include "fuzz_target.hpp"
#include "vpm/sampling.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace vpm;
  const auto [tsv, sidecar] = fuzz::split_files(fuzz::bytes(data, size));
  const std::string path = fuzz::write_scratch("table.tsv", tsv);
  fuzz::write_scratch("table.json", sidecar);
  fuzz::expect_input_error_only([&] {
    const ElementTable t = read_subject_table(path);
    const size_t n = static_cast<size_t>(t.definition.elements());
    for (const ElementFeature& f : t.features)
      fuzz::require(f.mean.size() == n && f.std.size() == n && f.count.size() == n, "one feature value per element");
    for (const ElementLabels& l : t.label_images) {
      fuzz::require(l.fraction.size() == l.labels.size(), "one fraction column per label");
      for (const auto& column : l.fraction) fuzz::require(column.size() == n, "one label fraction per element");
    }
  });
  return 0;
}
