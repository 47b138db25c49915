// Geomview .off surfaces: "OFF" (also COFF/NOFF/CNOFF: extra vertex columns ignored), counts
// "nv nf ne" (on the OFF line or the next), nv vertex lines, nf face lines "k i1 .. ik [color]",
// 0-based; polygons are fan-triangulated. '#' starts a comment.
#include "core/atomic_file.hpp"
#include "io/formats.hpp"
#include "io/text.hpp"
#include "vpm/error.hpp"

namespace vpm::detail {

TriSurface read_off(const std::string& path) {
  const std::string data = read_whole_file(path);
  Scanner s(path, data);
  std::vector<std::string_view> t;
  s.need_line(t, "the OFF header");
  const std::string_view head = t[0];
  if (head.size() < 3 || head.substr(head.size() - 3) != "OFF" || head.size() > 5)
    s.fail("not an OFF file: first word is " + show(head) + ", expected OFF");
  if (t.size() == 1) s.need_line(t, "the counts 'vertices faces edges'");
  else t.erase(t.begin());
  if (t.size() < 2) s.fail("expected the counts 'vertices faces edges', found " + std::to_string(t.size()) + " value(s)");
  const int nv = s.to_count(t[0], "the number of vertices");
  const int nf = s.to_count(t[1], "the number of faces");
  s.check_fits(nv, 3, "vertices");
  s.check_fits(nf, 4, "faces");
  s.check_fits(static_cast<long long>(nv) + nf, 3, "vertices and faces");
  TriSurface surf;
  surf.vertices.resize(nv, 3);
  for (int i = 0; i < nv; ++i) {
    s.need_line_lazy(t, [&] { return "vertex " + std::to_string(i + 1) + " of " + std::to_string(nv); });
    if (t.size() < 3) s.fail("vertex line has " + std::to_string(t.size()) + " values, expected 3 (x y z)");
    for (int k = 0; k < 3; ++k) surf.vertices(i, k) = s.to_real(t[static_cast<size_t>(k)], "a coordinate");
  }
  std::vector<int> tris;
  tris.reserve(static_cast<size_t>(nf) * 3);
  std::vector<int> poly;
  for (int f = 0; f < nf; ++f) {
    s.need_line_lazy(t, [&] { return "face " + std::to_string(f + 1) + " of " + std::to_string(nf); });
    const int k = s.to_count(t[0], "the number of face vertices");
    if (k < 3) s.fail("face " + std::to_string(f) + " has " + std::to_string(k) + " vertices, need at least 3");
    if (t.size() < 1 + static_cast<size_t>(k))
      s.fail("face " + std::to_string(f) + " declares " + std::to_string(k) + " vertices but lists " +
             std::to_string(t.size() - 1) + " (wrong count)");
    poly.clear();
    for (int j = 0; j < k; ++j) {
      const long long v = s.to_int(t[1 + static_cast<size_t>(j)], "a vertex index");
      if (v < 0 || v >= nv)
        s.fail("face " + std::to_string(f) + ": vertex index " + std::to_string(v) + " out of range 0.." +
               std::to_string(nv - 1) + (v == nv ? " (OFF is 0-based; the file looks 1-based)" : ""));
      poly.push_back(static_cast<int>(v));
    }
    for (int j = 1; j + 1 < k; ++j) tris.insert(tris.end(), {poly[0], poly[static_cast<size_t>(j)], poly[static_cast<size_t>(j) + 1]});
  }
  if (!s.at_end()) s.fail("unexpected data after the " + std::to_string(nf) + " faces the header declares (wrong count)");
  surf.triangles = Eigen::Map<Triangles>(tris.data(), static_cast<Eigen::Index>(tris.size() / 3), 3);
  return surf;
}

void write_off(const std::string& path, const TriSurface& surf) {
  AtomicFile file(path);
  TextOut o(file.stream());
  o << "OFF\n";
  o.integer(surf.vertices.rows()) << ' ';
  o.integer(surf.triangles.rows()) << " 0\n";
  for (Eigen::Index i = 0; i < surf.vertices.rows(); ++i) {
    o.real(surf.vertices(i, 0)) << ' ';
    o.real(surf.vertices(i, 1)) << ' ';
    o.real(surf.vertices(i, 2)) << '\n';
  }
  for (Eigen::Index i = 0; i < surf.triangles.rows(); ++i) {
    o << '3';
    for (int k = 0; k < 3; ++k) o << ' ', o.integer(surf.triangles(i, k));
    o << '\n';
  }
  o.flush();
  file.commit();
}

}  // namespace vpm::detail
