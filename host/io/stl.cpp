// STL surfaces, ASCII ("solid ... facet normal ... outer loop vertex x y z (x3) endloop endfacet
// ... endsolid") or binary (80-byte header, uint32 count, 50 bytes a triangle). Binary is
// recognised by its exact size (84 + 50 n), so binary files whose header starts with "solid"
// work too. Vertices with exactly equal coordinates are merged (-0 == +0); normals are ignored.
// Errors in binary files give the byte offset ("PATH:byte N: ...").
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <unordered_map>

#include <Eigen/Geometry>

#include "core/atomic_file.hpp"
#include "io/formats.hpp"
#include "io/text.hpp"
#include "vpm/error.hpp"

namespace vpm::detail {

namespace {

static_assert(std::endian::native == std::endian::little, "binary STL code assumes little endian");

struct Key {
  double x, y, z;
  bool operator==(const Key& o) const { return x == o.x && y == o.y && z == o.z; }
};
struct KeyHash {
  size_t operator()(const Key& k) const {
    auto bits = [](double d) {
      d += 0.0;  // -0 -> +0
      uint64_t u;
      std::memcpy(&u, &d, 8);
      return u;
    };
    uint64_t h = bits(k.x) * 0x9E3779B97F4A7C15ULL;
    h ^= bits(k.y) + 0x7F4A7C159E3779B9ULL + (h << 6) + (h >> 2);
    h ^= bits(k.z) + 0x94D049BB133111EBULL + (h << 6) + (h >> 2);
    return static_cast<size_t>(h ^ (h >> 31));
  }
};

// Collects triangle corners, merging exactly equal points.
class Merger {
 public:
  explicit Merger(size_t triangles) { index_.reserve(triangles); tris_.reserve(triangles * 3); }
  void add(double x, double y, double z) {
    Key k{x + 0.0, y + 0.0, z + 0.0};
    auto [it, inserted] = index_.try_emplace(k, static_cast<int>(xyz_.size() / 3));
    if (inserted) xyz_.insert(xyz_.end(), {k.x, k.y, k.z});
    tris_.push_back(it->second);
  }
  TriSurface surface() {
    TriSurface s;
    s.vertices = Eigen::Map<Points>(xyz_.data(), static_cast<Eigen::Index>(xyz_.size() / 3), 3);
    s.triangles = Eigen::Map<Triangles>(tris_.data(), static_cast<Eigen::Index>(tris_.size() / 3), 3);
    return s;
  }

 private:
  std::unordered_map<Key, int, KeyHash> index_;
  std::vector<double> xyz_;
  std::vector<int> tris_;
};

[[noreturn]] void fail_byte(const std::string& path, size_t offset, const std::string& what) {
  throw InputError(path + ":byte " + std::to_string(offset) + ": " + what);
}

TriSurface read_binary(const std::string& path, const std::string& data) {
  if (data.size() < 84)
    fail_byte(path, data.size(), "binary STL shorter than its 84-byte header (truncated file?)");
  uint32_t count = 0;
  std::memcpy(&count, data.data() + 80, 4);
  const unsigned long long need = 84ULL + 50ULL * count;
  if (need != data.size())
    fail_byte(path, 80, "binary STL declares " + std::to_string(count) + " triangles (" +
                            std::to_string(need) + " bytes) but the file has " +
                            std::to_string(data.size()) + " bytes (truncated or wrong count)");
  Merger merge(count);
  for (uint32_t t = 0; t < count; ++t) {
    const size_t base = 84 + 50 * static_cast<size_t>(t);
    for (int c = 0; c < 3; ++c) {
      float v[3];
      std::memcpy(v, data.data() + base + 12 + 12 * static_cast<size_t>(c), 12);
      for (int k = 0; k < 3; ++k)
        if (!std::isfinite(v[k]))
          fail_byte(path, base + 12 + 12 * static_cast<size_t>(c) + 4 * static_cast<size_t>(k),
                    "triangle " + std::to_string(t) + ": coordinate is not a finite number");
      merge.add(v[0], v[1], v[2]);
    }
  }
  return merge.surface();
}

// Line by line: "solid NAME", then per facet the lines "facet normal nx ny nz", "outer loop",
// three "vertex x y z", "endloop", "endfacet"; "endsolid NAME"; several solids may follow.
TriSurface read_ascii(const std::string& path, const std::string& data) {
  Scanner s(path, data, '\0');
  std::vector<std::string_view> t;
  Merger merge(data.size() / 64);  // a facet takes >= ~64 bytes of text: generous reserve
  auto expect = [&](const char* word, size_t values, const char* what) {
    s.need_line(t, std::string("'") + word + "'");
    if (t[0] != word) s.fail(std::string("expected '") + word + "', found " + show(t[0]));
    if (t.size() < 1 + values)
      s.fail(std::string("'") + word + "' line has " + std::to_string(t.size() - 1) + " values, expected " +
             std::to_string(values) + " (" + what + ")");
  };
  bool in_solid = false;
  while (s.next_line(t)) {
    if (!in_solid) {
      if (t[0] != "solid") s.fail("expected 'solid', found " + show(t[0]));
      in_solid = true;
    } else if (t[0] == "endsolid") {
      in_solid = false;
    } else if (t[0] == "facet") {
      if (t.size() < 5 || t[1] != "normal") s.fail("expected 'facet normal nx ny nz'");
      for (size_t k = 2; k < 5; ++k) s.to_real(t[k], "a normal component");
      expect("outer", 1, "loop");
      if (t[1] != "loop") s.fail("expected 'outer loop'");
      for (int c = 0; c < 3; ++c) {
        expect("vertex", 3, "x y z");
        double v[3];
        for (int k = 0; k < 3; ++k) v[k] = s.to_real(t[1 + static_cast<size_t>(k)], "a vertex coordinate");
        merge.add(v[0], v[1], v[2]);
      }
      expect("endloop", 0, "");
      expect("endfacet", 0, "");
    } else {
      s.fail("expected 'facet' or 'endsolid', found " + show(t[0]));
    }
  }
  if (in_solid) s.fail("unexpected end of file (truncated?): expected 'endsolid'");
  return merge.surface();
}

Eigen::RowVector3d normal_of(const TriSurface& s, Eigen::Index i) {
  const Eigen::RowVector3d a = s.vertices.row(s.triangles(i, 0)), b = s.vertices.row(s.triangles(i, 1)),
                           c = s.vertices.row(s.triangles(i, 2));
  Eigen::RowVector3d n = (b - a).cross(c - a);
  const double len = n.norm();
  return len > 0 ? Eigen::RowVector3d(n / len) : Eigen::RowVector3d::Zero();
}

}  // namespace

TriSurface read_stl(const std::string& path) {
  const std::string data = read_whole_file(path);
  if (data.size() >= 84) {
    uint32_t count = 0;
    std::memcpy(&count, data.data() + 80, 4);
    if (84ULL + 50ULL * count == data.size()) return read_binary(path, data);
  }
  size_t i = 0;
  while (i < data.size() && std::isspace(static_cast<unsigned char>(data[i]))) ++i;
  if (data.compare(i, 5, "solid") == 0) return read_ascii(path, data);
  return read_binary(path, data);
}

void write_stl(const std::string& path, const TriSurface& surf, bool binary) {
  AtomicFile file(path, binary);
  if (binary) {
    char header[80] = {};
    std::strncpy(header, "binary STL written by vpm", sizeof header);
    file.stream().write(header, 80);
    const uint32_t count = static_cast<uint32_t>(surf.triangles.rows());
    file.stream().write(reinterpret_cast<const char*>(&count), 4);
    std::string buf;
    buf.reserve(50 * static_cast<size_t>(count));
    for (Eigen::Index i = 0; i < surf.triangles.rows(); ++i) {
      float rec[12];
      const Eigen::RowVector3d n = normal_of(surf, i);
      for (int k = 0; k < 3; ++k) rec[k] = static_cast<float>(n(k));
      for (int c = 0; c < 3; ++c)
        for (int k = 0; k < 3; ++k) rec[3 + 3 * c + k] = static_cast<float>(surf.vertices(surf.triangles(i, c), k));
      buf.append(reinterpret_cast<const char*>(rec), 48);
      buf.append(2, '\0');
    }
    file.stream().write(buf.data(), static_cast<std::streamsize>(buf.size()));
  } else {
    TextOut o(file.stream());
    o << "solid vpm\n";
    for (Eigen::Index i = 0; i < surf.triangles.rows(); ++i) {
      const Eigen::RowVector3d n = normal_of(surf, i);
      o << "facet normal ";
      o.real(n(0)) << ' ';
      o.real(n(1)) << ' ';
      o.real(n(2)) << "\n  outer loop\n";
      for (int c = 0; c < 3; ++c) {
        o << "    vertex ";
        for (int k = 0; k < 3; ++k) {
          if (k) o << ' ';
          o.real(surf.vertices(surf.triangles(i, c), k));
        }
        o << '\n';
      }
      o << "  endloop\nendfacet\n";
    }
    o << "endsolid vpm\n";
    o.flush();
  }
  file.commit();
}

}  // namespace vpm::detail
