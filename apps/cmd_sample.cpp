// vpm sample REGISTERED -o TABLE.h5: per-element features of one subject (vpm/sampling.hpp).
#include <sstream>

#include "cli.hpp"
#include "element_options.hpp"
#include "vpm/element_sampler.hpp"
#include "vpm/elements.hpp"
#include "vpm/error.hpp"
#include "vpm/image.hpp"
#include "vpm/io.hpp"
#include "vpm/sampling.hpp"

namespace {

// "pet=a.nii.gz,t1=b.nii" -> {(pet, a.nii.gz), (t1, b.nii)}
std::vector<std::pair<std::string, std::string>> named_images(const std::string& spec) {
  std::vector<std::pair<std::string, std::string>> out;
  std::stringstream ss(spec);
  std::string item;
  while (std::getline(ss, item, ',')) {
    const auto eq = item.find('=');
    if (eq == 0 || eq == std::string::npos || eq + 1 == item.size())
      throw vpm::InputError("option --images: '" + item + "' is not NAME=IMAGE.nii[.gz]");
    const std::string name = item.substr(0, eq);
    for (char c : name)
      if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_')
        throw vpm::InputError("option --images: feature name '" + name + "' must be letters, digits or _");
    out.emplace_back(name, item.substr(eq + 1));
  }
  return out;
}

int run(const vpm::cli::Command& self, const std::vector<std::string>& argv) {
  vpm::cli::Args args(argv, self);
  args.expect_positional(1, vpm::cli::synopsis(self));
  const std::string mesh_path = args.positional()[0];
  const auto out = args.get("-o");
  if (!out) throw vpm::InputError("missing -o TABLE.h5; usage: " + vpm::cli::synopsis(self));
  vpm::cli::parse_option("-o", [&] { return vpm::table_format(*out); });  // before the work, not after
  if (!args.has("--images") && !args.has("--labels"))
    throw vpm::InputError("nothing to sample: give --images NAME=IMAGE[,...] and/or --labels LABELS");
  vpm::ElementTable table;
  table.definition = vpm::cli::element_definition(args);
  table.subject = args.get("--subject", "");
  table.mesh = mesh_path;
  const auto images = named_images(args.get("--images", ""));

  const vpm::TetMesh mesh = vpm::read_mesh(mesh_path);
  const vpm::Points native = vpm::native_positions(mesh, mesh_path);
  const vpm::CanonicalElements el(table.definition);
  const vpm::ElementSampler sampler(el, mesh.vertices, mesh.tets, native, vpm::Device::current());
  std::vector<vpm::Image> read;  // the images, then the label image
  for (const auto& [name, path] : images) read.push_back(vpm::read_image(path));
  if (const auto labels = args.get("--labels")) read.push_back(vpm::read_image(*labels));
  std::vector<vpm::NamedImage> features;
  for (size_t k = 0; k < images.size(); ++k) features.push_back({images[k].first, &read[k]});
  std::vector<const vpm::Image*> label_images;
  if (read.size() > images.size()) label_images.push_back(&read.back());
  vpm::ElementTable sampled = sampler.sample(features, label_images);
  table.features = std::move(sampled.features);
  table.label_images = std::move(sampled.label_images);
  vpm::write_subject_table(*out, table);
  const vpm::Placed& sampling = *sampler.placement().sampling;
  vpm::cli::info("wrote " + *out + (vpm::table_format(*out) == vpm::TableFormat::tsv ? " and " + vpm::sidecar_path(*out) : "") + ": " + std::to_string(el.size()) +
                 " elements x " + std::to_string(table.definition.samples) + " samples, " +
                 std::to_string(images.size()) + " features" + (args.has("--labels") ? " and label fractions" : "") +
                 "; sampled on " + (sampling.on_device ? "the device " + sampler.placement().device : "the host") + " (" +
                 sampling.reason + ")");
  return 0;
}

vpm::cli::Registrar reg(
    {"sample", "REGISTERED -o TABLE.h5", "per-element features of a subject: element samples read in its images; TABLE.h5 (HDF5) or TABLE.tsv (text)",
     {{"--images", "NAME=IMAGE[,NAME=IMAGE...]", "images to read (trilinear, world mm): columns NAME_mean/_std/_count"},
      {"--labels", "LABELS.nii[.gz]", "a label image: per-element label fractions (label_<id> columns)"},
      {"--subject", "ID", "subject id recorded in the sidecar"},
      {"--level", "L", "element definition: icosphere subdivisions (default 3)"},
      {"--shells", "K", "element definition: radial shells (default 8; layout shells)"},
      {"--layout", "shells|graded", "element definition: shells (default) or graded (near-cubic elements, K from L; vpm elements)"},
      {"--samples", "S", "element definition: samples per element (default 64)"}},
     run});

}  // namespace
