// vpm mesh-image: NIfTI image (or closed surface) -> quality tet mesh, optional atlas labels.
#include <cstdlib>
#include <iostream>
#include <sstream>

#include "cli.hpp"
#include "vpm/error.hpp"
#include "vpm/io.hpp"
#include "vpm/json.hpp"
#include "vpm/mesh_image.hpp"

namespace {
// The library's message with the remedy in this command's flags.
std::string cli_message(const vpm::MeshImageError& e) {
  using P = vpm::MeshImageError::Problem;
  switch (e.problem()) {
    case P::kTooFewTargetVertices: return "--target-vertices " + e.context() + ": need at least 10";
    case P::kAtlasWithSurface: return "--labels needs an image input, not a surface (" + e.context() + ")";
    case P::kMaskTouchesBorder:
      return e.context() + " (pad the image, raise --threshold, or pass --close-at-border to close it with a flat cap there)";
    case P::kMaskVanishes: return e.context() + "; lower --smooth or raise --target-vertices";
    case P::kSurfaceSelfIntersects:
      return e.context() + "; --voxelize MM meshes the solid it encloses from a mask of MM voxels instead";
  }
  return e.what();
}

int run(const vpm::cli::Command& self, const std::vector<std::string>& argv) {
  const std::string kUsage = vpm::cli::synopsis(self);
  vpm::cli::Args args(argv, self);
  args.expect_positional(1, kUsage);
  const auto out = args.get("-o");
  if (!out) throw vpm::InputError(std::string("missing -o OUT; usage: ") + kUsage);
  if (args.has("--target-vertices") && args.has("--max-volume"))
    throw vpm::InputError("give either --target-vertices or --max-volume, not both");
  vpm::MeshImageOptions o;
  o.threshold = args.get_double("--threshold", o.threshold);
  if (args.has("--threshold") && args.has("--label"))
    throw vpm::InputError("give either --threshold or --label, not both");
  if (const auto sel = args.get("--label")) {
    if (sel->empty()) throw vpm::InputError("--label: empty (expected L or L1,L2,...)");
    std::string item;
    std::stringstream ss(*sel);
    while (std::getline(ss, item, ',')) {
      char* end = nullptr;
      const long v = std::strtol(item.c_str(), &end, 10);
      if (item.empty() || *end != '\0')
        throw vpm::InputError("--label: '" + item + "' is not an integer label (expected L or L1,L2,...)");
      o.select_labels.push_back(static_cast<int>(v));
    }
  }
  o.target_vertices = args.get_int("--target-vertices", o.target_vertices);
  o.max_volume = args.get_double("--max-volume", 0.0);
  if (args.has("--max-volume") && !(o.max_volume > 0)) throw vpm::InputError("--max-volume must be > 0");
  o.smooth = args.get_double("--smooth", o.smooth);
  o.radius_edge = args.get_double("--radius-edge", o.radius_edge);
  o.min_dihedral_deg = args.get_double("--min-dihedral", o.min_dihedral_deg);
  o.max_closing_radius = args.get_int("--max-closing-radius", o.max_closing_radius);
  o.close_at_border = args.has("--close-at-border");
  o.voxelize_mm = args.get_double("--voxelize", 0.0);
  if (args.has("--voxelize") && !(o.voxelize_mm > 0)) throw vpm::InputError("--voxelize must be > 0");
  o.progress = [](const std::string& s) { vpm::cli::progress("mesh-image: " + s); };
  vpm::MeshImageReport report;
  vpm::TetMesh mesh;
  try {
    mesh = vpm::mesh_image_file(args.positional()[0], o, &report, args.get("--labels", ""));
  } catch (const vpm::MeshImageError& e) {
    throw vpm::InputError(cli_message(e));
  }
  vpm::write_mesh(*out, mesh);
  if (auto r = args.get("--report")) vpm::write_json_file(*r, vpm::to_json(report));
  const vpm::MeshImageReport::Mesh& m = report.mesh;
  std::string line = "mesh-image: " + std::to_string(m.vertices) + " vertices, " + std::to_string(m.tets) +
                     " tets, smallest dihedral " + std::to_string(m.min_dihedral_deg) + " deg";
  if (report.image_input) line += ", coordinates from the " + report.input.affine_source;
  if (report.topology.closing_radius_cells > 0)
    line += ", handles removed by closing (radius " + std::to_string(report.topology.closing_radius_cells) + " cells)";
  line += " -> " + *out;
  vpm::cli::info(line);
  return 0;
}
vpm::cli::Registrar reg(
    {"mesh-image", "IMAGE.nii[.gz]|SURFACE.off|.obj|.stl -o OUT", "image mask or closed surface -> quality tet mesh",
     {{"--threshold", "T", "mask = voxels above T (default 0)", false, 1},
      {"--label", "L[,L...]", "mask = voxels with these labels (a label image)", false, 1},
      {"--labels", "ATLAS.nii[.gz]", "attach atlas labels (cell and point field `label`)"},
      {"--target-vertices", "N", "surface density for about N boundary vertices (default 5200)", false, 2},
      {"--max-volume", "V", "largest tet volume in mm^3 (sets the density instead)", false, 2},
      {"--smooth", "S", "Gaussian smoothing of the mask in mm (default: from the density)"},
      {"--close-at-border", "", "cap a mask that touches the image border"},
      {"--voxelize", "MM", "surface input: mesh the solid it encloses from a mask of MM voxels (crossing triangles allowed)"},
      {"--radius-edge", "Q", "TetGen radius-edge bound (default 1.5)"},
      {"--min-dihedral", "D", "TetGen smallest dihedral angle bound, degrees (default 12)"},
      {"--max-closing-radius", "R", "largest morphological closing tried for genus 0, grid cells (default 6)"},
      {"--report", "R.json", "write the report (sizes, quality, topology, timings)"}},
     run});
}  // namespace
