#include "vpm/registration_preset.hpp"

#include "vpm/error.hpp"

namespace vpm {

const char* to_string(RegistrationPreset preset) {
  switch (preset) {
    case RegistrationPreset::landmarks: return "landmarks";
    case RegistrationPreset::standard: return "standard";
    case RegistrationPreset::accurate: return "accurate";
  }
  return "?";
}

RegistrationPreset registration_preset_from_string(const std::string& word) {
  for (RegistrationPreset p : {RegistrationPreset::landmarks, RegistrationPreset::standard, RegistrationPreset::accurate})
    if (word == to_string(p)) return p;
  throw InputError("unknown preset '" + word + "' (landmarks, standard or accurate)");
}

DenseRegistrationOptions with_preset(RegistrationPreset preset, DenseRegistrationOptions o) {
  const DenseRegistrationOptions defaults;
  switch (preset) {
    case RegistrationPreset::landmarks:
      o.iterations = 0;
      o.widths = defaults.widths;
      o.restore_cycles = 0;
      break;
    case RegistrationPreset::standard:
      o.iterations = 12;
      o.widths = defaults.widths;
      o.restore_cycles = 0;
      break;
    case RegistrationPreset::accurate:
      o.iterations = 32;
      o.widths = {0.3, 0.2, 0.14, 0.1};
      o.restore_cycles = 2;
      break;
  }
  return o;
}

}  // namespace vpm
