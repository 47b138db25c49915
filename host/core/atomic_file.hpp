#pragma once
// Private helper: every output file of vpm is written through an AtomicFile, so that no process
// death (an exception, a full disk, SIGKILL from a scheduler or the OOM killer) ever leaves a
// partial file under any name.
//
// Where the file system supports it (ext4, xfs, btrfs, tmpfs: Linux O_TMPFILE), the contents
// go to an unnamed file in the destination's folder; commit() gives it the final name with
// linkat() (through /proc/self/fd) when the destination does not exist yet, or links it under
// a hidden temporary name and renames that over the destination. Before commit() the file has
// no name at all, so a killed process leaves nothing behind; the only window is between that
// link and the rename when replacing an existing file, and the file is complete by then.
// Elsewhere (NFS, Lustre, no /proc) it falls back to a hidden temporary "<dir>/.<name>.tmp.<pid>.<k>"
// renamed on commit(), which a SIGKILL before commit() leaves behind (never the final name).
#include <memory>
#include <ostream>
#include <string>

namespace vpm::detail {

class AtomicFile {
 public:
  /// Opens the unnamed (or hidden temporary) file in `path`'s folder; throws InputError naming
  /// `path` if the folder does not exist or cannot be written. `binary` is kept for the callers'
  /// documentation: the stream never translates bytes.
  explicit AtomicFile(const std::string& path, bool binary = false);
  /// Without commit(): discards the contents; the destination is left as it was.
  ~AtomicFile();
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;
  /// The stream to write to (precision 17). A failed write (disk full) sets its badbit and is
  /// reported by commit().
  std::ostream& stream();
  /// Flushes, checks for write errors (InputError naming the path and the system's reason),
  /// then gives the file its final name, replacing an existing file atomically.
  void commit();
  /// True when this file is written without a name (O_TMPFILE), false for the named fallback.
  bool unnamed() const { return unnamed_; }

 private:
  class Buf;
  void link_into_place();
  std::string path_, dir_, tmp_;
  int fd_ = -1;
  bool unnamed_ = false, done_ = false;
  std::unique_ptr<Buf> buf_;
  std::unique_ptr<std::ostream> out_;
};

/// Test hook: when true, AtomicFile never uses O_TMPFILE (the named fallback runs), so tests
/// cover the path that file systems without O_TMPFILE take. Not thread-safe; tests only.
void atomic_file_force_named_fallback(bool on);

}  // namespace vpm::detail
