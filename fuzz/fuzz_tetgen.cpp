// Fuzz target for the TetGen reader: the input holds the .node file, the kSplit line and the
// .ele file (no .ele: read_mesh refuses the lone .node). A mesh that reads is validated.
#include <filesystem>

#include "fuzz_target.hpp"
#include "vpm/io.hpp"
#include "vpm/validate.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace vpm;
  const std::string_view in = fuzz::bytes(data, size);
  const auto [node, ele] = fuzz::split_files(in);
  const std::string path = fuzz::write_scratch("input.node", node);
  if (in.find(fuzz::kSplit) != std::string_view::npos) {
    fuzz::write_scratch("input.ele", ele);
  } else {
    std::error_code ec;
    std::filesystem::remove(fuzz::scratch_dir() + "/input.ele", ec);
  }
  fuzz::expect_input_error_only([&] {
    TetMesh mesh = read_mesh(path);
    fuzz::require_well_formed(mesh);
    validate_mesh(mesh, path);
  });
  return 0;
}
