// Focus clusters measured in the patient's native space (vpm/map_back.hpp).
#include <cmath>
#include <iomanip>
#include <limits>
#include <map>

#include "core/atomic_file.hpp"
#include "vpm/map_back.hpp"

namespace vpm {

std::vector<NativeFocus> native_foci(const Image& foci, const Comparison& c, const Image* labels,
                                     const std::map<int, std::string>* names) {
  std::vector<NativeFocus> out(c.clusters.size());
  std::vector<std::map<int, long>> label_counts(out.size());
  for (size_t i = 0; i < out.size(); ++i) {
    out[i].id = c.clusters[i].id;
    out[i].peak_z = c.clusters[i].peak_z;
    out[i].p_family = c.clusters[i].p_family;
  }
  std::map<int, size_t> row;
  for (size_t i = 0; i < out.size(); ++i) row[out[i].id] = i;
  for (int k = 0; k < foci.dims[2]; ++k)
    for (int j = 0; j < foci.dims[1]; ++j)
      for (int i = 0; i < foci.dims[0]; ++i) {
        const int id = static_cast<int>(std::lround(foci.at(i, j, k)));
        const auto it = row.find(id);
        if (id <= 0 || it == row.end()) continue;
        NativeFocus& f = out[it->second];
        const Eigen::Vector3d x = foci.to_world(Eigen::Vector3d(i, j, k));
        f.centroid += x;
        ++f.voxels;
        if (labels) {
          const Eigen::Vector3d v = labels->to_voxel(x);
          const int a = static_cast<int>(std::lround(v(0))), b = static_cast<int>(std::lround(v(1))),
                    d = static_cast<int>(std::lround(v(2)));
          const bool in = a >= 0 && b >= 0 && d >= 0 && a < labels->dims[0] && b < labels->dims[1] && d < labels->dims[2];
          ++label_counts[it->second][in ? static_cast<int>(std::lround(labels->at(a, b, d))) : 0];
        }
      }
  const double voxel_mm3 = std::abs(foci.affine.topLeftCorner<3, 3>().determinant());
  for (size_t i = 0; i < out.size(); ++i) {
    NativeFocus& f = out[i];
    f.volume_mm3 = f.voxels * voxel_mm3;
    f.centroid = f.voxels > 0 ? Eigen::Vector3d(f.centroid / f.voxels)
                              : Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
    long best = 0;
    for (const auto& [label, n] : label_counts[i])
      if (label > 0 && n > best) {
        best = n;
        f.label = label;
      }
    f.label_fraction = f.voxels > 0 ? static_cast<double>(best) / f.voxels : 0.0;
    if (names && f.label > 0)
      if (const auto it = names->find(f.label); it != names->end()) f.region = it->second;
  }
  return out;
}

void write_native_foci(const std::string& tsv_path, const std::vector<NativeFocus>& foci) {
  detail::AtomicFile file(tsv_path);
  std::ostream& out = file.stream();
  out << "focus\tvoxels\tvolume_mm3\tcentroid_x\tcentroid_y\tcentroid_z\tpeak_z\tlabel\tlabel_fraction\tregion\tp_family\n"
      << std::setprecision(6);
  for (const NativeFocus& f : foci) {
    std::string region = f.region;  // one field whatever the table held
    for (char& ch : region)
      if (ch == '\t' || ch == '\n' || ch == '\r') ch = ' ';
    out << f.id << '\t' << f.voxels << '\t' << f.volume_mm3 << '\t' << f.centroid(0) << '\t' << f.centroid(1) << '\t'
        << f.centroid(2) << '\t' << f.peak_z << '\t' << f.label << '\t' << f.label_fraction << '\t' << region << '\t';
    if (f.p_family >= 0)
      out << f.p_family << '\n';
    else
      out << "NA\n";
  }
  file.commit();
}

}  // namespace vpm
