// The HDF5 layer of vpm's binary files (io/hdf5.hpp).
#include "io/hdf5.hpp"

#include "io/hdf5_lock.hpp"

#include <algorithm>
#include <cmath>
#include <atomic>
#include <cstring>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <unistd.h>

#include "core/atomic_file.hpp"
#include "core/file_digest.hpp"
#include "vpm/error.hpp"

namespace vpm::detail::h5 {

namespace {

// Bytes of the user block before the superblock: the digest (HDF5's smallest user block).
constexpr std::size_t kDigestBytes = 512;
// Datasets of at most this many values are stored contiguous, without chunks or filters.
constexpr std::size_t kSmallValues = 4096;
// Rows a chunk holds: about 64k values, whatever the column count.
constexpr std::size_t kChunkValues = 1 << 16;
// The most values one chunk of a file being read may declare (a larger one is refused before
// the library allocates for it).
constexpr hsize_t kMaxChunkValues = 1 << 22;

hid_t file_type(Stored t) {
  switch (t) {
    case Stored::u8: return H5T_STD_U8LE;
    case Stored::f32: return H5T_IEEE_F32LE;
    case Stored::f64: return H5T_IEEE_F64LE;
    case Stored::u16: return H5T_STD_U16LE;
    case Stored::i32: return H5T_STD_I32LE;
    case Stored::i64: return H5T_STD_I64LE;
  }
  return H5T_IEEE_F64LE;
}

// A variable-length UTF-8 string type (h5py reads it as str).
Id string_type() {
  Id t(H5Tcopy(H5T_C_S1));
  H5Tset_size(static_cast<hid_t>(t.get()), H5T_VARIABLE);
  H5Tset_cset(static_cast<hid_t>(t.get()), H5T_CSET_UTF8);
  return t;
}

}  // namespace

Id::~Id() {
  if (id_ < 0) return;
  Guard g;
  H5Idec_ref(static_cast<hid_t>(id_));
}

Id& Id::operator=(Id&& o) noexcept {
  if (this != &o) {
    Id drop(id_);
    id_ = o.id_;
    o.id_ = -1;
  }
  return *this;
}

bool is_hdf5_path(const std::string& path) {
  const auto ext = std::filesystem::path(path).extension().string();
  return ext == ".h5" || ext == ".hdf5";
}

// ---- writing ---------------------------------------------------------------------------

Writer::Writer(std::string path) : path_(std::move(path)) {
  Guard g;
  static std::atomic<long> serial{0};
  Id fapl(H5Pcreate(H5P_FILE_ACCESS)), fcpl(H5Pcreate(H5P_FILE_CREATE));
  // in memory, never on disk (commit() writes the image), in the earliest format that holds it
  // (the core driver's image of a newer superblock does not match its own checksum); the user
  // block before the superblock holds the digest (kDigestBytes)
  H5Pset_fapl_core(static_cast<hid_t>(fapl.get()), 1 << 20, 0);
  H5Pset_libver_bounds(static_cast<hid_t>(fapl.get()), H5F_LIBVER_EARLIEST, H5F_LIBVER_V18);
  H5Pset_userblock(static_cast<hid_t>(fcpl.get()), kDigestBytes);
  const std::string name = "vpm-memory-" + std::to_string(getpid()) + "-" + std::to_string(serial++) + ".h5";
  file_ = Id(H5Fcreate(name.c_str(), H5F_ACC_EXCL, static_cast<hid_t>(fcpl.get()), static_cast<hid_t>(fapl.get())));
  if (!file_.valid()) throw InputError(path_ + ": HDF5 could not create the file in memory");
}

Writer::~Writer() = default;

void Writer::group(const std::string& path) {
  Guard g;
  Id gcpl(H5Pcreate(H5P_GROUP_CREATE));
  H5Pset_obj_track_times(static_cast<hid_t>(gcpl.get()), false);  // the same bytes for the same contents
  Id gid(H5Gcreate2(static_cast<hid_t>(file_.get()), path.c_str(), H5P_DEFAULT, static_cast<hid_t>(gcpl.get()), H5P_DEFAULT));
  if (!gid.valid()) throw InputError(path_ + ": " + path + ": the group could not be created");
}

void Writer::attribute(const std::string& object, const std::string& name, const std::string& value) {
  Guard g;
  Id type = string_type();
  Id space(H5Screate(H5S_SCALAR));
  Id a(H5Acreate_by_name(static_cast<hid_t>(file_.get()), object.c_str(), name.c_str(), static_cast<hid_t>(type.get()),
                         static_cast<hid_t>(space.get()), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
  const char* text = value.c_str();
  if (!a.valid() || H5Awrite(static_cast<hid_t>(a.get()), static_cast<hid_t>(type.get()), &text) < 0)
    throw InputError(path_ + ": " + object + ": attribute " + name + " could not be written");
}

void Writer::attribute(const std::string& object, const std::string& name, std::int64_t value) {
  Guard g;
  Id space(H5Screate(H5S_SCALAR));
  Id a(H5Acreate_by_name(static_cast<hid_t>(file_.get()), object.c_str(), name.c_str(), H5T_STD_I64LE,
                         static_cast<hid_t>(space.get()), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT));
  if (!a.valid() || H5Awrite(static_cast<hid_t>(a.get()), H5T_NATIVE_INT64, &value) < 0)
    throw InputError(path_ + ": " + object + ": attribute " + name + " could not be written");
}

void Writer::write_any(const std::string& path, const void* values, std::int64_t memory_type, std::size_t rows,
                       std::size_t cols, Stored type, bool compress) {
  Guard g;
  const int rank = cols > 1 ? 2 : 1;
  const hsize_t dims[2] = {rows, cols};
  Id space(H5Screate_simple(rank, dims, nullptr));
  Id dcpl(H5Pcreate(H5P_DATASET_CREATE));
  H5Pset_obj_track_times(static_cast<hid_t>(dcpl.get()), false);  // the same bytes for the same contents
  // small datasets (a label list, a test's table) contiguous: a chunk index alone is kilobytes
  if (double(rows) * double(std::max<std::size_t>(cols, 1)) > double(kSmallValues)) {
    const hsize_t chunk_cols = std::min<hsize_t>(cols, kChunkValues);
    const hsize_t chunk[2] = {std::min<hsize_t>(rows, std::max<hsize_t>(1, kChunkValues / chunk_cols)), chunk_cols};
    H5Pset_chunk(static_cast<hid_t>(dcpl.get()), rank, chunk);
    if (compress) {
      H5Pset_shuffle(static_cast<hid_t>(dcpl.get()));
      H5Pset_deflate(static_cast<hid_t>(dcpl.get()), 4);
    }
  }
  Id d(H5Dcreate2(static_cast<hid_t>(file_.get()), path.c_str(), file_type(type), static_cast<hid_t>(space.get()),
                  H5P_DEFAULT, static_cast<hid_t>(dcpl.get()), H5P_DEFAULT));
  if (!d.valid() ||
      (rows > 0 && H5Dwrite(static_cast<hid_t>(d.get()), static_cast<hid_t>(memory_type), H5S_ALL, H5S_ALL, H5P_DEFAULT, values) < 0))
    throw InputError(path_ + ": " + path + ": the dataset could not be written");
}

void Writer::dataset(const std::string& path, const double* v, std::size_t rows, std::size_t cols, Stored type,
                     bool compress) {
  write_any(path, v, H5T_NATIVE_DOUBLE, rows, cols, type, compress);
}
void Writer::dataset(const std::string& path, const int* v, std::size_t rows, std::size_t cols, Stored type) {
  write_any(path, v, H5T_NATIVE_INT, rows, cols, type, true);
}
void Writer::dataset(const std::string& path, const std::int64_t* v, std::size_t rows, std::size_t cols, Stored type) {
  write_any(path, v, H5T_NATIVE_INT64, rows, cols, type, true);
}

void Writer::text(const std::string& path, const std::string& value) {
  write_any(path, value.data(), H5T_NATIVE_CHAR, value.size(), 1, Stored::u8, true);
}

void Writer::commit() {
  std::vector<char> image;
  {
    Guard g;
    const hid_t f = static_cast<hid_t>(file_.get());
    H5Fflush(f, H5F_SCOPE_GLOBAL);
    const ssize_t size = H5Fget_file_image(f, nullptr, 0);
    if (size <= 0) throw InputError(path_ + ": HDF5 could not produce the file's image");
    image.resize(static_cast<std::size_t>(size));
    if (H5Fget_file_image(f, image.data(), image.size()) != size)
      throw InputError(path_ + ": HDF5 could not produce the file's image");
  }
  // the image starts at the superblock, which places the HDF5 data after a user block of
  // kDigestBytes: that block is the digest line and zeros
  std::string block = digest_line(image.data(), image.size());
  block.resize(kDigestBytes, '\0');
  AtomicFile out(path_, true);
  out.stream().write(block.data(), static_cast<std::streamsize>(block.size()));
  out.stream().write(image.data(), static_cast<std::streamsize>(image.size()));
  out.commit();
}

// ---- reading ---------------------------------------------------------------------------

Reader::Reader(std::string path) : path_(std::move(path)) {
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path_, ec)) throw InputError(path_ + ": no such file");
  check_digest(path_, kDigestBytes,
               "not an HDF5 file vpm wrote (no digest in its user block): vpm reads the HDF5 files it writes; give "
               "other tools' tables as TSV");
  Guard g;
  file_ = Id(H5Fopen(path_.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT));
  if (!file_.valid()) throw InputError(path_ + ": not an HDF5 file (or a truncated or corrupt one)");
}

Reader::~Reader() = default;

bool Reader::has(const std::string& path) const {
  Guard g;
  // every prefix must exist before H5Lexists may be asked about the next one
  for (std::size_t at = path.find('/', 1);; at = path.find('/', at + 1)) {
    const std::string prefix = path.substr(0, at);
    if (H5Lexists(static_cast<hid_t>(file_.get()), prefix.c_str(), H5P_DEFAULT) <= 0) return false;
    if (at == std::string::npos) return true;
  }
}

namespace {

// Attribute `name` of `object`, or an invalid Id when absent.
Id open_attribute(const Id& file, const std::string& object, const std::string& name) {
  const hid_t f = static_cast<hid_t>(file.get());
  if (H5Aexists_by_name(f, object.c_str(), name.c_str(), H5P_DEFAULT) <= 0) return Id();
  return Id(H5Aopen_by_name(f, object.c_str(), name.c_str(), H5P_DEFAULT, H5P_DEFAULT));
}

bool scalar(hid_t attr) {
  Id space(H5Aget_space(attr));
  return space.valid() && H5Sget_simple_extent_npoints(static_cast<hid_t>(space.get())) == 1;
}

}  // namespace

std::optional<std::string> Reader::string_attribute(const std::string& object, const std::string& name,
                                                    std::size_t max_bytes) const {
  Guard g;
  if (!has(object)) return std::nullopt;
  Id a = open_attribute(file_, object, name);
  if (!a.valid()) return std::nullopt;
  const std::string where = path_ + ": " + object + ": attribute " + name;
  const hid_t attr = static_cast<hid_t>(a.get());
  Id type(H5Aget_type(attr));
  if (!type.valid() || H5Tget_class(static_cast<hid_t>(type.get())) != H5T_STRING || !scalar(attr))
    throw InputError(where + " is not a string");
  const hid_t t = static_cast<hid_t>(type.get());
  if (H5Tis_variable_str(t) > 0) {
    Id memory = string_type();
    char* text = nullptr;
    if (H5Aread(attr, static_cast<hid_t>(memory.get()), &text) < 0 || !text) throw InputError(where + " does not read");
    std::string s(text, strnlen(text, max_bytes + 1));
    H5free_memory(text);
    if (s.size() > max_bytes) throw InputError(where + " is longer than " + std::to_string(max_bytes) + " bytes");
    return s;
  }
  const std::size_t size = H5Tget_size(t);
  if (size == 0 || size > max_bytes) throw InputError(where + " is longer than " + std::to_string(max_bytes) + " bytes");
  std::string s(size, '\0');
  if (H5Aread(attr, t, s.data()) < 0) throw InputError(where + " does not read");
  s.resize(strnlen(s.data(), s.size()));
  return s;
}

std::optional<std::int64_t> Reader::integer_attribute(const std::string& object, const std::string& name) const {
  Guard g;
  if (!has(object)) return std::nullopt;
  Id a = open_attribute(file_, object, name);
  if (!a.valid()) return std::nullopt;
  const hid_t attr = static_cast<hid_t>(a.get());
  Id type(H5Aget_type(attr));
  std::int64_t v = 0;
  if (!type.valid() || H5Tget_class(static_cast<hid_t>(type.get())) != H5T_INTEGER || !scalar(attr) ||
      H5Aread(attr, H5T_NATIVE_INT64, &v) < 0)
    throw InputError(path_ + ": " + object + ": attribute " + name + " is not an integer");
  return v;
}

std::vector<std::size_t> Reader::shape(const std::string& path) const {
  Guard g;
  const std::string where = path_ + ": " + path;
  if (!has(path)) throw InputError(where + ": missing");
  Id d(H5Dopen2(static_cast<hid_t>(file_.get()), path.c_str(), H5P_DEFAULT));
  if (!d.valid()) throw InputError(where + ": not a dataset");
  Id type(H5Dget_type(static_cast<hid_t>(d.get())));
  const H5T_class_t c = type.valid() ? H5Tget_class(static_cast<hid_t>(type.get())) : H5T_NO_CLASS;
  if (c != H5T_FLOAT && c != H5T_INTEGER) throw InputError(where + ": not numeric");
  Id space(H5Dget_space(static_cast<hid_t>(d.get())));
  const int rank = space.valid() ? H5Sget_simple_extent_ndims(static_cast<hid_t>(space.get())) : -1;
  if (rank != 1 && rank != 2) throw InputError(where + ": has " + std::to_string(rank) + " dimensions, expected 1 or 2");
  hsize_t dims[2] = {0, 1};
  H5Sget_simple_extent_dims(static_cast<hid_t>(space.get()), dims, nullptr);
  return rank == 1 ? std::vector<std::size_t>{dims[0]} : std::vector<std::size_t>{dims[0], dims[1]};
}

Id Reader::open_dataset(const std::string& path, std::size_t rows, std::size_t cols, bool integral) const {
  const std::string where = path_ + ": " + path;
  const std::vector<std::size_t> s = shape(path);
  const std::vector<std::size_t> want = cols > 1 ? std::vector<std::size_t>{rows, cols} : std::vector<std::size_t>{rows};
  if (s != want) {
    auto text = [](const std::vector<std::size_t>& v) {
      std::string t;
      for (std::size_t x : v) t += (t.empty() ? "" : " x ") + std::to_string(x);
      return t;
    };
    throw InputError(where + ": " + text(s) + " values, expected " + text(want));
  }
  Id d(H5Dopen2(static_cast<hid_t>(file_.get()), path.c_str(), H5P_DEFAULT));
  Id type(H5Dget_type(static_cast<hid_t>(d.get())));
  if (integral && H5Tget_class(static_cast<hid_t>(type.get())) != H5T_INTEGER)
    throw InputError(where + ": not of an integer type");
  // what a read allocates must be backed by the file: every chunk stored (a missing one would read
  // as fill values), each of bounded size; contiguous data no larger than the file
  Id dcpl(H5Dget_create_plist(static_cast<hid_t>(d.get())));
  const H5D_layout_t layout = dcpl.valid() ? H5Pget_layout(static_cast<hid_t>(dcpl.get())) : H5D_LAYOUT_ERROR;
  const std::size_t values = rows * std::max<std::size_t>(cols, 1);
  if (layout == H5D_CHUNKED) {
    hsize_t chunk[2] = {1, 1};
    const int r = H5Pget_chunk(static_cast<hid_t>(dcpl.get()), 2, chunk);
    if (r < 1 || r > 2 || (r == 2 ? double(chunk[0]) * double(chunk[1]) : double(chunk[0])) > double(kMaxChunkValues))
      throw InputError(where + ": chunks of more than " + std::to_string(kMaxChunkValues) + " values");
    const double per_row = r == 2 ? std::ceil(double(std::max<std::size_t>(cols, 1)) / double(std::max<hsize_t>(chunk[1], 1))) : 1.0;
    const double expected = std::ceil(double(rows) / double(std::max<hsize_t>(chunk[0], 1))) * per_row;
    hsize_t stored = 0;
    Id space(H5Dget_space(static_cast<hid_t>(d.get())));
    if (values > 0 && (H5Dget_num_chunks(static_cast<hid_t>(d.get()), static_cast<hid_t>(space.get()), &stored) < 0 ||
                       double(stored) != expected))
      throw InputError(where + ": some of its values are not stored (a truncated or corrupt file)");
  } else if (layout == H5D_CONTIGUOUS) {
    std::error_code ec;
    const auto bytes = std::filesystem::file_size(path_, ec);
    if (ec || double(H5Dget_storage_size(static_cast<hid_t>(d.get()))) > double(bytes) ||
        double(H5Tget_size(static_cast<hid_t>(type.get()))) * double(values) > double(bytes))
      throw InputError(where + ": declares more values than the file holds (a truncated or corrupt file)");
  } else if (layout != H5D_COMPACT) {
    throw InputError(where + ": an unknown storage layout");
  }
  return d;
}

std::vector<double> Reader::doubles(const std::string& path, std::size_t rows, std::size_t cols) const {
  if (cols <= 1)
    if (std::optional<std::vector<double>> v = direct(path, rows, false)) return std::move(*v);
  Guard g;
  Id d = open_dataset(path, rows, cols, false);
  std::vector<double> out(rows * std::max<std::size_t>(cols, 1));
  if (!out.empty() && H5Dread(static_cast<hid_t>(d.get()), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, out.data()) < 0)
    throw InputError(path_ + ": " + path + ": the values do not read (a corrupt or truncated file)");
  return out;
}

std::vector<std::int64_t> Reader::integers(const std::string& path, std::size_t rows, std::size_t cols) const {
  if (cols <= 1)
    if (std::optional<std::vector<double>> v = direct(path, rows, true)) return {v->begin(), v->end()};
  Guard g;
  Id d = open_dataset(path, rows, cols, true);
  std::vector<std::int64_t> out(rows * std::max<std::size_t>(cols, 1));
  if (!out.empty() && H5Dread(static_cast<hid_t>(d.get()), H5T_NATIVE_INT64, H5S_ALL, H5S_ALL, H5P_DEFAULT, out.data()) < 0)
    throw InputError(path_ + ": " + path + ": the values do not read (a corrupt or truncated file)");
  return out;
}

std::string Reader::text(const std::string& path, std::size_t max_bytes) const {
  Guard g;
  const std::vector<std::size_t> s = shape(path);
  if (s.size() != 1 || s[0] > max_bytes)
    throw InputError(path_ + ": " + path + ": not a text of at most " + std::to_string(max_bytes) + " bytes");
  Id d = open_dataset(path, s[0], 1, true);
  std::string out(s[0], '\0');
  if (!out.empty() && H5Dread(static_cast<hid_t>(d.get()), H5T_NATIVE_CHAR, H5S_ALL, H5S_ALL, H5P_DEFAULT, out.data()) < 0)
    throw InputError(path_ + ": " + path + ": the text does not read (a corrupt or truncated file)");
  return out;
}

}  // namespace vpm::detail::h5
