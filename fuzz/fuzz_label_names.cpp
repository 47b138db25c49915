// Fuzz target for the atlas label tables the collective view and vpm sample read
// (--label-names: mricron's "id name [code]" lines or FreeSurfer's colour table
// "id name R G B A").
#include "fuzz_target.hpp"
#include "vpm/label_names.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace vpm;
  const std::string path = fuzz::write_scratch("labels.txt", fuzz::bytes(data, size));
  fuzz::expect_input_error_only([&] {
    const LabelTable table = read_label_table(path);
    fuzz::require(!table.names.empty(), "a table read holds a label");
    for (const auto& [id, name] : table.names) fuzz::require(!name.empty(), "label names are not empty");
    for (const auto& [id, rgba] : table.colours) {
      fuzz::require(table.names.count(id) == 1, "a colour belongs to a named label");
      for (int c : rgba) fuzz::require(c >= 0 && c <= 255, "colour values are 0-255");
    }
    fuzz::require(table.format == "aal" || table.format == "freesurfer", "the format is named");
  });
  return 0;
}
