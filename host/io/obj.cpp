// Wavefront .obj surfaces: "v x y z [w]" and "f a b c ..." with a, a/b, a//c or a/b/c
// references (1-based, negative = relative to the last vertex); polygons are fan-triangulated.
// Every other statement (vn, vt, g, o, s, usemtl, l, ...) is ignored. '#' starts a comment.
#include <charconv>

#include "core/atomic_file.hpp"
#include "io/formats.hpp"
#include "io/text.hpp"
#include "vpm/error.hpp"

namespace vpm::detail {

TriSurface read_obj(const std::string& path) {
  const std::string data = read_whole_file(path);
  Scanner s(path, data);
  std::vector<std::string_view> t;
  std::vector<double> xyz;
  std::vector<long long> tris;       // 0-based, range-checked at the end
  std::vector<size_t> tri_line;      // line of each triangle
  std::vector<long long> poly;
  while (s.next_line(t)) {
    if (t[0] == "v") {
      if (t.size() < 4) s.fail("vertex line has " + std::to_string(t.size() - 1) + " values, expected 3 (x y z)");
      for (size_t k = 1; k <= 3; ++k) xyz.push_back(s.to_real(t[k], "a vertex coordinate"));
    } else if (t[0] == "f") {
      if (t.size() < 4) s.fail("face has " + std::to_string(t.size() - 1) + " vertices, need at least 3");
      poly.clear();
      const long long nv = static_cast<long long>(xyz.size() / 3);
      for (size_t k = 1; k < t.size(); ++k) {
        const std::string_view ref = t[k];
        const std::string_view idx = ref.substr(0, ref.find('/'));
        long long v = s.to_int(idx, "a face vertex index");
        if (v == 0) s.fail("face vertex index 0: OBJ indices start at 1 (the file looks 0-based)");
        if (v < 0) {
          if (-v > nv) s.fail("relative face vertex index " + std::to_string(v) + " reaches before the first vertex");
          v = nv + v;
        } else {
          v -= 1;
        }
        poly.push_back(v);
      }
      for (size_t j = 1; j + 1 < poly.size(); ++j) {
        tris.insert(tris.end(), {poly[0], poly[j], poly[j + 1]});
        tri_line.push_back(s.line());
      }
    }
  }
  const long long nv = static_cast<long long>(xyz.size() / 3);
  TriSurface surf;
  surf.vertices = Eigen::Map<Points>(xyz.data(), nv, 3);
  surf.triangles.resize(static_cast<Eigen::Index>(tris.size() / 3), 3);
  for (size_t i = 0; i < tris.size(); ++i) {
    if (tris[i] >= nv)
      s.fail_at(tri_line[i / 3], "face vertex index " + std::to_string(tris[i] + 1) + " out of range 1.." +
                                     std::to_string(nv));
    surf.triangles(static_cast<Eigen::Index>(i / 3), static_cast<Eigen::Index>(i % 3)) = static_cast<int>(tris[i]);
  }
  return surf;
}

void write_obj(const std::string& path, const TriSurface& surf) {
  AtomicFile file(path);
  TextOut o(file.stream());
  o << "# written by vpm\n";
  for (Eigen::Index i = 0; i < surf.vertices.rows(); ++i) {
    o << "v ";
    o.real(surf.vertices(i, 0)) << ' ';
    o.real(surf.vertices(i, 1)) << ' ';
    o.real(surf.vertices(i, 2)) << '\n';
  }
  for (Eigen::Index i = 0; i < surf.triangles.rows(); ++i) {
    o << 'f';
    for (int k = 0; k < 3; ++k) o << ' ', o.integer(surf.triangles(i, k) + 1);
    o << '\n';
  }
  o.flush();
  file.commit();
}

}  // namespace vpm::detail
