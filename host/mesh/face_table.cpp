#include "mesh/face_table.hpp"

#include <algorithm>
#include <array>
#include <numeric>

#include "core/parallel.hpp"

namespace vpm::detail {

namespace {
// the three other corners of corner k, as in topology's outward faces
constexpr int kOpposite[4][3] = {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}};

std::array<int, 3> sorted_face(const Tets& tets, int t, int k) {
  std::array<int, 3> s = {tets(t, kOpposite[k][0]), tets(t, kOpposite[k][1]), tets(t, kOpposite[k][2])};
  if (s[0] > s[1]) std::swap(s[0], s[1]);
  if (s[1] > s[2]) std::swap(s[1], s[2]);
  if (s[0] > s[1]) std::swap(s[0], s[1]);
  return s;
}
}  // namespace

FaceTable face_table(const Tets& tets) {
  FaceTable ft;
  const int m = static_cast<int>(tets.rows());
  const int n = m > 0 ? tets.maxCoeff() + 1 : 0;
  ft.start.assign(static_cast<size_t>(n) + 1, 0);
  for (int t = 0; t < m; ++t)
    for (int k = 0; k < 4; ++k) ++ft.start[static_cast<size_t>(sorted_face(tets, t, k)[0]) + 1];
  std::partial_sum(ft.start.begin(), ft.start.end(), ft.start.begin());
  ft.entries.resize(4 * static_cast<size_t>(m));
  std::vector<int> cursor(ft.start.begin(), ft.start.end() - 1);
  for (int t = 0; t < m; ++t)
    for (int k = 0; k < 4; ++k) {
      const std::array<int, 3> s = sorted_face(tets, t, k);
      const std::uint64_t rest = (static_cast<std::uint64_t>(s[1]) << 32) | static_cast<std::uint32_t>(s[2]);
      ft.entries[static_cast<size_t>(cursor[static_cast<size_t>(s[0])]++)] = {rest, 4 * t + k};
    }
  parallel_for(n, 4096, [&](int v0, int v1) {
    for (int v = v0; v < v1; ++v)
      std::sort(ft.entries.begin() + ft.start[static_cast<size_t>(v)],
                ft.entries.begin() + ft.start[static_cast<size_t>(v) + 1],
                [](const FaceTable::Entry& a, const FaceTable::Entry& b) {
                  return a.rest != b.rest ? a.rest < b.rest : a.slot < b.slot;
                });
  });
  return ft;
}

}  // namespace vpm::detail
