// GIfTI surfaces (.gii, .surf.gii) through Debian's libgiftiio: the DataArray of intent
// NIFTI_INTENT_POINTSET (n x 3, float32 or float64) and the one of NIFTI_INTENT_TRIANGLE (k x 3,
// int32), either index order, any of GIfTI's inline encodings (ASCII, base64, base64 of gzip).
// The header is read first without the data: external-file data (GIFTI_ENCODING_EXTBIN, which
// would make the library open a path the file names) is refused, and the arrays' sizes are
// checked before the library allocates them. Written as float32 points and int32 triangles,
// base64 of gzip, to a hidden name in the same folder, renamed when complete.
extern "C" {  // libgiftiio's header declares C functions without saying so
#include <gifti_io.h>
}

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>
#include <unistd.h>

#include "io/formats.hpp"
#include "vpm/error.hpp"

namespace vpm::detail {

namespace {

// Limits on what a header may ask the library to allocate (a gzip-compressed array can
// expand a thousandfold, and a fuzzer runs in 2 GB): 2^25 values an array (11 million vertices
// or triangles; a cortical surface has 150,000).
constexpr long long kMaxValues = 1LL << 25;

struct GiftiFree {
  void operator()(gifti_image* g) const { gifti_free_image(g); }
};
using Gifti = std::unique_ptr<gifti_image, GiftiFree>;

// gifti_read_image, with what the library prints on stderr (its XML parser's complaints, e.g.
// "** syntax error at line 1", whatever gifti_set_verb says) captured into *said instead, so
// that vpm's error stays one line.
Gifti read_quietly(const std::string& path, int read_data, std::string* said) {
  gifti_set_verb(0);
  std::fflush(stderr);
  const int saved = dup(2);
  std::FILE* sink = std::tmpfile();
  if (saved < 0 || !sink) {
    if (sink) std::fclose(sink);
    if (saved >= 0) close(saved);
    return Gifti(gifti_read_image(path.c_str(), read_data));
  }
  dup2(fileno(sink), 2);
  Gifti g(gifti_read_image(path.c_str(), read_data));
  std::fflush(stderr);
  dup2(saved, 2);
  close(saved);
  std::rewind(sink);
  char buf[256];
  while (said && std::fgets(buf, sizeof buf, sink)) {
    std::string line(buf);
    while (!line.empty() && (line.back() == '\n' || line.back() == '\r')) line.pop_back();
    const size_t start = line.find_first_not_of("* ");
    if (start != std::string::npos && said->empty()) *said = line.substr(start);
  }
  std::fclose(sink);
  return g;
}

// The index of the one DataArray of `intent` (InputError when none).
int array_of(const gifti_image& g, int intent, const std::string& path, const char* what) {
  for (int i = 0; i < g.numDA; ++i)
    if (g.darray[i] && g.darray[i]->intent == intent) return i;
  throw InputError(path + ": no DataArray of intent " + what + " (a GIfTI surface has one; a .func.gii or " +
                   ".shape.gii holds values, not a surface)");
}

void check_array(const giiDataArray& a, int index, const std::string& path, const char* what, bool points) {
  const std::string where = path + ": DataArray " + std::to_string(index) + " (" + what + "): ";
  if (a.encoding == GIFTI_ENCODING_EXTBIN)
    throw InputError(where + "its data is in an external file, which vpm does not read; write it inline");
  if (a.num_dim != 2 || a.dims[1] != 3 || a.dims[0] < (points ? 3 : 1))
    throw InputError(where + "expected " + (points ? "n x 3 coordinates" : "k x 3 vertex indices") + ", found " +
                     std::to_string(a.num_dim) + " dimensions" +
                     (a.num_dim >= 2 ? " of " + std::to_string(a.dims[0]) + " x " + std::to_string(a.dims[1]) : ""));
  if (static_cast<long long>(a.dims[0]) * 3 > kMaxValues)
    throw InputError(where + std::to_string(a.dims[0]) + " rows: more than vpm reads (" +
                     std::to_string(kMaxValues / 3) + ")");
  const bool ok = points ? (a.datatype == NIFTI_TYPE_FLOAT32 || a.datatype == NIFTI_TYPE_FLOAT64)
                         : a.datatype == NIFTI_TYPE_INT32;
  if (!ok)
    throw InputError(where + "data type " + std::to_string(a.datatype) + "; expected " +
                     (points ? "FLOAT32 or FLOAT64" : "INT32"));
}

// Element (r, c) of an n x 3 array in the array's index order.
template <class T>
T at(const giiDataArray& a, long long r, int c) {
  const T* d = static_cast<const T*>(a.data);
  return a.ind_ord == GIFTI_IND_ORD_COL_MAJOR ? d[c * static_cast<long long>(a.dims[0]) + r] : d[r * 3 + c];
}

}  // namespace

TriSurface read_gifti(const std::string& path) {
  if (!std::filesystem::is_regular_file(path)) throw InputError(path + ": no such file");
  std::string said;
  Gifti head = read_quietly(path, 0, &said);
  if (!head)
    throw InputError(path + ": not a readable GIfTI file (libgiftiio: " + (said.empty() ? "cannot parse it" : said) + ")");
  const int ip = array_of(*head, NIFTI_INTENT_POINTSET, path, "NIFTI_INTENT_POINTSET");
  const int it = array_of(*head, NIFTI_INTENT_TRIANGLE, path, "NIFTI_INTENT_TRIANGLE");
  check_array(*head->darray[ip], ip, path, "points", true);
  check_array(*head->darray[it], it, path, "triangles", false);
  head.reset();
  said.clear();
  Gifti g = read_quietly(path, 1, &said);
  if (!g || g->numDA <= std::max(ip, it) || !g->darray[ip]->data || !g->darray[it]->data)
    throw InputError(path + ": the GIfTI data could not be decoded (libgiftiio: " +
                     (said.empty() ? "bad base64, gzip or ASCII data" : said) + ")");
  const giiDataArray& p = *g->darray[ip];
  const giiDataArray& t = *g->darray[it];
  check_array(p, ip, path, "points", true);
  check_array(t, it, path, "triangles", false);
  TriSurface s;
  const long long n = p.dims[0], m = t.dims[0];
  s.vertices.resize(n, 3);
  for (long long i = 0; i < n; ++i)
    for (int k = 0; k < 3; ++k) {
      const double v = p.datatype == NIFTI_TYPE_FLOAT32 ? at<float>(p, i, k) : at<double>(p, i, k);
      if (!std::isfinite(v))
        throw InputError(path + ": point " + std::to_string(i) + ": coordinate is not a finite number");
      s.vertices(i, k) = v;
    }
  s.triangles.resize(m, 3);
  for (long long i = 0; i < m; ++i)
    for (int k = 0; k < 3; ++k) {
      const int v = at<int>(t, i, k);
      if (v < 0 || v >= n)
        throw InputError(path + ": triangle " + std::to_string(i) + ": vertex index " + std::to_string(v) +
                         " out of range (" + std::to_string(n) + " points)");
      s.triangles(i, k) = v;
    }
  return s;
}

Eigen::VectorXd read_gifti_values(const std::string& path) {
  if (!std::filesystem::is_regular_file(path)) throw InputError(path + ": no such file");
  std::string said;
  Gifti head = read_quietly(path, 0, &said);
  if (!head)
    throw InputError(path + ": not a readable GIfTI file (libgiftiio: " + (said.empty() ? "cannot parse it" : said) + ")");
  int pick = -1;
  for (int i = 0; i < head->numDA && pick < 0; ++i) {
    const giiDataArray* a = head->darray[i];
    if (a && a->intent != NIFTI_INTENT_POINTSET && a->intent != NIFTI_INTENT_TRIANGLE &&
        (a->num_dim == 1 || (a->num_dim == 2 && a->dims[1] == 1)))
      pick = i;
  }
  if (pick < 0) throw InputError(path + ": no DataArray of one value a vertex (a .shape.gii or .func.gii holds one)");
  const giiDataArray& h = *head->darray[pick];
  if (h.encoding == GIFTI_ENCODING_EXTBIN)
    throw InputError(path + ": DataArray " + std::to_string(pick) + ": its data is in an external file, which vpm does not read");
  if (h.dims[0] < 1 || h.dims[0] > kMaxValues)
    throw InputError(path + ": DataArray " + std::to_string(pick) + ": " + std::to_string(h.dims[0]) + " values out of range");
  if (h.datatype != NIFTI_TYPE_FLOAT32 && h.datatype != NIFTI_TYPE_FLOAT64 && h.datatype != NIFTI_TYPE_INT32)
    throw InputError(path + ": DataArray " + std::to_string(pick) + ": data type " + std::to_string(h.datatype) +
                     "; expected FLOAT32, FLOAT64 or INT32");
  head.reset();
  said.clear();
  Gifti g = read_quietly(path, 1, &said);
  if (!g || g->numDA <= pick || !g->darray[pick]->data)
    throw InputError(path + ": the GIfTI data could not be decoded (libgiftiio: " +
                     (said.empty() ? "bad base64, gzip or ASCII data" : said) + ")");
  const giiDataArray& a = *g->darray[pick];
  Eigen::VectorXd v(a.dims[0]);
  for (int i = 0; i < a.dims[0]; ++i) {
    v(i) = a.datatype == NIFTI_TYPE_FLOAT32   ? static_cast<const float*>(a.data)[i]
           : a.datatype == NIFTI_TYPE_FLOAT64 ? static_cast<const double*>(a.data)[i]
                                              : static_cast<const int*>(a.data)[i];
    if (!std::isfinite(v(i))) throw InputError(path + ": vertex " + std::to_string(i) + ": value is not a finite number");
  }
  return v;
}

void write_gifti(const std::string& path, const TriSurface& s) {
  const long long n = s.vertices.rows(), m = s.triangles.rows();
  for (long long i = 0; i < m; ++i)
    for (int k = 0; k < 3; ++k)
      if (s.triangles(i, k) < 0 || s.triangles(i, k) >= n)
        throw InputError(path + ": cannot write: triangle " + std::to_string(i) + " has vertex index " +
                         std::to_string(s.triangles(i, k)) + " out of range");
  if (3 * std::max(n, m) > kMaxValues) throw InputError(path + ": cannot write: too many points or triangles for GIfTI");
  const int pdims[2] = {static_cast<int>(n), 3};
  Gifti g(gifti_create_image(1, NIFTI_INTENT_POINTSET, NIFTI_TYPE_FLOAT32, 2, pdims, 1));
  if (!g || gifti_add_empty_darray(g.get(), 1) != 0) throw InputError(path + ": cannot write: libgiftiio could not make the image");
  giiDataArray& t = *g->darray[1];
  t.intent = NIFTI_INTENT_TRIANGLE;
  t.datatype = NIFTI_TYPE_INT32;
  t.ind_ord = GIFTI_IND_ORD_ROW_MAJOR;
  t.num_dim = 2;
  t.dims[0] = static_cast<int>(m);
  t.dims[1] = 3;
  t.nvals = 3 * m;
  t.nbyper = 4;
  const int which = 1;
  if (gifti_alloc_DA_data(g.get(), &which, 1) != 0) throw InputError(path + ": cannot write: out of memory");
  giiDataArray& p = *g->darray[0];
  for (int i = 0; i < 2; ++i) {
    g->darray[i]->encoding = GIFTI_ENCODING_B64GZ;
    g->darray[i]->endian = GIFTI_ENDIAN_LITTLE;
    g->darray[i]->ind_ord = GIFTI_IND_ORD_ROW_MAJOR;
  }
  auto* pv = static_cast<float*>(p.data);
  for (long long i = 0; i < n; ++i)
    for (int k = 0; k < 3; ++k) pv[3 * i + k] = static_cast<float>(s.vertices(i, k));
  auto* tv = static_cast<int*>(t.data);
  for (long long i = 0; i < m; ++i)
    for (int k = 0; k < 3; ++k) tv[3 * i + k] = s.triangles(i, k);
  // a hidden name in the destination's folder, renamed when complete (no partial file)
  const std::filesystem::path dest(path);
  const std::filesystem::path dir = dest.has_parent_path() ? dest.parent_path() : std::filesystem::path(".");
  const std::filesystem::path tmp = dir / ("." + dest.filename().string() + ".tmp." + std::to_string(getpid()));
  gifti_set_verb(0);
  if (gifti_write_image(g.get(), tmp.c_str(), 1) != 0) {
    std::error_code ec;
    std::filesystem::remove(tmp, ec);
    throw InputError(path + ": cannot write (libgiftiio failed; is the folder writable?)");
  }
  std::error_code ec;
  std::filesystem::rename(tmp, dest, ec);
  if (ec) {
    std::filesystem::remove(tmp, ec);
    throw InputError(path + ": cannot write: " + ec.message());
  }
}

}  // namespace vpm::detail
