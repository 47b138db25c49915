#include "vpm/sampling.hpp"

#include <algorithm>
#include <cmath>
#include <map>

#include "core/parallel.hpp"
#include "vpm/error.hpp"
#include "vpm/locate.hpp"

namespace vpm {

Points pull_back_samples(const CanonicalElements& el, const Points& ball, const Tets& tets, const Points& native) {
  return pull_back_points(el.samples(), ball, tets, native);
}

ElementFeature sample_feature(const CanonicalElements& el, const Points& positions, const Image& image,
                              const std::string& name) {
  const int n = el.size(), S = el.definition().samples;
  ElementFeature f;
  f.name = name;
  f.source = image.path;
  f.mean.assign(n, 0.0);
  f.std.assign(n, 0.0);
  f.count.assign(n, 0);
  detail::parallel_for(n, 64, [&](int begin, int end) {
    for (int e = begin; e < end; ++e) {
      double sum = 0, sum2 = 0;
      int c = 0;
      for (int s = 0; s < S; ++s) {
        const Eigen::Vector3d x = positions.row(static_cast<Eigen::Index>(e) * S + s).transpose();
        if (!inside_grid(image, x)) continue;
        const double v = sample_image(image, x, Interpolation::linear);
        sum += v;
        sum2 += v * v;
        ++c;
      }
      f.count[e] = c;
      if (c == 0) continue;
      f.mean[e] = sum / c;
      f.std[e] = std::sqrt(std::max(0.0, sum2 / c - f.mean[e] * f.mean[e]));
    }
  });
  return f;
}

ElementLabels sample_label_fractions(const CanonicalElements& el, const Points& positions, const Image& labels) {
  const int n = el.size(), S = el.definition().samples;
  std::vector<int> lab(static_cast<size_t>(positions.rows()), 0);
  detail::parallel_for(static_cast<int>(positions.rows()), 4096, [&](int begin, int end) {
    for (int i = begin; i < end; ++i)
      lab[i] = static_cast<int>(std::lround(sample_image(labels, positions.row(i).transpose(), Interpolation::nearest)));
  });
  std::map<int, int> column;
  for (int l : lab)
    if (l != 0) column.emplace(l, 0);
  ElementLabels out;
  out.source = labels.path;
  for (auto& [l, c] : column) {
    c = static_cast<int>(out.labels.size());
    out.labels.push_back(l);
  }
  out.fraction.assign(out.labels.size(), std::vector<double>(n, 0.0));
  for (int e = 0; e < n; ++e)
    for (int s = 0; s < S; ++s) {
      const int l = lab[static_cast<size_t>(e) * S + s];
      if (l != 0) out.fraction[column.at(l)][e] += 1.0 / S;
    }
  return out;
}

}  // namespace vpm
