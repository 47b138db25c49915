// mesh-image pipeline: mask -> smoothed grid -> topology repair -> marching tetrahedra ->
// remeshing (host/with_cgal) -> TetGen (host/with_tetgen) -> labels.
#include "vpm/mesh_image.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <ctime>
#include <fstream>
#include <map>
#include <numeric>
#include <sstream>
#include <unordered_map>

#include "vpm/config.hpp"
#include "vpm/error.hpp"
#include "vpm/geometry.hpp"
#include "vpm/io.hpp"
#include "vpm/topology.hpp"
#include "vpm/format.hpp"
#include "vpm/timing.hpp"

namespace vpm {

namespace {

// report.timings_s[key] = wall seconds, report.cpu_s[key] = process CPU seconds.
void record(Json& report, const std::string& key, const Stopwatch& t0) {
  report["timings_s"][key] = t0.seconds();
  report["cpu_s"][key] = t0.cpu_seconds();
}

std::string world_str(const Image& img, int i, int j, int k) {
  const Eigen::Vector3d w = img.to_world(Eigen::Vector3d(i, j, k));
  return "voxel (" + std::to_string(i) + "," + std::to_string(j) + "," + std::to_string(k) +
         ") = (" + format_sig(w.x()) + ", " + format_sig(w.y()) + ", " + format_sig(w.z()) + ") mm";
}

// ---- a 3-D grid of bytes with flood fills -------------------------------------------------

struct Grid3 {
  int nx = 0, ny = 0, nz = 0;
  size_t size() const { return size_t(nx) * ny * nz; }
  size_t idx(int x, int y, int z) const { return size_t(x) + size_t(nx) * (size_t(y) + size_t(ny) * z); }
};

// Neighbour offsets: 6-connectivity, or the 14 edges of the Freudenthal (Kuhn) split used by
// marching tetrahedra (axes, the three (+,+) face diagonals, the (+,+,+) diagonal, and negatives).
const int kN6[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
const int kN14[14][3] = {{1, 0, 0},  {-1, 0, 0}, {0, 1, 0},  {0, -1, 0},  {0, 0, 1},
                         {0, 0, -1}, {1, 1, 0},  {-1, -1, 0}, {1, 0, 1},  {-1, 0, -1},
                         {0, 1, 1},  {0, -1, -1}, {1, 1, 1},  {-1, -1, -1}};

// Labels the connected components of voxels with value == `value` (comp id >= 0; others -1).
// Returns the component sizes.
template <int N>
std::vector<size_t> components(const Grid3& g, const std::vector<uint8_t>& v, uint8_t value,
                               const int (&nb)[N][3], std::vector<int>& comp) {
  comp.assign(g.size(), -1);
  std::vector<size_t> sizes;
  std::vector<size_t> stack;
  for (int z = 0; z < g.nz; ++z)
    for (int y = 0; y < g.ny; ++y)
      for (int x = 0; x < g.nx; ++x) {
        const size_t s = g.idx(x, y, z);
        if (v[s] != value || comp[s] >= 0) continue;
        const int id = int(sizes.size());
        size_t count = 0;
        comp[s] = id;
        stack.push_back(s);
        while (!stack.empty()) {
          const size_t p = stack.back();
          stack.pop_back();
          ++count;
          const int px = int(p % g.nx), py = int((p / g.nx) % g.ny), pz = int(p / (size_t(g.nx) * g.ny));
          for (int k = 0; k < N; ++k) {
            const int qx = px + nb[k][0], qy = py + nb[k][1], qz = pz + nb[k][2];
            if (qx < 0 || qy < 0 || qz < 0 || qx >= g.nx || qy >= g.ny || qz >= g.nz) continue;
            const size_t q = g.idx(qx, qy, qz);
            if (v[q] == value && comp[q] < 0) {
              comp[q] = id;
              stack.push_back(q);
            }
          }
        }
        sizes.push_back(count);
      }
  return sizes;
}

// Keeps the largest foreground component and fills every background component that does
// not touch the grid border. Returns {foreground components removed, cavities filled}.
template <int N>
std::pair<int, int> keep_largest_fill_cavities(const Grid3& g, std::vector<uint8_t>& m, const int (&nb)[N][3]) {
  std::vector<int> comp;
  auto sizes = components(g, m, 1, nb, comp);
  int removed = 0, filled = 0;
  if (sizes.size() > 1) {
    const int best = int(std::max_element(sizes.begin(), sizes.end()) - sizes.begin());
    for (size_t i = 0; i < m.size(); ++i)
      if (m[i] && comp[i] != best) m[i] = 0;
    removed = int(sizes.size()) - 1;
  }
  sizes = components(g, m, 0, nb, comp);
  std::vector<char> outside(sizes.size(), 0);
  for (int z = 0; z < g.nz; ++z)
    for (int y = 0; y < g.ny; ++y)
      for (int x = 0; x < g.nx; ++x) {
        if (x != 0 && y != 0 && z != 0 && x != g.nx - 1 && y != g.ny - 1 && z != g.nz - 1) continue;
        const size_t s = g.idx(x, y, z);
        if (comp[s] >= 0) outside[comp[s]] = 1;
      }
  for (size_t c = 0; c < sizes.size(); ++c) filled += !outside[c];
  if (filled)
    for (size_t i = 0; i < m.size(); ++i)
      if (!m[i] && !outside[comp[i]]) m[i] = 1;
  return {removed, filled};
}

// Morphological dilation (value 1 grows) or erosion (value 0 grows) by a Euclidean ball of
// radius r cells, stamping only around boundary cells.
void morph(const Grid3& g, std::vector<uint8_t>& m, int r, bool dilate) {
  std::vector<std::array<int, 3>> ball;
  for (int z = -r; z <= r; ++z)
    for (int y = -r; y <= r; ++y)
      for (int x = -r; x <= r; ++x)
        if (x * x + y * y + z * z <= r * r) ball.push_back({x, y, z});
  const uint8_t grow = dilate ? 1 : 0;
  std::vector<uint8_t> out = m;
  for (int z = 0; z < g.nz; ++z)
    for (int y = 0; y < g.ny; ++y)
      for (int x = 0; x < g.nx; ++x) {
        const size_t s = g.idx(x, y, z);
        if (m[s] != grow) continue;
        bool edge = false;
        for (int k = 0; k < 6 && !edge; ++k) {
          const int qx = x + kN6[k][0], qy = y + kN6[k][1], qz = z + kN6[k][2];
          if (qx < 0 || qy < 0 || qz < 0 || qx >= g.nx || qy >= g.ny || qz >= g.nz) continue;
          edge = m[g.idx(qx, qy, qz)] != grow;
        }
        if (!edge) continue;
        for (const auto& o : ball) {
          const int qx = x + o[0], qy = y + o[1], qz = z + o[2];
          if (qx < 0 || qy < 0 || qz < 0 || qx >= g.nx || qy >= g.ny || qz >= g.nz) continue;
          out[g.idx(qx, qy, qz)] = grow;
        }
      }
  m.swap(out);
}

// ---- marching tetrahedra on the Freudenthal split ----------------------------------------

// Extracts the level set f = iso of the piecewise-linear interpolation of `f` on the Kuhn
// split of the grid cells. Vertices in grid index coordinates; triangles oriented with
// normals pointing from f > iso to f < iso. No grid value may equal iso.
TriSurface marching_tets(const Grid3& g, const std::vector<float>& f, float iso) {
  TriSurface s;
  std::vector<Eigen::Vector3d> pts;
  std::vector<std::array<int, 3>> tris;
  std::unordered_map<uint64_t, int> edge_vertex;
  edge_vertex.reserve(1 << 16);
  auto corner = [&](int b) { return std::array<int, 3>{b & 1, (b >> 1) & 1, (b >> 2) & 1}; };
  // The six Kuhn tets of a cube as corner bit masks, positively oriented.
  int kuhn[6][4];
  {
    const int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
    for (int p = 0; p < 6; ++p) {
      const int a0 = perms[p][0], a1 = perms[p][1], a2 = perms[p][2];
      int v1 = 1 << a0, v2 = v1 | (1 << a1);
      kuhn[p][0] = 0, kuhn[p][1] = v1, kuhn[p][2] = v2, kuhn[p][3] = 7;
      // orientation = sign of the permutation (a0 a1 a2)
      const int inv = (a0 > a1) + (a0 > a2) + (a1 > a2);
      if (inv % 2) std::swap(kuhn[p][2], kuhn[p][3]);
    }
  }
  auto gidx = [&](int x, int y, int z) -> uint64_t { return g.idx(x, y, z); };
  auto vertex_on = [&](uint64_t p, uint64_t q, const Eigen::Vector3d& pp, const Eigen::Vector3d& pq) -> int {
    const uint64_t key = std::min(p, q) * uint64_t(g.size()) + std::max(p, q);
    auto it = edge_vertex.find(key);
    if (it != edge_vertex.end()) return it->second;
    double t = (double(iso) - f[p]) / (double(f[q]) - f[p]);
    t = std::clamp(t, 0.02, 0.98);
    pts.push_back(pp + t * (pq - pp));
    const int id = int(pts.size()) - 1;
    edge_vertex.emplace(key, id);
    return id;
  };
  for (int z = 0; z + 1 < g.nz; ++z)
    for (int y = 0; y + 1 < g.ny; ++y)
      for (int x = 0; x + 1 < g.nx; ++x) {
        uint64_t id[8];
        bool in[8];
        int nin = 0;
        for (int b = 0; b < 8; ++b) {
          const auto c = corner(b);
          id[b] = gidx(x + c[0], y + c[1], z + c[2]);
          in[b] = f[id[b]] > iso;
          nin += in[b];
        }
        if (nin == 0 || nin == 8) continue;
        for (int t = 0; t < 6; ++t) {
          int vi[4], nin_t = 0;
          Eigen::Vector3d P[4];
          for (int k = 0; k < 4; ++k) {
            vi[k] = kuhn[t][k];
            const auto c = corner(vi[k]);
            P[k] = Eigen::Vector3d(x + c[0], y + c[1], z + c[2]);
            nin_t += in[vi[k]];
          }
          if (nin_t == 0 || nin_t == 4) continue;
          std::vector<int> ins, outs;
          for (int k = 0; k < 4; ++k) (in[vi[k]] ? ins : outs).push_back(k);
          auto V = [&](int a, int b) { return vertex_on(id[vi[a]], id[vi[b]], P[a], P[b]); };
          auto det = [&](int a, int b, int c, int d) {
            return (P[b] - P[a]).dot((P[c] - P[a]).cross(P[d] - P[a]));
          };
          if (ins.size() == 1) {
            const int a = ins[0], b = outs[0], c = outs[1], d = outs[2];
            std::array<int, 3> tri{V(a, b), V(a, c), V(a, d)};
            if (det(a, b, c, d) < 0) std::swap(tri[1], tri[2]);
            tris.push_back(tri);
          } else if (ins.size() == 3) {
            const int d = outs[0], a = ins[0], b = ins[1], c = ins[2];
            std::array<int, 3> tri{V(a, d), V(b, d), V(c, d)};
            if (det(d, a, b, c) > 0) std::swap(tri[1], tri[2]);
            tris.push_back(tri);
          } else {
            const int a = ins[0], b = ins[1], c = outs[0], d = outs[1];
            const int q[4] = {V(a, c), V(a, d), V(b, d), V(b, c)};
            // Newell normal of the quad vs the in -> out direction
            Eigen::Vector3d n = Eigen::Vector3d::Zero();
            for (int k = 0; k < 4; ++k) n += pts[q[k]].cross(pts[q[(k + 1) % 4]]);
            const Eigen::Vector3d dir = P[c] + P[d] - P[a] - P[b];
            if (n.dot(dir) >= 0) {
              tris.push_back({q[0], q[1], q[2]});
              tris.push_back({q[0], q[2], q[3]});
            } else {
              tris.push_back({q[0], q[2], q[1]});
              tris.push_back({q[0], q[3], q[2]});
            }
          }
        }
      }
  s.vertices.resize(Eigen::Index(pts.size()), 3);
  for (size_t i = 0; i < pts.size(); ++i) s.vertices.row(Eigen::Index(i)) = pts[i].transpose();
  s.triangles.resize(Eigen::Index(tris.size()), 3);
  for (size_t i = 0; i < tris.size(); ++i)
    for (int c = 0; c < 3; ++c) s.triangles(Eigen::Index(i), c) = tris[i][c];
  return s;
}

// ---- Gaussian smoothing ----------------------------------------------------------------

void blur_axis(std::vector<float>& v, const Grid3& g, int axis, double sigma) {
  if (sigma <= 0) return;
  const int r = int(std::ceil(3 * sigma));
  std::vector<float> w(2 * r + 1);
  double sum = 0;
  for (int k = -r; k <= r; ++k) sum += w[k + r] = float(std::exp(-0.5 * k * k / (sigma * sigma)));
  for (auto& x : w) x = float(x / sum);
  const int n = axis == 0 ? g.nx : axis == 1 ? g.ny : g.nz;
  const size_t stride = axis == 0 ? 1 : axis == 1 ? size_t(g.nx) : size_t(g.nx) * g.ny;
  std::vector<float> line(n), out(n);
  const int na = axis == 0 ? g.ny : g.nx, nb = axis == 2 ? g.ny : g.nz;
  for (int b = 0; b < nb; ++b)
    for (int a = 0; a < na; ++a) {
      size_t base;
      if (axis == 0) base = g.idx(0, a, b);
      else if (axis == 1) base = g.idx(a, 0, b);
      else base = g.idx(a, b, 0);
      bool any = false;
      for (int i = 0; i < n; ++i) {
        line[i] = v[base + i * stride];
        any |= line[i] != 0;
      }
      if (!any) continue;
      for (int i = 0; i < n; ++i) {
        double acc = 0;
        const int lo = std::max(-r, -i), hi = std::min(r, n - 1 - i);
        for (int k = lo; k <= hi; ++k) acc += w[k + r] * line[i + k];
        out[i] = float(acc);
      }
      for (int i = 0; i < n; ++i) v[base + i * stride] = out[i];
    }
}

double mean_edge(const TriSurface& s) {
  double sum = 0;
  for (int f = 0; f < s.triangles.rows(); ++f)
    for (int c = 0; c < 3; ++c)
      sum += (s.vertices.row(s.triangles(f, c)) - s.vertices.row(s.triangles(f, (c + 1) % 3))).norm();
  return s.triangles.rows() ? sum / (3.0 * s.triangles.rows()) : 0;
}

double enclosed_volume(const TriSurface& s) {
  double v = 0;
  for (int f = 0; f < s.triangles.rows(); ++f) {
    const Eigen::Vector3d a = s.vertices.row(s.triangles(f, 0)), b = s.vertices.row(s.triangles(f, 1)),
                          c = s.vertices.row(s.triangles(f, 2));
    v += a.dot(b.cross(c)) / 6;
  }
  return v;
}

// Constants relating the requested vertex count to the surface edge length and TetGen's
// volume bound (calibrated on Colin27, see docs/mesh_image.md):
//   edge = kEdge * (V / N)^(1/3),  max_volume = kVol * V / N.
constexpr double kEdge = 0.98;
constexpr double kVol = 0.47;

struct Resolution {
  double edge = 0, max_volume = 0;
};

Resolution resolution_for(double volume, const MeshImageOptions& o) {
  Resolution r;
  if (o.max_volume > 0) {
    r.max_volume = o.max_volume;
    r.edge = kEdge * std::cbrt(o.max_volume / kVol);
  } else {
    if (o.target_vertices < 10)
      throw InputError("--target-vertices " + std::to_string(o.target_vertices) + ": need at least 10");
    r.edge = kEdge * std::cbrt(volume / o.target_vertices);
    r.max_volume = kVol * volume / o.target_vertices;
  }
  return r;
}

Json surface_json(const TriSurface& s) {
  Json j = Json::object();
  const auto topo = surface_topology(int(s.vertices.rows()), s.triangles);
  const auto ang = triangle_angle_range_deg(s);
  j["vertices"] = int(s.vertices.rows());
  j["triangles"] = int(s.triangles.rows());
  j["euler"] = topo.euler;
  j["mean_edge_mm"] = mean_edge(s);
  j["min_angle_deg"] = ang.first;
  j["max_angle_deg"] = ang.second;
  return j;
}

void check_closed_genus0(const TriSurface& s, const std::string& source, const std::string& what) {
  const auto t = surface_topology(int(s.vertices.rows()), s.triangles);
  std::string why;
  if (t.open_edges) why = std::to_string(t.open_edges) + " open edges (e.g. " + std::to_string(t.first_bad_edge[0]) + "-" + std::to_string(t.first_bad_edge[1]) + ")";
  else if (t.nonmanifold_edges) why = std::to_string(t.nonmanifold_edges) + " non-manifold edges";
  else if (t.nonmanifold_vertices) why = std::to_string(t.nonmanifold_vertices) + " non-manifold vertices (e.g. vertex " + std::to_string(t.first_bad_vertex) + ")";
  else if (t.components != 1) why = std::to_string(t.components) + " connected components";
  else if (t.euler != 2) why = "genus " + std::to_string(t.genus()) + " (Euler characteristic " + std::to_string(t.euler) + ")";
  if (!why.empty()) throw InputError(source + ": " + what + " is not a closed genus-0 surface: " + why);
}

// Surface -> tets (+ report "surface", "mesh", "parameters"), shared by image and surface input.
TetMesh surface_to_tets(const TriSurface& raw, const Resolution& res, const MeshImageOptions& o,
                        Json& report, const std::string& source, bool already_checked) {
  if (!already_checked) check_closed_genus0(raw, source, "the input surface");
  Stopwatch t0;
  if (o.progress) o.progress("remeshing the surface to edge " + format_sig(res.edge, 3) + " mm");
  TriSurface s = remesh_surface(raw, res.edge, o.remesh_iterations);
  record(report, "remesh", t0);
  check_closed_genus0(s, source, "the remeshed surface");
  report["surface"] = surface_json(s);

  t0.restart();
  TetgenOptions to;
  to.radius_edge = o.radius_edge;
  to.min_dihedral_deg = o.min_dihedral_deg;
  to.max_volume = res.max_volume;
  if (o.progress) o.progress("tetrahedralising (TetGen)");
  Json tinfo = Json::object();
  TetMesh mesh = tetrahedralize_surface(s, to, &tinfo);
  record(report, "tetgen", t0);
  report["parameters"]["tetgen_switches"] = *tinfo.find("switches");

  const Triangles bf = boundary_faces(mesh.tets);
  const auto on_b = boundary_vertex_mask(mesh.num_vertices(), bf);
  const auto dih = dihedral_angles_deg(mesh.vertices, mesh.tets);
  const auto btopo = surface_topology(mesh.num_vertices(), bf);
  Json& m = report["mesh"];
  m["vertices"] = mesh.num_vertices();
  m["tets"] = mesh.num_tets();
  m["boundary_vertices"] = int(std::count(on_b.begin(), on_b.end(), 1));
  m["boundary_faces"] = int(bf.rows());
  m["boundary_euler"] = btopo.euler;
  m["min_dihedral_deg"] = dih.size() ? dih.minCoeff() : 0.0;
  m["max_dihedral_deg"] = dih.size() ? dih.maxCoeff() : 0.0;
  m["four_boundary_vertex_tets"] = *tinfo.find("four_boundary_vertex_tets");
  m["interior_points_added"] = *tinfo.find("interior_points_added");
  m["edge_splits"] = *tinfo.find("edge_splits");
  m["volume_mm3"] = tet_volumes(mesh.vertices, mesh.tets).sum();
  m["surface_volume_mm3"] = enclosed_volume(s);
  return mesh;
}

// Minimal OFF reader used until vpm::read_surface (vpm/io.hpp) lands on main.
TriSurface read_off_surface(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path + ": cannot open");
  std::string tok;
  auto next = [&](const char* what) {
    while (in >> tok) {
      if (tok[0] == '#') { std::string rest; std::getline(in, rest); continue; }
      return tok;
    }
    throw InputError(path + ": truncated: expected " + std::string(what));
  };
  if (next("OFF header") != "OFF") throw InputError(path + ": not an OFF file (no OFF header)");
  long nv, nf;
  try {
    nv = std::stol(next("vertex count"));
    nf = std::stol(next("face count"));
    next("edge count");
  } catch (const std::logic_error&) {
    throw InputError(path + ": OFF counts are not integers");
  }
  if (nv < 4 || nf < 4 || nv > 100000000 || nf > 200000000) throw InputError(path + ": implausible OFF counts");
  TriSurface s;
  s.vertices.resize(nv, 3);
  s.triangles.resize(nf, 3);
  for (long i = 0; i < nv; ++i)
    for (int d = 0; d < 3; ++d) {
      const std::string t = next("vertex coordinate");
      try { s.vertices(i, d) = std::stod(t); } catch (const std::logic_error&) {
        throw InputError(path + ": vertex " + std::to_string(i) + ": '" + t + "' is not a number");
      }
    }
  for (long f = 0; f < nf; ++f) {
    int k = 0;
    try {
      k = std::stoi(next("face"));
      if (k != 3) throw InputError(path + ": face " + std::to_string(f) + " has " + std::to_string(k) + " vertices (need triangles)");
      for (int c = 0; c < 3; ++c) {
        const long v = std::stol(next("face index"));
        if (v < 0 || v >= nv) throw InputError(path + ": face " + std::to_string(f) + ": vertex index " + std::to_string(v) + " out of range");
        s.triangles(f, c) = int(v);
      }
    } catch (const std::logic_error&) {
      throw InputError(path + ": face " + std::to_string(f) + ": not an integer");
    }
    std::string rest;
    std::getline(in, rest);
  }
  return s;
}

}  // namespace

// ---- public building blocks -------------------------------------------------------------

std::pair<double, double> triangle_angle_range_deg(const TriSurface& s) {
  double lo = 180, hi = 0;
  for (int f = 0; f < s.triangles.rows(); ++f) {
    Eigen::Vector3d p[3];
    for (int c = 0; c < 3; ++c) p[c] = s.vertices.row(s.triangles(f, c));
    for (int c = 0; c < 3; ++c) {
      const Eigen::Vector3d u = p[(c + 1) % 3] - p[c], v = p[(c + 2) % 3] - p[c];
      const double a = std::atan2(u.cross(v).norm(), u.dot(v)) * 180.0 / M_PI;
      lo = std::min(lo, a);
      hi = std::max(hi, a);
    }
  }
  return {lo, hi};
}

int count_four_boundary_vertex_tets(const TetMesh& mesh) {
  const Triangles bf = boundary_faces(mesh.tets);
  const auto on_b = boundary_vertex_mask(mesh.num_vertices(), bf);
  int n = 0;
  for (int t = 0; t < mesh.num_tets(); ++t)
    n += on_b[mesh.tets(t, 0)] && on_b[mesh.tets(t, 1)] && on_b[mesh.tets(t, 2)] && on_b[mesh.tets(t, 3)];
  return n;
}

Json label_mesh(TetMesh& mesh, const Image& atlas) {
  const int m = mesh.num_tets(), n = mesh.num_vertices();
  FieldValues cell(m, 1), point(n, 1);
  const Eigen::Matrix3d inv = atlas.affine.topLeftCorner<3, 3>().inverse();
  const Eigen::Vector3d off = atlas.affine.topRightCorner<3, 1>();
  const Eigen::VectorXd vol = tet_volumes(mesh.vertices, mesh.tets);
  std::vector<int> lab(m);
  std::map<int, std::pair<int, double>> stats;
  for (int t = 0; t < m; ++t) {
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    for (int k = 0; k < 4; ++k) c += mesh.vertices.row(mesh.tets(t, k)).transpose();
    const Eigen::Vector3d v = inv * (c / 4 - off);
    const int i = int(std::lround(v.x())), j = int(std::lround(v.y())), k = int(std::lround(v.z()));
    int l = 0;
    if (i >= 0 && j >= 0 && k >= 0 && i < atlas.dims[0] && j < atlas.dims[1] && k < atlas.dims[2])
      l = int(std::lround(atlas.at(i, j, k)));
    lab[t] = l;
    cell(t, 0) = l;
    auto& st = stats[l];
    st.first += 1;
    st.second += vol[t];
  }
  // Vertex label: the most frequent label of its tets (ties: the larger summed volume).
  const Incidence inc = vertex_tet_incidence(n, mesh.tets);
  std::vector<std::pair<int, std::pair<int, double>>> cnt;
  for (int v = 0; v < n; ++v) {
    cnt.clear();
    for (int e = inc.offset[v]; e < inc.offset[v + 1]; ++e) {
      const int t = inc.tet_of[e];
      auto it = std::find_if(cnt.begin(), cnt.end(), [&](auto& p) { return p.first == lab[t]; });
      if (it == cnt.end()) cnt.push_back({lab[t], {1, vol[t]}});
      else it->second.first += 1, it->second.second += vol[t];
    }
    int best = 0;
    std::pair<int, double> bs{-1, 0};
    for (auto& p : cnt)
      if (p.second.first > bs.first || (p.second.first == bs.first && p.second.second > bs.second))
        best = p.first, bs = p.second;
    point(v, 0) = best;
  }
  mesh.set_cell_field("label", cell, true);
  mesh.set_point_field("label", point, true);
  Json j = Json::object();
  for (auto& [l, st] : stats) {
    Json& e = j[std::to_string(l)];
    e["tets"] = st.first;
    e["volume_mm3"] = st.second;
  }
  return j;
}

#if !VPM_HAVE_CGAL
TriSurface remesh_surface(const TriSurface&, double, int) {
  throw InputError("mesh-image: this vpm was built without CGAL (surface remeshing unavailable)");
}
#endif
#if !VPM_HAVE_TETGEN
TetMesh tetrahedralize_surface(const TriSurface&, const TetgenOptions&, Json*) {
  throw InputError("mesh-image: this vpm was built without TetGen (tetrahedralisation unavailable)");
}
#endif

// ---- the pipeline --------------------------------------------------------------------------

TetMesh mesh_image(const Image& img, const MeshImageOptions& o, Json* report_out, const Image* atlas) {
  const Stopwatch t_total;
  Json report = Json::object();
  const std::string src = img.path.empty() ? std::string("image") : img.path;
  report["input"]["path"] = src;
  {
    Json d = Json::array(), sp = Json::array();
    for (int k = 0; k < 3; ++k) d.push_back(img.dims[k]), sp.push_back(img.spacing[k]);
    report["input"]["dims"] = d;
    report["input"]["spacing_mm"] = sp;
  }
  report["input"]["affine_source"] = img.affine_source;
  report["input"]["threshold"] = o.threshold;
  if (!o.select_labels.empty()) {
    Json sel = Json::array();
    for (int l : o.select_labels) sel.push_back(l);
    report["input"]["select_labels"] = sel;
  }
  if (img.data.size() != img.size() || img.size() == 0) throw InputError(src + ": image has no data");

  if (atlas) {
    const std::string asrc = atlas->path.empty() ? std::string("atlas") : atlas->path;
    if (atlas->dims != img.dims)
      throw InputError(asrc + ": atlas grid " + std::to_string(atlas->dims[0]) + "x" + std::to_string(atlas->dims[1]) + "x" +
                       std::to_string(atlas->dims[2]) + " differs from the image grid " + std::to_string(img.dims[0]) +
                       "x" + std::to_string(img.dims[1]) + "x" + std::to_string(img.dims[2]) + " of " + src);
    const double diff = (atlas->affine - img.affine).cwiseAbs().maxCoeff();
    if (diff > 1e-3)
      throw InputError(asrc + ": atlas affine (" + atlas->affine_source + ") differs from the image affine (" +
                       img.affine_source + ") of " + src + " by up to " + format_sig(diff) + " mm: not the same grid");
  }

  // ---- mask: threshold, largest 6-connected component, cavities filled -------------------
  Stopwatch t0;
  std::string label_list;
  for (int l : o.select_labels) label_list += (label_list.empty() ? "" : ",") + std::to_string(l);
  if (o.progress)
    o.progress(o.select_labels.empty() ? "mask (value > " + format_sig(o.threshold) + ")" : "mask (labels " + label_list + ")");
  const Grid3 G{img.dims[0], img.dims[1], img.dims[2]};
  std::vector<uint8_t> mask(G.size());
  size_t count = 0;
  float lo = img.data.empty() ? 0 : img.data[0], hi = lo;
  for (size_t i = 0; i < G.size(); ++i) {
    const float v = img.data[i];
    lo = std::min(lo, v), hi = std::max(hi, v);
    if (o.select_labels.empty()) {
      mask[i] = v > o.threshold;
    } else {
      const long l = std::lround(v);
      mask[i] = std::find(o.select_labels.begin(), o.select_labels.end(), l) != o.select_labels.end();
    }
    count += mask[i];
  }
  if (count == 0 && !o.select_labels.empty())
    throw InputError(src + ": mask is empty: no voxel has label " + label_list + " (values range " + format_sig(lo) +
                     " .. " + format_sig(hi) + ")");
  if (count == 0)
    throw InputError(src + ": mask is empty: no voxel is above the threshold " + format_sig(o.threshold) +
                     " (values range " + format_sig(lo) + " .. " + format_sig(hi) + ")");
  const auto [removed, filled] = keep_largest_fill_cavities(G, mask, kN6);
  int bx[2] = {G.nx, -1}, by[2] = {G.ny, -1}, bz[2] = {G.nz, -1};
  count = 0;
  size_t border_voxels = 0;
  for (int z = 0; z < G.nz; ++z)
    for (int y = 0; y < G.ny; ++y)
      for (int x = 0; x < G.nx; ++x) {
        if (!mask[G.idx(x, y, z)]) continue;
        ++count;
        if (x == 0 || y == 0 || z == 0 || x == G.nx - 1 || y == G.ny - 1 || z == G.nz - 1) {
          if (!o.close_at_border)
            throw InputError(src + ": mask touches the image border at " + world_str(img, x, y, z) +
                             ": the surface would be cut open (pad the image, raise --threshold, or "
                             "pass --close-at-border to close it with a flat cap there)");
          ++border_voxels;
        }
        bx[0] = std::min(bx[0], x), bx[1] = std::max(bx[1], x);
        by[0] = std::min(by[0], y), by[1] = std::max(by[1], y);
        bz[0] = std::min(bz[0], z), bz[1] = std::max(bz[1], z);
      }
  const double voxel_volume = std::abs(img.affine.topLeftCorner<3, 3>().determinant());
  const double mask_volume = count * voxel_volume;
  report["input"]["mask_voxels"] = double(count);
  report["input"]["mask_volume_mm3"] = mask_volume;
  report["input"]["components_removed"] = removed;
  report["input"]["cavities_filled"] = filled;
  report["input"]["border_voxels"] = double(border_voxels);
  record(report, "mask", t0);

  // ---- resolution, smoothing, resampling ----------------------------------------------------
  t0.restart();
  const Resolution res = resolution_for(mask_volume, o);
  const double min_sp = std::min({img.spacing[0], img.spacing[1], img.spacing[2]});
  const double grid = std::max(0.7 * res.edge, min_sp);
  const double sigma = o.smooth < 0 ? std::max(0.5 * res.edge, 2 * min_sp) : o.smooth;
  report["parameters"]["target_edge_mm"] = res.edge;
  report["parameters"]["grid_mm"] = grid;
  report["parameters"]["smooth_sigma_mm"] = sigma;
  report["parameters"]["max_volume_mm3"] = res.max_volume;
  if (o.progress) o.progress("smoothing (sigma " + format_sig(sigma, 3) + " mm) and resampling (" + format_sig(grid, 3) + " mm)");
  // Cropped, padded float copy of the mask.
  int pad[3], c0[3], cn[3];
  const int lo_b[3] = {bx[0], by[0], bz[0]}, hi_b[3] = {bx[1], by[1], bz[1]};
  for (int d = 0; d < 3; ++d) {
    pad[d] = int(std::ceil((3 * sigma + 2 * grid) / img.spacing[d])) + 2;
    c0[d] = lo_b[d] - pad[d];
    cn[d] = hi_b[d] - lo_b[d] + 1 + 2 * pad[d];
  }
  const Grid3 C{cn[0], cn[1], cn[2]};
  std::vector<float> field(C.size(), 0.f);
  for (int z = bz[0]; z <= bz[1]; ++z)
    for (int y = by[0]; y <= by[1]; ++y)
      for (int x = bx[0]; x <= bx[1]; ++x)
        if (mask[G.idx(x, y, z)]) field[C.idx(x - c0[0], y - c0[1], z - c0[2])] = 1.f;
  std::vector<uint8_t>().swap(mask);
  for (int d = 0; d < 3; ++d) blur_axis(field, C, d, sigma / img.spacing[d]);
  // Extraction grid: step (in voxels) per axis, covering the crop.
  double step[3];
  int gn[3];
  for (int d = 0; d < 3; ++d) {
    step[d] = grid / img.spacing[d];
    gn[d] = int(std::floor((cn[d] - 1) / step[d])) + 1;
  }
  const Grid3 E{gn[0], gn[1], gn[2]};
  std::vector<float> F(E.size());
  auto sample = [&](double x, double y, double z) {
    const int ix = std::min(int(x), C.nx - 2), iy = std::min(int(y), C.ny - 2), iz = std::min(int(z), C.nz - 2);
    const double fx = x - ix, fy = y - iy, fz = z - iz;
    double acc = 0;
    for (int c = 0; c < 8; ++c) {
      const int dx = c & 1, dy = (c >> 1) & 1, dz = (c >> 2) & 1;
      acc += (dx ? fx : 1 - fx) * (dy ? fy : 1 - fy) * (dz ? fz : 1 - fz) * field[C.idx(ix + dx, iy + dy, iz + dz)];
    }
    return float(acc);
  };
  for (int z = 0; z < E.nz; ++z)
    for (int y = 0; y < E.ny; ++y)
      for (int x = 0; x < E.nx; ++x) F[E.idx(x, y, z)] = sample(x * step[0], y * step[1], z * step[2]);
  std::vector<float>().swap(field);
  record(report, "grid", t0);

  // ---- topology: one component, no cavities, genus 0 (closing at growing radii) ----------
  t0.restart();
  if (o.progress) o.progress("topology check");
  const float iso = 0.5f;
  std::vector<uint8_t> B0(E.size());
  for (size_t i = 0; i < E.size(); ++i) B0[i] = F[i] > iso;
  for (int z = 0; z < E.nz; ++z)  // the outer layer is outside by construction of the padding
    for (int y = 0; y < E.ny; ++y)
      for (int x = 0; x < E.nx; ++x)
        if (x == 0 || y == 0 || z == 0 || x == E.nx - 1 || y == E.ny - 1 || z == E.nz - 1) B0[E.idx(x, y, z)] = 0;
  if (std::find(B0.begin(), B0.end(), 1) == B0.end())
    throw InputError(src + ": the mask vanishes after smoothing (sigma " + format_sig(sigma) + " mm): it is thinner than "
                     "the mesh resolution; lower --smooth or raise --target-vertices");
  Json& topo = report["topology"];
  topo["repairs"] = Json::array();
  auto extract = [&](const std::vector<uint8_t>& B, std::vector<float>& Fx) {
    Fx = F;
    for (size_t i = 0; i < E.size(); ++i) {
      if (B[i] && !(Fx[i] > iso + 1e-3f)) Fx[i] = std::max(Fx[i], iso + 0.05f);
      if (!B[i] && !(Fx[i] < iso - 1e-3f)) Fx[i] = std::min(Fx[i], iso - 0.05f);
    }
    return marching_tets(E, Fx, iso);
  };
  std::vector<uint8_t> B = B0;
  auto [rm0, fill0] = keep_largest_fill_cavities(E, B, kN14);
  std::vector<float> Fx;
  TriSurface surf = extract(B, Fx);
  SurfaceTopology st = surface_topology(int(surf.vertices.rows()), surf.triangles);
  topo["euler_before"] = st.euler;
  topo["genus_before"] = st.genus();
  topo["grid_components_removed"] = rm0;
  topo["grid_cavities_filled"] = fill0;
  int radius = 0;
  while (st.euler != 2 || st.components != 1) {
    ++radius;
    if (radius > o.max_closing_radius)
      throw InputError(src + ": the mask surface has genus " + std::to_string(st.genus()) + " (Euler characteristic " +
                       std::to_string(st.euler) + ") and morphological closing up to radius " +
                       std::to_string(o.max_closing_radius) + " grid cells (" + format_sig(o.max_closing_radius * grid) +
                       " mm) did not remove the handles; cannot make a genus-0 boundary");
    if (o.progress) o.progress("genus " + std::to_string(st.genus()) + ": closing with radius " + std::to_string(radius));
    B = B0;
    morph(E, B, radius, true);
    morph(E, B, radius, false);
    keep_largest_fill_cavities(E, B, kN14);
    surf = extract(B, Fx);
    const int before = st.euler;
    st = surface_topology(int(surf.vertices.rows()), surf.triangles);
    Json r = Json::object();
    r["closing_radius_cells"] = radius;
    r["closing_radius_mm"] = radius * grid;
    r["euler_before"] = before;
    r["euler_after"] = st.euler;
    topo["repairs"].push_back(r);
  }
  topo["closing_radius_cells"] = radius;
  topo["euler"] = st.euler;
  record(report, "topology", t0);

  // ---- surface to world coordinates ---------------------------------------------------------
  t0.restart();
  for (int v = 0; v < surf.vertices.rows(); ++v) {
    Eigen::Vector3d ijk;
    for (int d = 0; d < 3; ++d) ijk[d] = c0[d] + surf.vertices(v, d) * step[d];
    surf.vertices.row(v) = img.to_world(ijk).transpose();
  }
  if (img.affine.topLeftCorner<3, 3>().determinant() < 0) surf.triangles.col(1).swap(surf.triangles.col(2));
  report["extracted_surface"] = surface_json(surf);
  report["extracted_surface"]["volume_mm3"] = enclosed_volume(surf);
  record(report, "extract", t0);

  TetMesh mesh = surface_to_tets(surf, res, o, report, src, true);

  if (atlas) {
    t0.restart();
    if (o.progress) o.progress("labels");
    Json labels = label_mesh(mesh, *atlas);
    // voxel counts per label inside the atlas, for comparison
    std::map<int, double> voxels;
    for (float v : atlas->data) voxels[int(std::lround(v))] += 1;
    const double avox = std::abs(atlas->affine.topLeftCorner<3, 3>().determinant());
    Json out = Json::object();
    for (auto& [l, n] : voxels) {
      if (l == 0) continue;
      const Json* e = labels.find(std::to_string(l));
      Json& r = out[std::to_string(l)];
      r["tets"] = e ? e->find("tets")->number() : 0.0;
      r["volume_mm3"] = e ? e->find("volume_mm3")->number() : 0.0;
      r["voxels"] = n;
      r["voxel_volume_mm3"] = n * avox;
    }
    report["labels"] = out;
    record(report, "labels", t0);
  }
  record(report, "total", t_total);
  if (report_out) *report_out = report;
  return mesh;
}

TetMesh mesh_surface(const TriSurface& surface, const MeshImageOptions& o, Json* report_out, const std::string& source) {
  const Stopwatch t_total;
  Json report = Json::object();
  report["input"]["path"] = source;
  check_closed_genus0(surface, source, "the input surface");
  double vol = enclosed_volume(surface);
  TriSurface s = surface;
  if (vol < 0) {  // inward normals: flip
    s.triangles.col(1).swap(s.triangles.col(2));
    vol = -vol;
  }
  report["input"]["volume_mm3"] = vol;
  const Resolution res = resolution_for(vol, o);
  report["parameters"]["target_edge_mm"] = res.edge;
  report["parameters"]["max_volume_mm3"] = res.max_volume;
  TetMesh mesh = surface_to_tets(s, res, o, report, source, true);
  record(report, "total", t_total);
  if (report_out) *report_out = report;
  return mesh;
}

TetMesh mesh_image_file(const std::string& path, const MeshImageOptions& o, Json* report, const std::string& labels_path) {
  auto ends_with = [&](const std::string& s) {
    std::string p = path;
    std::transform(p.begin(), p.end(), p.begin(), ::tolower);
    return p.size() >= s.size() && p.compare(p.size() - s.size(), s.size(), s) == 0;
  };
  if (ends_with(".off") || ends_with(".obj") || ends_with(".stl")) {
    if (!labels_path.empty()) throw InputError("--labels needs an image input, not a surface (" + path + ")");
    const Stopwatch t0;
    TriSurface s;
    try {
      s = read_surface(path);
    } catch (const InputError& e) {
      // vpm::read_surface may not read OFF yet (io in progress): use the small reader here.
      if (!ends_with(".off") || std::string(e.what()).find("not implemented") == std::string::npos) throw;
      s = read_off_surface(path);
    }
    Json r;
    record(r, "read", t0);
    TetMesh m = mesh_surface(s, o, report, path);
    if (report) (*report)["timings_s"]["read"] = r["timings_s"]["read"], (*report)["cpu_s"]["read"] = r["cpu_s"]["read"];
    return m;
  }
  const Stopwatch t0;
  Image img = read_nifti(path);
  Image atlas;
  if (!labels_path.empty()) atlas = read_nifti(labels_path);
  Json r;
  record(r, "read", t0);
  TetMesh m = mesh_image(img, o, report, labels_path.empty() ? nullptr : &atlas);
  if (report) (*report)["timings_s"]["read"] = r["timings_s"]["read"], (*report)["cpu_s"]["read"] = r["cpu_s"]["read"];
  return m;
}

}  // namespace vpm
