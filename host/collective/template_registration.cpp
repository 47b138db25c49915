// register_to_template (vpm/template_registration.hpp): landmarks paired by regions or moments,
// the landmarks' flow, the dense iterations.
#include "vpm/template_registration.hpp"

#include <utility>

namespace vpm {
namespace {

using Mesh = TemplateRegistrationError::Mesh;

const char* name_of(Mesh mesh) { return mesh == Mesh::subject ? "the subject" : "the template"; }

// The mesh's labels; with moments a mesh without labels has none (all 0: no region), which only
// the image force can do without.
std::vector<int> labels_or_none(const TetMesh& mesh, Mesh which, const TemplateRegistrationOptions& opt) {
  if (mesh.find_cell_field("label") || opt.landmarks == TemplateLandmarks::regions) return cell_labels(mesh);
  if (opt.dense.force != DenseForce::image)
    throw TemplateRegistrationError(which, std::string("no cell field 'label': the ") + to_string(opt.dense.force) +
                                               " force needs atlas labels on both meshes; use the image force");
  return std::vector<int>(static_cast<size_t>(mesh.num_tets()), 0);
}

// The mesh's native positions (point field original_position), which the image force and the
// moments need.
void check_native(const TetMesh& mesh, Mesh which) {
  const Field* f = mesh.find_point_field("original_position");
  if (!f || f->values.cols() != 3)
    throw TemplateRegistrationError(which, "no point field original_position (3 components): not a mesh mapped by `vpm map`");
}

Points native_of(const TetMesh& mesh, Mesh which) {
  check_native(mesh, which);
  return native_positions(mesh, name_of(which));
}

void pair_landmarks(const TetMesh& subject, const TetMesh& templ, const TemplateRegistrationOptions& opt,
                    TemplateRegistration& out) {
  if (opt.landmarks == TemplateLandmarks::moments) {
    check_native(subject, Mesh::subject);
    check_native(templ, Mesh::templ);
    try {
      MomentLandmarks lm = moment_landmarks(subject, templ);
      out.landmarks = std::move(lm.source), out.targets = std::move(lm.target);
    } catch (const InputError& e) {
      throw TemplateRegistrationError(Mesh::both, e.what());
    }
    return;
  }
  RegionLandmarks lm;
  try {
    lm = region_landmarks(subject, templ, opt.exclude_labels);
  } catch (const InputError& e) {  // a mesh without labels
    throw TemplateRegistrationError(subject.find_cell_field("label") ? Mesh::templ : Mesh::subject, e.what());
  }
  if (lm.labels.size() < 4)
    throw TemplateRegistrationError(Mesh::both, std::to_string(lm.labels.size()) +
                                                    " atlas regions in common (cell field 'label'); need at least 4");
  out.landmark_labels = std::move(lm.labels);
  out.landmarks = std::move(lm.source), out.targets = std::move(lm.target);
}

DenseImages dense_images(const TetMesh& subject, const TetMesh& templ, const TemplateImages& images) {
  DenseImages d;
  d.subject = images.subject, d.templ = images.templ;
  d.subject_native = native_of(subject, Mesh::subject);
  d.template_native = native_of(templ, Mesh::templ);
  return d;
}

}  // namespace

const char* to_string(TemplateLandmarks landmarks) {
  return landmarks == TemplateLandmarks::moments ? "moments" : "regions";
}

TemplateLandmarks template_landmarks_from_string(const std::string& word) {
  if (word == "regions") return TemplateLandmarks::regions;
  if (word == "moments") return TemplateLandmarks::moments;
  throw InputError("'" + word + "' is not one of regions, moments");
}

TemplateRegistration register_to_template(Device& device, const TetMesh& subject, const TetMesh& templ,
                                          const TemplateRegistrationOptions& options, const TemplateImages& images) {
  if ((images.subject == nullptr) != (images.templ == nullptr))
    throw TemplateRegistrationError(images.subject ? Mesh::templ : Mesh::subject,
                                    "an image for one mesh only: the image force compares two");
  const bool image_force = options.dense.iterations > 0 && options.dense.force != DenseForce::labels;
  if (image_force && !images.subject)
    throw TemplateRegistrationError(Mesh::both, std::string("the ") + to_string(options.dense.force) +
                                                    " force needs both meshes' images");
  TemplateRegistration out;
  pair_landmarks(subject, templ, options, out);
  out.ball = subject.vertices;
  if (options.dense.iterations == 0) {
    out.result = register_landmarks(device, out.ball, subject.tets, out.landmarks, out.targets, options.flow);
    return out;
  }
  DenseRegistrationOptions dense = options.dense;
  dense.exclude_labels = options.exclude_labels;  // held-out regions stay out of the force too
  const DenseImages d = image_force ? dense_images(subject, templ, images) : DenseImages{};
  out.dense = register_dense(device, {out.ball, subject.tets, labels_or_none(subject, Mesh::subject, options)},
                             {templ.vertices, templ.tets, labels_or_none(templ, Mesh::templ, options)}, out.landmarks,
                             out.targets, options.flow, dense, image_force ? &d : nullptr);
  out.result = out.dense->landmark;
  out.result.landmark_rms_error = out.dense->landmark_rms_error;
  out.result.landmark_max_error = out.dense->landmark_max_error;
  out.result.max_normal_velocity = out.dense->max_normal_velocity;
  out.result.inverted_tets = out.dense->inverted_tets;
  return out;
}

}  // namespace vpm
