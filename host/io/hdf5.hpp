#pragma once
// Private: a small layer over the HDF5 C library (Debian's libhdf5) for vpm's binary files
// (element tables, reference sums). Files are built in memory (the core driver) and written
// through AtomicFile, so no process death leaves a partial file; files are read from disk with
// every shape, type and size checked before anything is allocated for it. Every failure is an
// InputError naming the file and the object ("a.h5: /features/pet/mean: ..."); HDF5's own error
// printing is off. The calls are serialised by one lock (the library's own global lock would do
// the same), so the layer is safe from the host's threads.
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace vpm::detail::h5 {

/// An HDF5 identifier closed on destruction (any kind: file, group, dataset, ...).
class Id {
 public:
  Id() = default;
  explicit Id(std::int64_t id) : id_(id) {}
  ~Id();
  Id(Id&& o) noexcept : id_(o.id_) { o.id_ = -1; }
  Id& operator=(Id&& o) noexcept;
  Id(const Id&) = delete;
  Id& operator=(const Id&) = delete;
  std::int64_t get() const { return id_; }
  bool valid() const { return id_ >= 0; }

 private:
  std::int64_t id_ = -1;
};

/// How a dataset is stored: values are converted to this type on write.
enum class Stored { u8, f32, f64, u16, i32, i64 };

/// A file being written: built in memory, written to `path` by commit() (atomically).
class Writer {
 public:
  /// `path` names the file in messages and is where commit() writes.
  explicit Writer(std::string path);
  ~Writer();
  Writer(const Writer&) = delete;
  Writer& operator=(const Writer&) = delete;

  /// Creates the group `path` (its parents must exist), e.g. "/features/pet".
  void group(const std::string& path);
  /// A string attribute of the object at `object` ("/" for the file).
  void attribute(const std::string& object, const std::string& name, const std::string& value);
  void attribute(const std::string& object, const std::string& name, std::int64_t value);
  /// A dataset of `rows` x `cols` values (cols 1: one dimension), row-major, stored as `type`,
  /// chunked along the rows and, with `compress`, compressed (shuffle + deflate: float32 tables
  /// shrink to about half; float64 sums hardly shrink and would take seconds).
  void dataset(const std::string& path, const double* values, std::size_t rows, std::size_t cols, Stored type,
               bool compress = true);
  void dataset(const std::string& path, const int* values, std::size_t rows, std::size_t cols, Stored type);
  void dataset(const std::string& path, const std::int64_t* values, std::size_t rows, std::size_t cols, Stored type);
  /// A text of any length as a dataset of bytes (attributes are for short texts).
  void text(const std::string& path, const std::string& value);
  /// Writes the file to its path (AtomicFile); InputError naming it when that fails.
  void commit();

 private:
  void write_any(const std::string& path, const void* values, std::int64_t memory_type, std::size_t rows,
                 std::size_t cols, Stored type, bool compress);
  std::string path_;
  Id file_;
};

/// A file being read.
class Reader {
 public:
  /// Opens `path` read-only; InputError naming it when it is missing or not an HDF5 file.
  explicit Reader(std::string path);
  ~Reader();
  Reader(const Reader&) = delete;
  Reader& operator=(const Reader&) = delete;

  const std::string& path() const { return path_; }
  /// Whether a link (group or dataset) `path` exists (its parents must too, or false).
  bool has(const std::string& path) const;
  /// A string attribute of `object`; nothing when absent; InputError when it is not a string
  /// or longer than `max_bytes`.
  std::optional<std::string> string_attribute(const std::string& object, const std::string& name,
                                              std::size_t max_bytes = 1 << 20) const;
  std::optional<std::int64_t> integer_attribute(const std::string& object, const std::string& name) const;
  /// The shape of dataset `path` (1 or 2 dimensions), checked: InputError when it is missing, of
  /// another rank, or not numeric.
  std::vector<std::size_t> shape(const std::string& path) const;
  /// Dataset `path`, which must be numeric with exactly `rows` (x `cols` when cols > 1) values,
  /// read as doubles (row-major). InputError naming the file and the dataset otherwise, or when
  /// a value does not read (a corrupt or truncated chunk).
  std::vector<double> doubles(const std::string& path, std::size_t rows, std::size_t cols = 1) const;
  /// The same read as integers (the dataset must be of an integer type).
  std::vector<std::int64_t> integers(const std::string& path, std::size_t rows, std::size_t cols = 1) const;
  /// A text written by Writer::text; InputError when it is missing or longer than `max_bytes`.
  std::string text(const std::string& path, std::size_t max_bytes) const;

 private:
  Id open_dataset(const std::string& path, std::size_t rows, std::size_t cols, bool integral) const;
  /// A one-dimensional dataset stored as Writer stores it (float32 or uint16, shuffle + deflate)
  /// read chunk by chunk: the compressed chunks under the lock, then inflated, unshuffled and
  /// converted outside it in parallel, so that tables read on several threads decompress at once
  /// (io/hdf5_chunks.cpp). Nothing for any other storage (the caller reads through the library).
  std::optional<std::vector<double>> direct(const std::string& path, std::size_t rows, bool integral) const;
  std::string path_;
  Id file_;
};

/// Whether `path` names an HDF5 file by its extension (.h5, .hdf5).
bool is_hdf5_path(const std::string& path);

}  // namespace vpm::detail::h5
