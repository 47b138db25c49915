#pragma once
// A tiny cohort results folder for the view's fuzz target and its seeds: the subject tables of
// four normals and one patient (feature "pet", level-0 elements: 20) with their sidecars, and
// their registered ball meshes (an octahedron, original_position a scaled copy), written as
// the workflow writes them: DIR/results/tables/<id>.tsv, DIR/results/reg/<id>.vtu.
#include <string>

#include "vpm/mesh.hpp"

namespace vpm::fuzz {

/// The octahedron ball: the unit ball's six poles and its centre, eight positively oriented tets.
TetMesh octahedron();

/// Writes the folder under `dir` (once per `dir` and process is enough).
void write_cohort_fixture(const std::string& dir);

/// The sidecar text vpm compare writes for the patient against the normals, naming the tables
/// relative to `dir` ("results/tables/..."), as load_cohort_view resolves them.
std::string comparison_sidecar(const std::string& dir);

}  // namespace vpm::fuzz
