// Landmark CSV reader and writer (vpm/landmarks.hpp).
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>

#include "core/atomic_file.hpp"
#include "vpm/error.hpp"
#include "vpm/landmarks.hpp"

namespace vpm {

namespace {

std::string trim(const std::string& s) {
  const char* ws = " \t\r\n\xEF\xBB\xBF";  // also a UTF-8 byte order mark
  const auto b = s.find_first_not_of(ws);
  if (b == std::string::npos) return "";
  return s.substr(b, s.find_last_not_of(" \t\r\n") - b + 1);
}

std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> out;
  std::string cell;
  std::istringstream in(line);
  while (std::getline(in, cell, ',')) out.push_back(trim(cell));
  if (!line.empty() && line.back() == ',') out.push_back("");
  return out;
}

bool parse_number(const std::string& s, double& x) {
  if (s.empty()) return false;
  char* end = nullptr;
  errno = 0;
  x = std::strtod(s.c_str(), &end);
  return end == s.c_str() + s.size() && errno != ERANGE;
}

}  // namespace

LandmarkFile read_landmarks_csv(const std::string& path, const Points& vertices) {
  std::ifstream in(path);
  if (!in) throw InputError(path + ": cannot open landmark file");
  LandmarkFile out;
  std::vector<Eigen::RowVector3d> pts;
  std::string raw;
  int lineno = 0;
  bool first = true;
  while (std::getline(in, raw)) {
    ++lineno;
    const std::string line = trim(raw);
    if (line.empty() || line[0] == '#') continue;
    const auto cells = split(line);
    std::vector<double> v(cells.size());
    size_t bad = cells.size();
    for (size_t i = 0; i < cells.size(); ++i)
      if (!parse_number(cells[i], v[i])) {
        bad = i;
        break;
      }
    const std::string where = path + ":" + std::to_string(lineno) + ": ";
    if (bad < cells.size()) {
      if (first) {  // header line
        first = false;
        continue;
      }
      throw InputError(where + "'" + cells[bad] + "' is not a number (expected x,y,z or vertex_id)");
    }
    first = false;
    Eigen::RowVector3d p;
    if (cells.size() == 3) {
      p << v[0], v[1], v[2];
      if (!p.allFinite()) throw InputError(where + "non-finite coordinate");
    } else if (cells.size() == 1) {
      const double id = v[0];
      if (id != std::floor(id)) throw InputError(where + "vertex id '" + cells[0] + "' is not an integer");
      if (id < 0 || id >= static_cast<double>(vertices.rows()))
        throw InputError(where + "vertex id " + cells[0] + " out of range (the mesh has " +
                         std::to_string(vertices.rows()) + " vertices, ids are 0-based)");
      p = vertices.row(static_cast<Eigen::Index>(id));
    } else {
      throw InputError(where + "expected x,y,z or vertex_id, got " + std::to_string(cells.size()) +
                       " values");
    }
    if (p.norm() > 1 + 1e-9) {
      std::ostringstream s;
      s << where << "landmark (" << p(0) << ", " << p(1) << ", " << p(2)
        << ") is outside the unit ball (|p| = " << p.norm() << "); coordinates are ball coordinates";
      throw InputError(s.str());
    }
    pts.push_back(p);
    out.lines.push_back(lineno);
  }
  if (pts.empty()) throw InputError(path + ": no landmarks in the file");
  out.points.resize(static_cast<Eigen::Index>(pts.size()), 3);
  for (size_t i = 0; i < pts.size(); ++i) out.points.row(static_cast<Eigen::Index>(i)) = pts[i];
  return out;
}

void write_landmarks_csv(const std::string& path, const Points& points) {
  detail::AtomicFile f(path);
  f.stream() << "x,y,z\n";
  char buf[32];
  for (int i = 0; i < points.rows(); ++i)
    for (int c = 0; c < 3; ++c) {
      const auto r = std::to_chars(buf, buf + sizeof buf, points(i, c));
      f.stream().write(buf, r.ptr - buf) << (c < 2 ? ',' : '\n');
    }
  f.commit();
}

}  // namespace vpm
