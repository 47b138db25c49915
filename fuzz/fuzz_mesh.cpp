// Fuzz target for one tet-mesh or surface reader, chosen at build time: FUZZ_EXT is the file
// extension read_mesh()/read_surface() dispatches on (".mesh", ".vtu", ".msh" with FUZZ_MESH;
// ".off", ".obj", ".stl", ".white" (FreeSurfer), ".gii" (GIfTI) without; ".curv", a FreeSurfer
// per-vertex file, with FUZZ_OVERLAY: read_overlay, whose values must be finite). What reads is validated as `vpm map`
// does next (a surface as one closed genus-0 surface for the sphere map).
#include "fuzz_target.hpp"
#include "vpm/io.hpp"
#include "vpm/surface_map.hpp"
#include "vpm/validate.hpp"

#ifndef FUZZ_EXT
#error "FUZZ_EXT (the file extension to read) must be defined"
#endif

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace vpm;
  const std::string path = fuzz::write_scratch("input" FUZZ_EXT, fuzz::bytes(data, size));
  fuzz::expect_input_error_only([&] {
#if defined(FUZZ_OVERLAY)
    fuzz::require(read_overlay(path).allFinite(), "read_overlay returns finite values");
#elif defined(FUZZ_MESH)
    TetMesh mesh = read_mesh(path);
    fuzz::require_well_formed(mesh);
    validate_mesh(mesh, path);
#else
    const TriSurface surface = read_surface(path);
    fuzz::require_well_formed(surface);
    validate_closed_surface(surface, path);
#endif
  });
  return 0;
}
