#pragma once
// Private helper: write a file under a temporary name in the same folder, rename on commit().
// If commit() is never reached (an exception), the temporary file is removed: no half-written
// output ever carries the final name.
#include <fstream>
#include <string>

namespace vpm::detail {

class AtomicFile {
 public:
  /// Opens "<dir>/.<name>.tmp.<pid>" for writing; throws InputError naming `path` if it cannot.
  explicit AtomicFile(const std::string& path, bool binary = false);
  ~AtomicFile();
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;
  std::ofstream& stream() { return out_; }
  /// Flushes, checks for write errors, renames onto the final path.
  void commit();

 private:
  std::string path_, tmp_;
  std::ofstream out_;
  bool done_ = false;
};

}  // namespace vpm::detail
