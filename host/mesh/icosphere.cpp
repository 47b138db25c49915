#include "vpm/icosphere.hpp"

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "vpm/error.hpp"

namespace vpm {

TriSurface icosphere(int level) {
  if (level < 0 || level > 10) throw InputError("icosphere: level " + std::to_string(level) + " is not in 0..10");
  const double t = (1 + std::sqrt(5.0)) / 2;
  std::vector<Eigen::Vector3d> V = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                                    {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  for (auto& v : V) v.normalize();
  std::vector<std::array<int, 3>> F = {{0, 11, 5}, {0, 5, 1}, {0, 1, 7}, {0, 7, 10}, {0, 10, 11},
                                       {1, 5, 9}, {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                       {3, 9, 4}, {3, 4, 2}, {3, 2, 6}, {3, 6, 8}, {3, 8, 9},
                                       {4, 9, 5}, {2, 4, 11}, {6, 2, 10}, {8, 6, 7}, {9, 8, 1}};
  for (int l = 0; l < level; ++l) {
    std::map<std::pair<int, int>, int> mid;
    auto m = [&](int i, int j) {
      const auto key = std::minmax(i, j);
      const auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      V.push_back((V[i] + V[j]).normalized());
      return mid[key] = static_cast<int>(V.size()) - 1;
    };
    std::vector<std::array<int, 3>> G;
    G.reserve(4 * F.size());
    for (const auto& f : F) {
      const int ab = m(f[0], f[1]), bc = m(f[1], f[2]), ca = m(f[2], f[0]);
      G.push_back({f[0], ab, ca});
      G.push_back({f[1], bc, ab});
      G.push_back({f[2], ca, bc});
      G.push_back({ab, bc, ca});
    }
    F = std::move(G);
  }
  TriSurface s;
  s.vertices.resize(static_cast<Eigen::Index>(V.size()), 3);
  for (size_t i = 0; i < V.size(); ++i) s.vertices.row(static_cast<Eigen::Index>(i)) = V[i].transpose();
  s.triangles.resize(static_cast<Eigen::Index>(F.size()), 3);
  for (size_t i = 0; i < F.size(); ++i) s.triangles.row(static_cast<Eigen::Index>(i)) << F[i][0], F[i][1], F[i][2];
  return s;
}

}  // namespace vpm
