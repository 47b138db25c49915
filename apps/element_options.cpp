#include "element_options.hpp"

#include "vpm/error.hpp"

namespace vpm::cli {

ElementDefinition element_definition(const Args& args) {
  ElementDefinition d;
  d.level = args.get_int("--level", d.level);
  d.layout = parse_option("--layout", [&] { return parse_element_layout(args.get("--layout", "shells")); });
  if (d.layout == ElementLayout::graded) {
    if (args.has("--shells")) throw InputError("option --shells: the graded layout sets the shells from --level");
    d.shells = graded_shells(d.level);
  } else {
    d.shells = args.get_int("--shells", d.shells);
  }
  d.samples = args.get_int("--samples", d.samples);
  return d;
}

}  // namespace vpm::cli
