#include "vpm/elements.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <climits>
#include <cmath>
#include <map>
#include <utility>

#include "collective/element_arrays.hpp"
#include "core/parallel.hpp"
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

void check(const ElementDefinition& d) {
  auto bad = [](const std::string& what) { throw InputError("elements: " + what); };
  if (d.level < 0 || d.level > 7) bad("level " + std::to_string(d.level) + " is not in 0..7");
  if (d.shells < 1 || d.shells > 256) bad("shells " + std::to_string(d.shells) + " is not in 1..256");
  if (d.samples < 1 || d.samples > 4096) bad("samples " + std::to_string(d.samples) + " is not in 1..4096");
  if (d.layout == ElementLayout::graded && d.shells != graded_shells(d.level))
    bad("the graded layout at level " + std::to_string(d.level) + " has " + std::to_string(graded_shells(d.level)) +
        " shells, not " + std::to_string(d.shells));
}

int triangles_at(int level) { return 20 << (2 * level); }

}  // namespace

ElementLayout parse_element_layout(const std::string& name) {
  if (name == "shells") return ElementLayout::shells;
  if (name == "graded") return ElementLayout::graded;
  throw InputError("element layout '" + name + "' is not one of shells, graded");
}

const char* to_string(ElementLayout layout) { return layout == ElementLayout::graded ? "graded" : "shells"; }

std::string to_string(const ElementDefinition& d) {
  return std::to_string(d.level) + "/" + std::to_string(d.shells) + "/" + std::to_string(d.samples) + " " +
         to_string(d.layout);
}

std::vector<int> shell_levels(const ElementDefinition& d) {
  if (d.layout == ElementLayout::shells) return std::vector<int>(static_cast<size_t>(std::max(d.shells, 0)), d.level);
  // the volume of a cube as wide as a level-L triangle at r = 1, as a fraction of the ball's
  const double width = std::sqrt(4 * M_PI / triangles_at(d.level));
  const double cube = width * width * width / (4 * M_PI / 3);
  std::vector<int> levels;
  for (int j = d.level; j >= 0; --j) {  // bands from the inside out: level L - j
    const double inner = j == d.level ? 0.0 : std::pow(2.0, -3 * (j + 0.5));
    const double outer = j == 0 ? 1.0 : std::pow(2.0, -3 * (j - 0.5));
    const int level = d.level - j;
    const long n = std::max(1L, std::lround((outer - inner) / (cube * triangles_at(level))));
    levels.insert(levels.end(), static_cast<size_t>(n), level);
  }
  return levels;
}

int graded_shells(int level) {
  ElementDefinition d;
  d.level = level;
  d.layout = ElementLayout::graded;
  return static_cast<int>(shell_levels(d).size());
}

int ElementDefinition::elements() const {
  int n = 0;
  for (int l : shell_levels(*this)) n += triangles_at(l);
  return n;
}

Json to_json(const ElementDefinition& d) {
  Json j = Json::object();
  j["level"] = d.level;
  j["shells"] = d.shells;
  j["samples"] = d.samples;
  j["layout"] = to_string(d.layout);
  j["generator"] = "icosphere-arvo-r3";
  j["generator_version"] = ElementDefinition::kGeneratorVersion;
  return j;
}

ElementDefinition element_definition_from_json(const Json& j, const std::string& source) {
  auto num = [&](const char* key) {
    const Json* v = j.find(key);
    if (!v || v->type() != Json::Type::Number)
      throw InputError(source + ": element definition has no number \"" + std::string(key) + "\"");
    const double x = v->number();
    if (!(x >= INT_MIN && x <= INT_MAX) || x != std::floor(x))
      throw InputError(source + ": element definition's \"" + std::string(key) + "\" is not an integer");
    return static_cast<int>(x);
  };
  ElementDefinition d;
  d.level = num("level");
  d.shells = num("shells");
  d.samples = num("samples");
  if (const Json* layout = j.find("layout")) {
    if (layout->type() != Json::Type::String) throw InputError(source + ": element definition's \"layout\" is not a string");
    try {
      d.layout = parse_element_layout(layout->string());
    } catch (const InputError& e) {
      throw InputError(source + ": " + e.what());
    }
  }
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
  for (int l = 0; l <= def_.level; ++l) {
    levels_.push_back(icosphere(l));
    const TriSurface& s = levels_.back();
    const int T = static_cast<int>(s.triangles.rows());
    std::vector<double> omega(static_cast<size_t>(T));
    for (int f = 0; f < T; ++f) omega[f] = solid_angle(corner(s, f, 0), corner(s, f, 1), corner(s, f, 2));
    solid_angle_.push_back(std::move(omega));
    // edge-adjacent triangles: the directed edge (i, j) of one is (j, i) of the other
    std::map<std::pair<int, int>, int> owner;
    for (int f = 0; f < T; ++f)
      for (int i = 0; i < 3; ++i) owner[{s.triangles(f, i), s.triangles(f, (i + 1) % 3)}] = f;
    std::vector<int> across(3 * static_cast<size_t>(T));
    for (int f = 0; f < T; ++f)
      for (int i = 0; i < 3; ++i) across[3 * static_cast<size_t>(f) + i] = owner.at({s.triangles(f, (i + 1) % 3), s.triangles(f, i)});
    edge_neighbours_.push_back(std::move(across));
  }
  sphere_ = levels_.back();
  shell_level_ = shell_levels(def_);
  offset_.assign(1, 0);
  for (int l : shell_level_) offset_.push_back(offset_.back() + triangles_at(l));
  // equal element volumes: shell k holds its share of the elements of the ball's volume
  radius3_.resize(offset_.size());
  for (size_t k = 0; k < offset_.size(); ++k) radius3_[k] = static_cast<double>(offset_[k]) / offset_.back();
  radius3_.back() = 1.0;
  make_arrays();
  lazy_ = std::make_shared<Lazy>();
}

void CanonicalElements::make_arrays() {
  auto a = std::make_shared<detail::ElementArrays>();
  a->samples = def_.samples;
  a->offset = offset_;
  a->level = shell_level_;
  for (const TriSurface& s : levels_) {
    a->first.push_back(static_cast<int>(a->corners.size() / 9));
    for (int f = 0; f < s.triangles.rows(); ++f)
      for (int k = 0; k < 3; ++k)
        for (int c = 0; c < 3; ++c) a->corners.push_back(s.vertices(s.triangles(f, k), c));
  }
  const int S = def_.samples;
  a->u.resize(3 * static_cast<size_t>(S));
  for (int i = 0; i < S; ++i) detail::es_r3(i + 1, &a->u[3 * static_cast<size_t>(i)]);
  for (size_t k = 0; k < shell_level_.size(); ++k)
    for (int i = 0; i < S; ++i) a->radius.push_back(detail::es_radius(radius3_[k], radius3_[k + 1], a->u[3 * i + 2]));
  arrays_ = std::move(a);
}

namespace detail {

const std::vector<double>& element_directions(const ElementArrays& a) {
  std::call_once(a.directions_made, [&] {
    const size_t rows = a.corners.size() / 9, S = static_cast<size_t>(a.samples);
    a.directions.resize(rows * S * 3);
    const EsLayout L = es_layout(a);
    parallel_for(static_cast<int>(rows), 1024, [&](int begin, int end) {
      for (int t = begin; t < end; ++t) es_directions(&L, t, &a.directions[static_cast<size_t>(t) * S * 3]);
    });
  });
  return a.directions;
}

}  // namespace detail

const Points& CanonicalElements::samples() const {
  const detail::ElementArrays& a = *arrays_;
  detail::element_directions(a);
  std::call_once(a.samples_made, [&] {
    const int S = def_.samples;
    a.points.resize(static_cast<Eigen::Index>(size()) * S, 3);
    const detail::EsLayout L = detail::es_layout(a);
    detail::parallel_for(size(), 1024, [&](int begin, int end) {
      for (int e = begin; e < end; ++e) {
        int k;
        const long row = detail::es_row(&L, e, &k);
        for (int i = 0; i < S; ++i) detail::es_sample(&L, row, k, i, &a.points(static_cast<Eigen::Index>(e) * S + i, 0));
      }
    });
  });
  return a.points;
}

Eigen::Vector3d CanonicalElements::sample(int id, int s) const {
  const detail::EsLayout L = detail::es_layout(*arrays_);
  int k;
  const long row = detail::es_row(&L, id, &k);
  Eigen::Vector3d p;
  detail::es_sample_direct(&L, row, k, s, p.data());
  return p;
}

const CanonicalElements::Adjacency& CanonicalElements::adjacency() const {
  std::call_once(lazy_->adjacency_once, [this] {
    Adjacency& a = lazy_->adjacency;
    a.offset.assign(1, 0);
    a.offset.reserve(static_cast<size_t>(size()) + 1);
    a.list.reserve(static_cast<size_t>(size()) * 5);
    for (int e = 0; e < size(); ++e) {
      for (int nb : neighbours(e)) a.list.push_back(nb);
      a.offset.push_back(static_cast<int>(a.list.size()));
    }
  });
  return lazy_->adjacency;
}

int CanonicalElements::shell_of(int id) const {
  return static_cast<int>(std::upper_bound(offset_.begin(), offset_.end(), id) - offset_.begin()) - 1;
}

double CanonicalElements::radius(int k) const { return std::cbrt(radius3_[k]); }

double CanonicalElements::mid_radius(int k) const { return std::cbrt(0.5 * (radius3_[k] + radius3_[k + 1])); }

Eigen::Vector3d CanonicalElements::centre(int id) const {
  const int k = shell_of(id), t = id - offset_[k];
  const TriSurface& s = levels_[shell_level_[k]];
  const Eigen::Vector3d dir =
      (s.vertices.row(s.triangles(t, 0)) + s.vertices.row(s.triangles(t, 1)) + s.vertices.row(s.triangles(t, 2)))
          .normalized()
          .transpose();
  return mid_radius(k) * dir;
}

double CanonicalElements::volume(int id) const {
  const int k = shell_of(id);
  return solid_angle_[shell_level_[k]][id - offset_[k]] * (radius3_[k + 1] - radius3_[k]) / 3;
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
  const int k = shell_of(id), f = id - offset_[k], l = shell_level_[k];
  std::vector<int> out;
  for (int i = 0; i < 3; ++i) out.push_back(this->id(k, edge_neighbours_[l][3 * static_cast<size_t>(f) + i]));
  if (k > 0) out.push_back(this->id(k - 1, f >> (2 * (l - shell_level_[k - 1]))));  // same or coarser
  if (k + 1 < def_.shells) {  // same or finer: every descendant of f at that level
    const int d = 2 * (shell_level_[k + 1] - l);
    for (int g = f << d; g < (f + 1) << d; ++g) out.push_back(this->id(k + 1, g));
  }
  return out;
}

int CanonicalElements::element_of(const Eigen::Vector3d& p) const {
  const double r = p.norm();
  if (r > 1 + 1e-9) return -1;
  const int k = std::min(def_.shells - 1, static_cast<int>(std::upper_bound(radius3_.begin(), radius3_.end(), r * r * r) -
                                                           radius3_.begin()) - 1);
  if (r == 0) return id(k, 0);
  const Vec3 d = p / r;
  int f = -1;
  for (int g = 0; g < 20 && f < 0; ++g)
    if (contains(corner(levels_[0], g, 0), corner(levels_[0], g, 1), corner(levels_[0], g, 2), d)) f = g;
  if (f < 0) f = 0;  // round-off at a corner
  for (int l = 1; l <= shell_level_[k]; ++l) {
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
