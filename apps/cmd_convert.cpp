// vpm convert IN OUT [--ascii]: reads any mesh (or surface) format and writes any other, by extension;
// element tables between HDF5 (.h5) and TSV (.tsv).
#include <iostream>

#include "cli.hpp"
#include "vpm/error.hpp"
#include "vpm/io.hpp"
#include "vpm/sampling.hpp"
#include "vpm/topology.hpp"

namespace {

bool is_table_path(const std::string& path) {
  try {
    vpm::table_format(path);
    return true;
  } catch (const vpm::InputError&) {
    return false;
  }
}

int run(const vpm::cli::Command& self, const std::vector<std::string>& argv) {
  vpm::cli::Args args(argv, self);
  args.expect_positional(2, vpm::cli::synopsis(self));
  const std::string& in = args.positional()[0];
  const std::string& out = args.positional()[1];
  if (is_table_path(in) || is_table_path(out)) {  // element tables: HDF5 <-> TSV
    const vpm::ElementTable t = vpm::read_subject_table(in);
    vpm::write_subject_table(out, t);
    vpm::cli::info("wrote " + out + ": " + std::to_string(t.definition.elements()) + " elements, " +
                   std::to_string(t.features.size()) + " features" + (t.label_images.empty() ? "" : " and label fractions"));
    return 0;
  }
  if (vpm::is_surface_path(in) && vpm::is_surface_path(out)) {
    const vpm::TriSurface s = vpm::read_surface(in);
    vpm::write_surface(out, s);
    vpm::cli::info("wrote " + out + ": " + std::to_string(s.vertices.rows()) + " vertices, " +
                   std::to_string(s.triangles.rows()) + " triangles");
    return 0;
  }
  if (vpm::is_surface_path(in))
    throw vpm::InputError(out + ": a surface (" + in + ") converts only to .off .obj .stl");
  if (!vpm::is_mesh_path(in))
    throw vpm::InputError(in + ": unknown file extension (meshes: .node .ele .mesh .vtu .msh; "
                          "surfaces: .off .obj .stl)");
  if (vpm::is_surface_path(out)) {  // a tet mesh's boundary (e.g. to remesh it with vpm mesh-image)
    const vpm::TriSurface s = vpm::boundary_surface(vpm::read_mesh(in));
    vpm::write_surface(out, s);
    vpm::cli::info("wrote the boundary of " + in + " to " + out + ": " + std::to_string(s.vertices.rows()) +
                   " vertices, " + std::to_string(s.triangles.rows()) + " triangles");
    return 0;
  }
  if (!vpm::is_mesh_path(out))
    throw vpm::InputError(out + ": unknown file extension for a tet mesh (expected .node .ele "
                          ".mesh .vtu .msh)");
  const vpm::TetMesh m = vpm::read_mesh(in);
  vpm::write_mesh(out, m, args.has("--ascii") ? vpm::VtuEncoding::ascii : vpm::VtuEncoding::binary);
  vpm::cli::info("wrote " + out + ": " + std::to_string(m.num_vertices()) + " vertices, " +
                 std::to_string(m.num_tets()) + " tets");
  return 0;
}
vpm::cli::Registrar reg({"convert", "IN OUT", "convert between mesh (or surface) formats, chosen by extension; a tet mesh to .off/.obj/.stl writes its boundary; element tables between .h5 and .tsv",
                          {{"--ascii", "", "a .vtu output as ASCII text (default: appended raw binary, as ParaView writes it)"}}, run});
}  // namespace
