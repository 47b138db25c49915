// The dense-registration flags of `vpm register` and `vpm demo`.
#include "dense_options.hpp"

#include <sstream>
#include <utility>

#include "vpm/error.hpp"
#include "vpm/format.hpp"
#include "vpm/surface_registration.hpp"

namespace vpm::cli {

DenseRegistrationOptions preset_option(const Args& args, DenseRegistrationOptions base) {
  const auto word = args.get("--preset");
  if (!word) return base;
  try {
    return with_preset(registration_preset_from_string(*word), std::move(base));
  } catch (const InputError& e) {
    throw InputError(std::string("--preset: ") + e.what());
  }
}

std::vector<double> parse_widths(const Args& args, const char* flag) {
  std::vector<double> widths;
  std::stringstream ss(args.get(flag).value_or(""));
  std::string item;
  while (std::getline(ss, item, ',')) {
    size_t used = 0;
    double v = 0;
    try {
      v = std::stod(item, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used == 0 || used != item.size() || !(v > 0 && v <= 2))
      throw InputError(std::string(flag) + ": expected widths in (0, 2] separated by commas, got '" + item + "'");
    widths.push_back(v);
  }
  if (widths.empty()) throw InputError(std::string(flag) + ": expected at least one width");
  return widths;
}

DenseRegistrationOptions dense_options(const Args& args, DenseRegistrationOptions o) {
  o.iterations = args.get_int("--dense-iterations", o.iterations);
  if (o.iterations < 0 || o.iterations > 1000) throw InputError("--dense-iterations: expected 0 to 1000");
  if (args.has("--dense-widths")) o.widths = parse_widths(args, "--dense-widths");
  o.step = args.get_double("--dense-step", o.step);
  if (!(o.step > 0 && o.step <= 1)) throw InputError("--dense-step: expected a fraction in (0, 1]");
  if (const auto f = args.get("--dense-force")) {
    try {
      o.force = dense_force_from_string(*f);
    } catch (const InputError& e) {
      throw InputError(std::string("--dense-force: ") + e.what());
    }
  }
  o.restore_image_weight = args.get_double("--dense-restore-image-weight", o.restore_image_weight);
  if (!(o.restore_image_weight >= 0 && o.restore_image_weight <= 1e6))
    throw InputError("--dense-restore-image-weight: expected 0 to 1e6");
  o.image_grid = args.get_int("--dense-image-grid", o.image_grid);
  if (o.image_grid != 0 && (o.image_grid < 8 || o.image_grid > 256))
    throw InputError("--dense-image-grid: expected 8 to 256 cells, or 0 (automatic)");
  o.restore_cycles = args.get_int("--dense-restore-cycles", o.restore_cycles);
  if (o.restore_cycles < 0 || o.restore_cycles > 100) throw InputError("--dense-restore-cycles: expected 0 to 100");
  o.fit_tolerance = args.get_double("--dense-fit-tolerance", o.fit_tolerance);
  if (!(o.fit_tolerance >= 1e-14 && o.fit_tolerance <= 0.1)) throw InputError("--dense-fit-tolerance: expected 1e-14 to 0.1");
  o.advect_steps = args.get_int("--dense-rk-steps", o.advect_steps);
  if (o.advect_steps < 1 || o.advect_steps > 64) throw InputError("--dense-rk-steps: expected 1 to 64");
  o.image_smoothing = args.get_double("--dense-image-smoothing", o.image_smoothing);
  if (!(o.image_smoothing >= 0 && o.image_smoothing <= 2))
    throw InputError("--dense-image-smoothing: expected 0 to 2 (x the level's width)");
  o.ridge = args.get_double("--dense-ridge", o.ridge);
  if (!(o.ridge > 0 && o.ridge <= 100)) throw InputError("--dense-ridge: expected (0, 100] (x the mean Gram diagonal)");
  o.smoothing = args.get_double("--dense-smoothing", o.smoothing);
  if (!(o.smoothing > 0 && o.smoothing <= 4)) throw InputError("--dense-smoothing: expected (0, 4] (x the level's width)");
  o.centre_spacing = args.get_double("--dense-centre-spacing", o.centre_spacing);
  if (!(o.centre_spacing >= 0.25 && o.centre_spacing <= 4))
    throw InputError("--dense-centre-spacing: expected 0.25 to 4 (x the level's width)");
  o.refine.iterations = args.get_int("--dense-refine", o.refine.iterations);
  if (o.refine.iterations < 0 || o.refine.iterations > 10000) throw InputError("--dense-refine: expected 0 to 10000");
  o.refine.volume_weight = args.get_double("--dense-refine-volume-weight", o.refine.volume_weight);
  if (!(o.refine.volume_weight >= 0 && o.refine.volume_weight <= 1e6))
    throw InputError("--dense-refine-volume-weight: expected 0 to 1e6");
  if (o.refine.iterations > 0 && o.force == DenseForce::labels)
    throw InputError("--dense-refine: the image refinement needs --dense-force image or both");
  return o;
}

void restore_step_options(const Args& args, RegistrationOptions& o) {
  o.restore_rounds = args.get_int("--restore-rounds", o.restore_rounds);
  if (o.restore_rounds < 1 || o.restore_rounds > 1000) throw InputError("--restore-rounds: expected 1 to 1000");
  o.restore_min_gain = args.get_double("--restore-min-gain", o.restore_min_gain);
  if (!(o.restore_min_gain >= 0 && o.restore_min_gain < 1))
    throw InputError("--restore-min-gain: expected a fraction in [0, 1)");
  for (const char* flag : {"--restore-rounds", "--restore-min-gain"})
    if (!o.restore_volumes && args.has(flag)) throw InputError(std::string(flag) + ": the restoration is off (--no-restore)");
}

Command with_dense_options(Command command, const std::string& after, int default_iterations,
                           DenseForce default_force) {
  const DenseRegistrationOptions d;
  const SphereMatchOptions sphere;
  auto list = [](const std::vector<double>& v) {
    std::string out;
    for (size_t i = 0; i < v.size(); ++i) out += (i ? "," : "") + format_sig(v[i], 6);
    return out;
  };
  const std::string widths = list(d.widths) + "; surfaces " + list(sphere.widths);
  const std::vector<OptionSpec> rows = {
          {"--dense-iterations", "N",
           "dense iterations after the landmarks: the subject pulled onto the template (--dense-force) by "
           "divergence-free flows (default " + std::to_string(default_iterations) + "; surfaces, a level " +
               std::to_string(sphere.iterations) + ")"},
          {"--dense-widths", "W[,W...]", "Gaussian widths of the dense levels, coarse to fine (default " + widths + ")",
           false, 0, true, true},
          {"--dense-step", "S", "fraction of the boundary displacement taken per dense iteration (default " +
                                    format_sig(d.step, 6) + ")", false, 0, true, true},
          {"--dense-force", "labels|image|both",
           std::string("what the dense flows pull: region boundaries, image intensities, or both (default ") +
               to_string(default_force) + ")", false, 0, true},
          {"--dense-refine", "N",
           "image refinement iterations (image force; default " + std::to_string(d.refine.iterations) + ": none)",
           false, 0, true},
          {"--dense-refine-volume-weight", "W", "weight of the image refinement's volume term against its image term (default " +
                                                    format_sig(d.refine.volume_weight, 6) + ")", false, 0, true, true},
          {"--dense-restore-image-weight", "W",
           "with an image force, how firmly the final volume restoration holds the image's edges (0: not; default " +
               format_sig(d.restore_image_weight, 6) + ")", false, 0, true, true},
          {"--dense-restore-cycles", "C",
           "cycles of volume restoration then more dense iterations at the finest width, after the others (default " +
               std::to_string(d.restore_cycles) + ")", false, 0, true, true},
          {"--dense-fit-tolerance", "T", "relative residual at which the fit's conjugate gradients stop (default " +
                                            format_sig(d.fit_tolerance, 6) + ")", false, 0, true, true},
          {"--dense-rk-steps", "K", "RK4 steps that carry the vertices through each dense iteration's flow (default " +
                                           std::to_string(d.advect_steps) + ")", false, 0, true, true},
          {"--dense-image-grid", "N", "cells across the ball of the image force's grid (default 0: about two "
                                          "grid points per tet of the subject)", false, 0, true, true},
          {"--dense-image-smoothing", "F", "Gaussian smoothing of the images before the image force, x the level's width (default " +
                                               format_sig(d.image_smoothing, 6) + ")", false, 0, true, true},
          {"--dense-ridge", "R", "smoothing ridge of the field's fit, x the mean Gram diagonal (default " +
                                     format_sig(d.ridge, 6) + ")", false, 0, true, true},
          {"--dense-smoothing", "F", "width of the Gaussian gathering the force at a centre, x the level's width (default " +
                                         format_sig(d.smoothing, 6) + ")", false, 0, true, true},
          {"--dense-centre-spacing", "F", "grid spacing of the field's centres, x the level's width (default " +
                                              format_sig(d.centre_spacing, 6) + ")", false, 0, true, true}};
  auto at = command.options.begin();
  while (at != command.options.end() && at->flag != after) ++at;
  if (at != command.options.end()) ++at;
  command.options.insert(at, rows.begin(), rows.end());
  return command;
}

}  // namespace vpm::cli
