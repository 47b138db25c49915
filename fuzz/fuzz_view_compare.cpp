// Fuzz target for the comparison sidecars the collective view reads (load_cohort_view reads
// RESULTS/compare/*.json, then the tables and meshes they name): the bytes are the one sidecar
// of a small, valid results folder (cohort_fixture.hpp). A view that loads has its subjects'
// values and z-scores per element.
#include "cohort_fixture.hpp"
#include "fuzz_target.hpp"
#include "vpm/cohort_view.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace vpm;
  static const bool fixture = (fuzz::write_cohort_fixture(fuzz::scratch_dir()), true);
  (void)fixture;
  fuzz::write_scratch("results/compare/sub-P1_pet.json", fuzz::bytes(data, size));
  fuzz::expect_input_error_only([&] {
    const CohortView v = load_cohort_view(fuzz::scratch_dir() + "/results");
    const size_t n = static_cast<size_t>(v.definition.elements());
    for (const ViewSubject& s : v.subjects)
      for (const auto& [feature, z] : s.z) fuzz::require(z.size() == n, "one z per element");
  });
  return 0;
}
