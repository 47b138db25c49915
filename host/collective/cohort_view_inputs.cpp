// The per-patient inputs of the collective view (vpm/cohort_view.hpp): the foci table and the
// image with its z-map for slice views, the template's atlas labels per element and their names.
#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "collective/cohort_view_detail.hpp"
#include "vpm/collective.hpp"
#include "vpm/error.hpp"
#include "vpm/image.hpp"
#include "vpm/io.hpp"

namespace vpm::detail {

std::vector<ViewFocus> read_view_foci(const std::string& path, const Comparison& c) {
  std::ifstream in(path);
  if (!in) throw InputError(path + ": cannot be read (the foci table of vpm compare --image)");
  std::string line;
  std::getline(in, line);
  std::vector<std::string> head;
  for (std::stringstream ss(line); std::getline(ss, line, '\t');) head.push_back(line);
  const auto col = [&](const std::string& name) {
    const auto it = std::find(head.begin(), head.end(), name);
    if (it == head.end()) throw InputError(path + ":1: no column '" + name + "'");
    return static_cast<size_t>(it - head.begin());
  };
  const size_t id = col("focus"), vol = col("volume_mm3"), pz = col("peak_z"), lab = col("label");
  const size_t cx[3] = {col("centroid_x"), col("centroid_y"), col("centroid_z")};
  std::vector<ViewFocus> out;
  for (int n = 2; std::getline(in, line); ++n) {
    if (line.empty()) continue;
    std::vector<std::string> cells;
    for (std::stringstream ss(line); std::getline(ss, line, '\t');) cells.push_back(line);
    if (cells.size() != head.size()) throw InputError(path + ":" + std::to_string(n) + ": expected " +
                                                      std::to_string(head.size()) + " columns");
    ViewFocus f;
    try {
      f.id = std::stoi(cells[id]);
      f.volume_mm3 = std::stod(cells[vol]);
      for (int a = 0; a < 3; ++a) f.centroid[a] = std::stod(cells[cx[a]]);
      f.peak_z = std::stod(cells[pz]);
      f.label = std::stoi(cells[lab]);
    } catch (const std::exception&) {
      throw InputError(path + ":" + std::to_string(n) + ": not a number");
    }
    for (const FocusCluster& cl : c.clusters)
      if (cl.id == f.id) f.peak_element = cl.peak_element;
    out.push_back(f);
  }
  return out;
}

namespace {

std::vector<std::uint8_t> scaled_bytes(const Image& image, const std::vector<size_t>& voxels) {
  std::vector<float> positive;
  for (size_t v : voxels)
    if (image.data[v] > 0 && std::isfinite(image.data[v])) positive.push_back(image.data[v]);
  float top = 1;
  if (!positive.empty()) {
    const size_t q = std::min(positive.size() - 1, static_cast<size_t>(0.995 * positive.size()));
    std::nth_element(positive.begin(), positive.begin() + static_cast<long>(q), positive.end());
    top = positive[q] > 0 ? positive[q] : 1;
  }
  std::vector<std::uint8_t> out(voxels.size());
  for (size_t i = 0; i < voxels.size(); ++i) {
    const float v = image.data[voxels[i]];
    out[i] = static_cast<std::uint8_t>(std::isfinite(v) ? std::clamp(v / top * 255.0f, 0.0f, 255.0f) : 0.0f);
  }
  return out;
}

}  // namespace

ViewSlices read_view_slices(const std::string& image_path, const std::string& z_path, long max_voxels) {
  const Image image = read_image(image_path);
  ViewSlices s;
  s.source = std::filesystem::absolute(image_path).lexically_normal().string();
  const double n = static_cast<double>(image.size());
  s.step = std::max(1, static_cast<int>(std::ceil(std::cbrt(n / std::max(1L, max_voxels)) - 1e-9)));
  for (int a = 0; a < 3; ++a) s.dims[a] = (image.dims[a] + s.step - 1) / s.step;
  s.affine = image.affine;
  s.affine.topLeftCorner<3, 3>() *= static_cast<double>(s.step);
  std::vector<size_t> voxels;
  voxels.reserve(static_cast<size_t>(s.dims[0]) * s.dims[1] * s.dims[2]);
  for (int k = 0; k < s.dims[2]; ++k)
    for (int j = 0; j < s.dims[1]; ++j)
      for (int i = 0; i < s.dims[0]; ++i) voxels.push_back(image.index(i * s.step, j * s.step, k * s.step));
  s.image = scaled_bytes(image, voxels);
  const Image z = read_image(z_path);
  if (z.dims != image.dims) throw InputError(z_path + ": the z-map's grid differs from the image's (" + image_path + ")");
  s.z.resize(voxels.size());
  for (size_t i = 0; i < voxels.size(); ++i) {
    const float v = z.data[voxels[i]];
    s.z[i] = static_cast<std::int8_t>(std::isfinite(v) ? std::clamp(std::lround(v * s.z_scale), -127L, 127L) : 0);
  }
  return s;
}

std::vector<int> element_labels(const CanonicalElements& el, const std::string& template_mesh) {
  const TetMesh t = read_mesh(template_mesh);
  const std::vector<int> labels = cell_labels(t);
  Points centres(el.size(), 3);
  for (int e = 0; e < el.size(); ++e) centres.row(e) = el.centre(e).transpose();
  return sample_labels(t.vertices, t.tets, labels, centres);
}

}  // namespace vpm::detail
