// GIfTI surfaces (.gii, .surf.gii) and per-vertex values (.shape.gii, .func.gii), read through
// gifti_document.cpp (expat) and gifti_decode.cpp: the DataArray of intent NIFTI_INTENT_POINTSET
// (n x 3 numbers) and the one of NIFTI_INTENT_TRIANGLE (k x 3 whole numbers), any GIfTI data
// type, either index order and byte order, ASCII, base64 or base64 of zlib. External-file data
// (ExternalFileBinary, a path the file names) is refused. Written as float32 points and int32
// triangles, little-endian, base64 of zlib, through an AtomicFile (no partial file).
#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>
#include <bit>
#include <cstdint>

#include "core/atomic_file.hpp"
#include "io/formats.hpp"
#include "io/vtk_binary.hpp"
#include "vpm/error.hpp"
#include "with_gifti/gifti_document.hpp"

namespace vpm::detail {

namespace {

// The one DataArray of `intent` (InputError when none).
const GiftiArray& array_of(const std::vector<GiftiArray>& arrays, const std::string& intent, const std::string& path) {
  for (const GiftiArray& a : arrays)
    if (a.intent == intent) return a;
  throw InputError(path + ": no DataArray of intent " + intent + " (a GIfTI surface has one; a .func.gii or " +
                   ".shape.gii holds values, not a surface)");
}

// Checks an n x 3 array's shape before its data are decoded.
void check_rows(const GiftiArray& a, const std::string& path, const char* what, bool points) {
  const std::string where = path + ": DataArray " + std::to_string(a.index) + " (" + what + "): ";
  if (a.dims.size() != 2 || a.dims[1] != 3 || a.dims[0] < (points ? 3 : 1))
    throw InputError(where + "expected " + (points ? "n x 3 coordinates" : "k x 3 vertex indices") + ", found " +
                     std::to_string(a.dims.size()) + " dimensions" +
                     (a.dims.size() >= 2 ? " of " + std::to_string(a.dims[0]) + " x " + std::to_string(a.dims[1]) : ""));
  if (a.dims[0] * 3 > kGiftiMaxValues)
    throw InputError(where + std::to_string(a.dims[0]) + " rows: more than vpm reads (" +
                     std::to_string(kGiftiMaxValues / 3) + ")");
  if (!points && a.data_type.find("FLOAT") != std::string::npos)
    throw InputError(where + "data type " + a.data_type + "; vertex indices are whole numbers");
}

std::string data_array(const char* intent, long long rows, const char* type, const std::string& bytes) {
  uLongf size = compressBound(static_cast<uLong>(bytes.size()));
  std::string z(size, '\0');
  if (compress2(reinterpret_cast<Bytef*>(z.data()), &size, reinterpret_cast<const Bytef*>(bytes.data()),
                static_cast<uLong>(bytes.size()), Z_DEFAULT_COMPRESSION) != Z_OK)
    throw std::bad_alloc();
  z.resize(size);
  return std::string("  <DataArray Intent=\"") + intent + "\" DataType=\"" + type +
         "\" ArrayIndexingOrder=\"RowMajorOrder\" Dimensionality=\"2\" Dim0=\"" + std::to_string(rows) +
         "\" Dim1=\"3\" Encoding=\"GZipBase64Binary\" Endian=\"LittleEndian\" ExternalFileName=\"\" "
         "ExternalFileOffset=\"\">\n    <MetaData/>\n    <Data>" + encode_base64(z) + "</Data>\n  </DataArray>\n";
}

template <class T>
void append(std::string& bytes, T v) {
  bytes.append(reinterpret_cast<const char*>(&v), sizeof v);
}

}  // namespace

TriSurface read_gifti(const std::string& path) {
  if (!std::filesystem::is_regular_file(path)) throw InputError(path + ": no such file");
  const std::vector<GiftiArray> arrays = read_gifti_document(path);
  const GiftiArray& p = array_of(arrays, "NIFTI_INTENT_POINTSET", path);
  const GiftiArray& t = array_of(arrays, "NIFTI_INTENT_TRIANGLE", path);
  check_rows(p, path, "points", true);
  check_rows(t, path, "triangles", false);
  const std::vector<double> pv = gifti_values(p, path), tv = gifti_values(t, path);
  const long long n = p.dims[0], m = t.dims[0];
  TriSurface s;
  s.vertices.resize(n, 3);
  for (long long i = 0; i < 3 * n; ++i) {
    if (!std::isfinite(pv[i]))
      throw InputError(path + ": point " + std::to_string(i / 3) + ": coordinate is not a finite number");
    s.vertices(i / 3, i % 3) = pv[i];
  }
  s.triangles.resize(m, 3);
  for (long long i = 0; i < 3 * m; ++i) {
    if (tv[i] < 0 || tv[i] >= static_cast<double>(n))
      throw InputError(path + ": triangle " + std::to_string(i / 3) + ": vertex index " +
                       std::to_string(static_cast<long long>(tv[i])) + " out of range (" + std::to_string(n) + " points)");
    s.triangles(i / 3, i % 3) = static_cast<int>(tv[i]);
  }
  return s;
}

Eigen::VectorXd read_gifti_values(const std::string& path) {
  if (!std::filesystem::is_regular_file(path)) throw InputError(path + ": no such file");
  const std::vector<GiftiArray> arrays = read_gifti_document(path);
  const auto pick = std::find_if(arrays.begin(), arrays.end(), [](const GiftiArray& a) {
    return a.intent != "NIFTI_INTENT_POINTSET" && a.intent != "NIFTI_INTENT_TRIANGLE" &&
           (a.dims.size() == 1 || (a.dims.size() == 2 && a.dims[1] == 1));
  });
  if (pick == arrays.end()) throw InputError(path + ": no DataArray of one value a vertex (a .shape.gii or .func.gii holds one)");
  if (pick->dims[0] < 1) throw InputError(path + ": DataArray " + std::to_string(pick->index) + ": no values");
  const std::vector<double> values = gifti_values(*pick, path);
  Eigen::VectorXd v(static_cast<Eigen::Index>(values.size()));
  for (size_t i = 0; i < values.size(); ++i) {
    if (!std::isfinite(values[i])) throw InputError(path + ": vertex " + std::to_string(i) + ": value is not a finite number");
    v(static_cast<Eigen::Index>(i)) = values[i];
  }
  return v;
}

void write_gifti(const std::string& path, const TriSurface& s) {
  const long long n = s.vertices.rows(), m = s.triangles.rows();
  if (3 * std::max(n, m) > kGiftiMaxValues) throw InputError(path + ": cannot write: too many points or triangles for GIfTI");
  static_assert(std::endian::native == std::endian::little, "the GIfTI writer writes the host's bytes as LittleEndian");
  std::string points, triangles;
  for (long long i = 0; i < n; ++i)
    for (int k = 0; k < 3; ++k) append(points, static_cast<float>(s.vertices(i, k)));
  for (long long i = 0; i < m; ++i)
    for (int k = 0; k < 3; ++k) append(triangles, static_cast<std::int32_t>(s.triangles(i, k)));
  const std::string text = "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
                           "<!DOCTYPE GIFTI SYSTEM \"http://www.nitrc.org/frs/download.php/115/gifti.dtd\">\n"
                           "<GIFTI Version=\"1.0\" NumberOfDataArrays=\"2\">\n  <MetaData/>\n  <LabelTable/>\n" +
                           data_array("NIFTI_INTENT_POINTSET", n, "NIFTI_TYPE_FLOAT32", points) +
                           data_array("NIFTI_INTENT_TRIANGLE", m, "NIFTI_TYPE_INT32", triangles) + "</GIFTI>\n";
  AtomicFile file(path, true);
  file.stream() << text;
  file.commit();
}

}  // namespace vpm::detail
