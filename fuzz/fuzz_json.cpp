// Fuzz target for the JSON reader behind every sidecar (read_json_file), and for the element
// definition every table's sidecar carries (element_definition_from_json). What parses dumps to
// text that parses back to the same dump.
#include "fuzz_target.hpp"
#include "vpm/elements.hpp"
#include "vpm/json.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace vpm;
  const std::string path = fuzz::write_scratch("sidecar.json", fuzz::bytes(data, size));
  fuzz::expect_input_error_only([&] {
    const Json j = read_json_file(path);
    const std::string text = j.dump(2);
    Json again;
    try {
      again = Json::parse(text);
    } catch (const std::exception&) {
      fuzz::require(false, "Json::dump writes text that Json::parse reads");
    }
    fuzz::require(again.dump(2) == text, "parse(dump(x)) dumps as dump(x)");
    if (const Json* d = j.find("definition")) {
      const ElementDefinition def = element_definition_from_json(*d, path);
      fuzz::require(def.elements() > 0, "a definition that reads has elements");
    }
  });
  return 0;
}
