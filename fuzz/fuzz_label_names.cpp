// Fuzz target for the atlas label names the collective view reads (vpm view --label-names:
// lines "id name [...]", as mricron's aal.nii.txt).
#include "collective/cohort_view_detail.hpp"
#include "fuzz_target.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace vpm;
  const std::string path = fuzz::write_scratch("labels.txt", fuzz::bytes(data, size));
  fuzz::expect_input_error_only([&] {
    for (const auto& [id, name] : detail::read_label_names(path)) fuzz::require(!name.empty(), "label names are not empty");
  });
  return 0;
}
