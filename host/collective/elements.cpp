#include "vpm/elements.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <map>
#include <utility>

#include "vpm/error.hpp"
#include "vpm/icosphere.hpp"

namespace vpm {

namespace {

using Vec3 = Eigen::Vector3d;

Vec3 corner(const TriSurface& s, int f, int k) { return s.vertices.row(s.triangles(f, k)).transpose(); }

// Solid angle of the spherical triangle (a, b, c) (unit vectors, counter-clockwise seen from
// outside): Van Oosterom & Strackee, tan(omega / 2) = a.(b x c) / (1 + a.b + b.c + c.a).
double solid_angle(const Vec3& a, const Vec3& b, const Vec3& c) {
  return 2 * std::atan2(a.dot(b.cross(c)), 1 + a.dot(b) + b.dot(c) + c.dot(a));
}

// Direction d lies in the spherical triangle (a, b, c): on the inner side of its three
// great-circle planes (ties count as inside, so every direction is in at least one triangle).
bool contains(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  return a.cross(b).dot(d) >= 0 && b.cross(c).dot(d) >= 0 && c.cross(a).dot(d) >= 0;
}

// The unit vector of x orthogonal to unit vector n (x not parallel to n).
Vec3 orthonormal(const Vec3& x, const Vec3& n) { return (x - x.dot(n) * n).normalized(); }

// Arvo, "Stratified sampling of spherical triangles" (SIGGRAPH 1995): maps (u1, u2) in [0,1]^2
// to a point of the spherical triangle (a, b, c), area-uniformly.
Vec3 arvo_sample(const Vec3& a, const Vec3& b, const Vec3& c, double u1, double u2) {
  // interior angles: between the great circles through each corner
  const double alpha = std::acos(std::clamp(orthonormal(b, a).dot(orthonormal(c, a)), -1.0, 1.0));
  const double beta = std::acos(std::clamp(orthonormal(a, b).dot(orthonormal(c, b)), -1.0, 1.0));
  const double gamma = std::acos(std::clamp(orthonormal(a, c).dot(orthonormal(b, c)), -1.0, 1.0));
  const double area = alpha + beta + gamma - M_PI;
  const double sub = u1 * area;  // area of the sub-triangle (a, b, c_hat)
  const double s = std::sin(sub - alpha), t = std::cos(sub - alpha);
  const double cos_c = a.dot(b);
  const double u = t - std::cos(alpha), v = s + std::sin(alpha) * cos_c;
  const double q = std::clamp(((v * t - u * s) * std::cos(alpha) - v) / ((v * s + u * t) * std::sin(alpha)), -1.0, 1.0);
  const Vec3 c_hat = q * a + std::sqrt(std::max(0.0, 1 - q * q)) * orthonormal(c, a);  // on the arc a-c
  const double z = 1 - u2 * (1 - c_hat.dot(b));  // cosine of the angle from b, uniform in area
  return (z * b + std::sqrt(std::max(0.0, 1 - z * z)) * orthonormal(c_hat, b)).normalized();
}

// The additive recurrence of Roberts' R3 sequence: point n of a low-discrepancy sequence in
// [0,1)^3 (alpha_i = phi^-i, phi the real root of x^4 = x + 1).
Vec3 r3(int n) {
  const double phi = 1.2207440845469035;
  const Vec3 alpha(1 / phi, 1 / (phi * phi), 1 / (phi * phi * phi));
  Vec3 x;
  for (int i = 0; i < 3; ++i) x(i) = std::fmod(0.5 + alpha(i) * n, 1.0);
  return x;
}

void check(const ElementDefinition& d) {
  auto bad = [](const std::string& what) { throw InputError("elements: " + what); };
  if (d.level < 0 || d.level > 7) bad("level " + std::to_string(d.level) + " is not in 0..7");
  if (d.shells < 1 || d.shells > 256) bad("shells " + std::to_string(d.shells) + " is not in 1..256");
  if (d.samples < 1 || d.samples > 4096) bad("samples " + std::to_string(d.samples) + " is not in 1..4096");
}

}  // namespace

Json to_json(const ElementDefinition& d) {
  Json j = Json::object();
  j["level"] = d.level;
  j["shells"] = d.shells;
  j["samples"] = d.samples;
  j["generator"] = "icosphere-arvo-r3";
  j["generator_version"] = ElementDefinition::kGeneratorVersion;
  return j;
}

ElementDefinition element_definition_from_json(const Json& j, const std::string& source) {
  auto num = [&](const char* key) {
    const Json* v = j.find(key);
    if (!v || v->type() != Json::Type::Number)
      throw InputError(source + ": element definition has no number \"" + std::string(key) + "\"");
    return static_cast<int>(v->number());
  };
  ElementDefinition d;
  d.level = num("level");
  d.shells = num("shells");
  d.samples = num("samples");
  if (num("generator_version") != ElementDefinition::kGeneratorVersion)
    throw InputError(source + ": element sample generator version " + std::to_string(num("generator_version")) +
                     ", this vpm makes version " + std::to_string(ElementDefinition::kGeneratorVersion));
  try {
    check(d);
  } catch (const InputError& e) {
    throw InputError(source + ": " + e.what());
  }
  return d;
}

CanonicalElements::CanonicalElements(const ElementDefinition& definition) : def_(definition) {
  check(def_);
  for (int l = 0; l <= def_.level; ++l) levels_.push_back(icosphere(l));
  sphere_ = levels_.back();
  const int T = triangles();
  solid_angle_.resize(static_cast<size_t>(T));
  for (int f = 0; f < T; ++f) solid_angle_[f] = solid_angle(corner(sphere_, f, 0), corner(sphere_, f, 1), corner(sphere_, f, 2));
  // edge-adjacent triangles: the directed edge (i, j) of one is (j, i) of the other
  std::map<std::pair<int, int>, int> owner;
  for (int f = 0; f < T; ++f)
    for (int i = 0; i < 3; ++i) owner[{sphere_.triangles(f, i), sphere_.triangles(f, (i + 1) % 3)}] = f;
  edge_neighbours_.resize(3 * static_cast<size_t>(T));
  for (int f = 0; f < T; ++f)
    for (int i = 0; i < 3; ++i)
      edge_neighbours_[3 * static_cast<size_t>(f) + i] = owner.at({sphere_.triangles(f, (i + 1) % 3), sphere_.triangles(f, i)});
  const int S = def_.samples;
  samples_.resize(static_cast<Eigen::Index>(size()) * S, 3);
  for (int e = 0; e < size(); ++e) {
    const int f = triangle_of(e), k = shell_of(e);
    const Vec3 a = corner(sphere_, f, 0), b = corner(sphere_, f, 1), c = corner(sphere_, f, 2);
    const double r0 = std::pow(radius(k), 3), r1 = std::pow(radius(k + 1), 3);
    for (int s = 0; s < S; ++s) {
      const Vec3 u = r3(s + 1);
      const double r = std::cbrt(r0 + u(2) * (r1 - r0));
      samples_.row(static_cast<Eigen::Index>(e) * S + s) = r * arvo_sample(a, b, c, u(0), u(1)).transpose();
    }
  }
}

double CanonicalElements::radius(int k) const { return std::cbrt(static_cast<double>(k) / def_.shells); }

double CanonicalElements::mid_radius(int k) const {
  return std::cbrt(0.5 * (std::pow(radius(k), 3) + std::pow(radius(k + 1), 3)));
}

Eigen::Vector3d CanonicalElements::centre(int id) const {
  const int t = triangle_of(id);
  const Eigen::Vector3d dir = (sphere_.vertices.row(sphere_.triangles(t, 0)) + sphere_.vertices.row(sphere_.triangles(t, 1)) +
                               sphere_.vertices.row(sphere_.triangles(t, 2)))
                                  .normalized()
                                  .transpose();
  return mid_radius(shell_of(id)) * dir;
}

double CanonicalElements::volume(int id) const {
  const int k = shell_of(id);
  return solid_angle_[triangle_of(id)] * (std::pow(radius(k + 1), 3) - std::pow(radius(k), 3)) / 3;
}

ElementVolumeStats CanonicalElements::volume_stats() const {
  ElementVolumeStats st;
  double sum = 0;
  st.min = 1e300;
  for (int e = 0; e < size(); ++e) {
    const double v = volume(e);
    sum += v;
    st.min = std::min(st.min, v);
    st.max = std::max(st.max, v);
  }
  st.mean = sum / size();
  double var = 0;
  for (int e = 0; e < size(); ++e) var += (volume(e) - st.mean) * (volume(e) - st.mean);
  st.std_relative = std::sqrt(var / size()) / st.mean;
  return st;
}

std::vector<int> CanonicalElements::neighbours(int id) const {
  const int f = triangle_of(id), k = shell_of(id);
  std::vector<int> out;
  for (int i = 0; i < 3; ++i) out.push_back(this->id(k, edge_neighbours_[3 * static_cast<size_t>(f) + i]));
  if (k > 0) out.push_back(this->id(k - 1, f));
  if (k + 1 < def_.shells) out.push_back(this->id(k + 1, f));
  return out;
}

int CanonicalElements::element_of(const Eigen::Vector3d& p) const {
  const double r = p.norm();
  if (r > 1 + 1e-9) return -1;
  const int k = std::min(def_.shells - 1, static_cast<int>(std::floor(r * r * r * def_.shells)));
  if (r == 0) return id(k, 0);
  const Vec3 d = p / r;
  int f = -1;
  for (int g = 0; g < 20 && f < 0; ++g)
    if (contains(corner(levels_[0], g, 0), corner(levels_[0], g, 1), corner(levels_[0], g, 2), d)) f = g;
  if (f < 0) f = 0;  // round-off at a corner
  for (size_t l = 1; l < levels_.size(); ++l) {
    int next = 4 * f;  // the child that contains d (the last one if round-off leaves none)
    for (int c = 0; c < 4; ++c) {
      const int g = 4 * f + c;
      if (contains(corner(levels_[l], g, 0), corner(levels_[l], g, 1), corner(levels_[l], g, 2), d)) {
        next = g;
        break;
      }
    }
    f = next;
  }
  return id(k, f);
}

}  // namespace vpm
