#pragma once
// Registration presets: the dense registration's settings picked by name, the way elastix ships
// parameter files, so the library, `vpm register --preset`, Python and the workflow share one
// default. Chosen on bench/register_peers' five volume-preserving pairs (docs/register.md
// "Presets"); a setting given explicitly after the preset overrides it.
#include <string>

#include "vpm/dense_registration.hpp"

namespace vpm {

enum class RegistrationPreset {
  /// The landmarks' flow alone, no dense iterations: seconds, and what the landmarks align.
  landmarks,
  /// 12 dense iterations over the widths 0.3, 0.2, 0.14: the workflow's and the demo's default.
  standard,
  /// 32 dense iterations over 0.3, 0.2, 0.14, 0.1, then 2 cycles of volume restoration and more
  /// iterations at the finest width: up to 0.01 more held-out Dice than standard at 45,000
  /// vertices with the image force (bench/results/register_force/), about 3x its time.
  accurate,
};

/// "landmarks", "standard", "accurate"; and back (InputError naming the accepted words
/// otherwise).
const char* to_string(RegistrationPreset preset);
RegistrationPreset registration_preset_from_string(const std::string& word);

/// `options` with the preset's iterations, widths and restore cycles; everything else (the
/// force, the fit, the held-out regions, the budget) as given.
DenseRegistrationOptions with_preset(RegistrationPreset preset, DenseRegistrationOptions options = {});

}  // namespace vpm
