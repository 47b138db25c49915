#pragma once
// Shared code of the fuzz targets (docs/robustness.md "Fuzzing"). Each fuzz_<name>.cpp defines
// LLVMFuzzerTestOneInput, which hands the bytes to one of vpm's readers the way its commands
// do. The readers take paths, so the bytes go to a file in a private temporary folder.
// The contract under test: a reader returns a well-formed result or throws vpm::InputError;
// any other exception, a crash, a sanitizer finding, a hang or a huge allocation is a bug.
#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <string_view>
#include <utility>

#include "vpm/mesh.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size);

namespace vpm::fuzz {

/// The input as text.
inline std::string_view bytes(const std::uint8_t* data, std::size_t size) {
  return {reinterpret_cast<const char*>(data), size};
}

/// This process's private folder (made on first use under $TMPDIR, removed at exit).
const std::string& scratch_dir();

/// Writes `bytes` to scratch_dir()/name (folders made as needed) and returns the path.
std::string write_scratch(const std::string& name, std::string_view bytes);

/// Inputs that hold two files (a .node and its .ele, a table and its sidecar) separate them by
/// this line; the seeds are written that way (fuzz_seeds) and the dictionaries hold it.
inline constexpr std::string_view kSplit = "\n==vpm-fuzz-next-file==\n";

/// The bytes before the first kSplit and those after it (empty when there is none).
std::pair<std::string_view, std::string_view> split_files(std::string_view bytes);

/// Runs `read`: returns normally or after a vpm::InputError (printed when VPM_FUZZ_VERBOSE is
/// set); prints and aborts on any other exception (what libFuzzer and the replay report as a
/// crash).
void expect_input_error_only(const std::function<void()>& read);

/// Aborts naming `promise` when `ok` is false: a reader returned something it promises not to.
void require(bool ok, const char* promise);

/// The promises of read_mesh: every tet's vertices in range, every field one row per vertex
/// (point data) or tet (cell data).
void require_well_formed(const TetMesh& mesh);

/// The promise of read_surface: every triangle's vertices in range.
void require_well_formed(const TriSurface& surface);

}  // namespace vpm::fuzz
