// vpm carry REGISTERED -o OUT --onto MAPPED: a registration found on one mesh of a subject
// carried onto another mesh of the same subject (vpm/transfer.hpp).
#include <sstream>

#include "cli.hpp"
#include "vpm/device.hpp"
#include "vpm/error.hpp"
#include "vpm/io.hpp"
#include "vpm/json.hpp"
#include "vpm/metrics.hpp"
#include "vpm/timing.hpp"
#include "vpm/transfer.hpp"

namespace {
int run(const vpm::cli::Command& self, const std::vector<std::string>& argv) {
  using namespace vpm;
  const auto t_start = Clock::now();
  cli::Args args(argv, self);
  const cli::MeshInOut io = cli::mesh_in_out(args, self);
  const auto onto = args.get("--onto");
  if (!onto) throw InputError("missing --onto MAPPED; usage: " + cli::synopsis(self));
  const TetMesh source = read_mesh(io.in);
  TetMesh target = read_mesh(*onto);
  const CarriedRegistration carried = carry_registration(source, target);
  Device& dev = Device::current();
  const MapMetrics mm = map_metrics(dev, target.vertices, carried.ball, target.tets);
  if (mm.inverted_tets > 0)
    throw NumericalError("carry: " + std::to_string(mm.inverted_tets) + " tets of " + *onto + " stay folded under " +
                         io.in + "'s map after untangling (" + std::to_string(carried.folded) +
                         " folded when carried): register " + *onto + " itself; nothing written");
  target.vertices = carried.ball;
  target.set_point_field("vertex_volume_ratio", mm.vertex_ratio);
  target.set_cell_field("tet_volume_ratio", mm.tet_ratio);
  write_mesh(io.out, target);
  std::ostringstream line;
  line.precision(3);
  line << "carried " << io.in << " (" << source.num_vertices() << " vertices) onto " << *onto << " ("
       << target.num_vertices() << " vertices): tet volume mean |r-1| " << mm.tet_volume_ratio.mean_abs_dev
       << " against its own map, " << carried.folded << " folded tets untangled; wrote " << io.out;
  cli::info(line.str());
  if (const auto report_path = args.get("--report")) {
    Json j = to_json(mm);
    j["source"] = io.in;
    j["target"] = *onto;
    j["source_vertices"] = source.num_vertices();
    j["folded_untangled"] = carried.folded;
    j["target_vertices"] = target.num_vertices();
    j["seconds"] = seconds_since(t_start);
    write_json_file(*report_path, j);
  }
  return 0;
}

vpm::cli::Registrar reg(
    {"carry", "REGISTERED -o OUT",
     "carry a registration (or map) of one mesh of a subject onto another mesh of the same subject, through their native positions",
     {{"--onto", "MAPPED", "the other mesh, mapped by `vpm map` (its original_position says where its vertices are)", true},
      {"--report", "R.json", "write the report (inverted tets, volume ratios, sizes, seconds)"}},
     run});
}  // namespace
