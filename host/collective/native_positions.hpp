#pragma once
// The native positions of a registered ball mesh's vertices (its point field original_position),
// shared by the map-back and the view.
#include "vpm/mesh.hpp"

namespace vpm::detail {

/// The point field original_position (n x 3) of `registered`; InputError naming `what` (the
/// caller, e.g. "map back") when it is missing or not 3 components: not a mapped mesh.
Points native_positions(const TetMesh& registered, const char* what);

}  // namespace vpm::detail
