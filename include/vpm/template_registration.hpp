#pragma once
// Registering a subject to a template (paper 5): both meshes mapped to the unit ball, landmarks
// paired by the atlas regions they share (or, for a subject without atlas labels, by the affine
// that matches their native moments), the landmarks' divergence-free flow, then the dense
// iterations the options ask for. One call for `vpm register --template`, Python's
// vpm.register(template=...) and `vpm demo`, so the three pair landmarks, hold regions out and
// read images the same way.
#include <optional>
#include <string>
#include <vector>

#include "vpm/collective.hpp"
#include "vpm/dense_registration.hpp"
#include "vpm/device.hpp"
#include "vpm/error.hpp"
#include "vpm/image.hpp"
#include "vpm/mesh.hpp"
#include "vpm/registration.hpp"

namespace vpm {

/// How the subject's landmarks are paired with the template's.
enum class TemplateLandmarks {
  /// The volume centroids of the atlas regions (cell field `label`) both meshes carry, at least 4.
  regions,
  /// Points paired by the affine matching the two native solids' moments (moment_landmarks): for
  /// a subject without atlas labels; the dense force is then the image force.
  moments,
};

/// "regions", "moments"; and back (InputError naming the accepted words otherwise).
const char* to_string(TemplateLandmarks landmarks);
TemplateLandmarks template_landmarks_from_string(const std::string& word);

struct TemplateRegistrationOptions {
  TemplateLandmarks landmarks = TemplateLandmarks::regions;
  /// Regions never used, neither as landmarks nor by the dense force (held out for scoring).
  std::vector<int> exclude_labels;
  RegistrationOptions flow;  ///< the landmarks' flow
  /// The dense iterations after the flow (none by default: RegistrationPreset::landmarks;
  /// with_preset picks another preset). Its exclude_labels are replaced by the ones above.
  DenseRegistrationOptions dense;
};

/// The two images the image force compares, each in its mesh's native space (the meshes' point
/// field original_position places them). Both or neither; needed for DenseForce::image and both.
struct TemplateImages {
  const Image* subject = nullptr;
  const Image* templ = nullptr;
};

struct TemplateRegistration {
  Points ball;  ///< the subject's registered vertex positions in the ball
  /// The landmarks' flow, with the final landmark errors, normal velocity and inverted tets of
  /// the whole registration (the dense iterations' when they ran).
  RegistrationResult result;
  std::optional<DenseRegistrationResult> dense;  ///< when dense iterations ran
  std::vector<int> landmark_labels;  ///< the paired regions (TemplateLandmarks::regions)
  Points landmarks, targets;         ///< the paired points: subject ball, template ball
};

/// A problem with the inputs of register_to_template, naming which mesh it lies in; the message
/// speaks in library terms (callers add file names).
class TemplateRegistrationError : public InputError {
 public:
  enum class Mesh { subject, templ, both };
  TemplateRegistrationError(Mesh mesh, const std::string& problem) : InputError(problem), mesh(mesh) {}
  Mesh mesh;
};

/// Registers `subject` (mapped to the ball; point field original_position for the image force)
/// to `templ` (mapped or registered; it is not moved). Throws TemplateRegistrationError when the
/// meshes share fewer than 4 regions, a label force meets a mesh without labels (moments), the
/// images are half given or missing for an image force, or a mesh lacks its native positions;
/// what register_landmarks and register_dense throw otherwise (RegistrationInputError for the
/// flow's inputs, NumericalError for a folded result).
TemplateRegistration register_to_template(Device& device, const TetMesh& subject, const TetMesh& templ,
                                          const TemplateRegistrationOptions& options,
                                          const TemplateImages& images = {});

}  // namespace vpm
