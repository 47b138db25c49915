#include "core/atomic_file.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <streambuf>
#include <vector>

#include "vpm/error.hpp"

namespace vpm::detail {

namespace {

std::atomic<bool> g_force_named{false};
std::atomic<unsigned> g_serial{0};

std::string proc_fd_path(int fd) { return "/proc/self/fd/" + std::to_string(fd); }

// A hidden name next to the destination, unique in this process and (by the pid) among processes.
std::string hidden_temp_name(const std::string& dir, const std::string& base) {
  return (std::filesystem::path(dir) / ("." + base + ".tmp." + std::to_string(::getpid()) + "." +
                                        std::to_string(g_serial.fetch_add(1))))
      .string();
}

}  // namespace

void atomic_file_force_named_fallback(bool on) { g_force_named = on; }

// An output buffer over a file descriptor: write(2) in 1 MiB pieces, errno kept for the message.
class AtomicFile::Buf : public std::streambuf {
 public:
  explicit Buf(int fd) : fd_(fd), buf_(1 << 20) { setp(buf_.data(), buf_.data() + buf_.size()); }
  int error() const { return error_; }

 protected:
  int_type overflow(int_type c) override {
    if (!drain()) return traits_type::eof();
    if (!traits_type::eq_int_type(c, traits_type::eof())) {
      *pptr() = traits_type::to_char_type(c);
      pbump(1);
    }
    return traits_type::not_eof(c);
  }
  int sync() override { return drain() ? 0 : -1; }

 private:
  bool drain() {
    const char* p = pbase();
    while (p < pptr() && error_ == 0) {
      const ssize_t w = ::write(fd_, p, static_cast<size_t>(pptr() - p));
      if (w > 0) p += w;
      else if (w < 0 && errno != EINTR) error_ = errno;
      else if (w == 0) error_ = EIO;
    }
    setp(buf_.data(), buf_.data() + buf_.size());
    return error_ == 0;
  }
  int fd_;
  int error_ = 0;
  std::vector<char> buf_;
};

AtomicFile::AtomicFile(const std::string& path, bool /*binary*/) : path_(path) {
  const std::filesystem::path p(path);
  dir_ = p.parent_path().string();
  if (dir_.empty()) dir_ = ".";
  std::error_code ec;
  if (!std::filesystem::is_directory(dir_, ec))
    throw InputError(path + ": cannot write: folder '" + dir_ + "' does not exist");
  if (p.filename().empty()) throw InputError(path + ": cannot write: the path names a folder, not a file");
  // O_TMPFILE needs /proc to give the file a name afterwards (linkat with AT_EMPTY_PATH would
  // need CAP_DAC_READ_SEARCH).
  if (!g_force_named && ::access("/proc/self/fd", X_OK) == 0) {
    fd_ = ::open(dir_.c_str(), O_TMPFILE | O_WRONLY | O_CLOEXEC, 0666);
    unnamed_ = fd_ >= 0;
  }
  if (fd_ < 0) {  // no O_TMPFILE here (EOPNOTSUPP, EISDIR on old kernels) or forced: a named temp
    for (int attempt = 0; attempt < 100 && fd_ < 0; ++attempt) {
      tmp_ = hidden_temp_name(dir_, p.filename().string());
      fd_ = ::open(tmp_.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
      if (fd_ < 0 && errno != EEXIST) break;
    }
    if (fd_ < 0)
      throw InputError(path + ": cannot write: " + std::strerror(errno) + " (folder '" + dir_ + "')");
  }
  buf_ = std::make_unique<Buf>(fd_);
  out_ = std::make_unique<std::ostream>(buf_.get());
  out_->precision(17);
}

AtomicFile::~AtomicFile() {
  if (fd_ >= 0) ::close(fd_);
  if (!done_ && !unnamed_ && !tmp_.empty()) std::remove(tmp_.c_str());
}

std::ostream& AtomicFile::stream() { return *out_; }

void AtomicFile::commit() {
  out_->flush();
  const int werr = buf_->error();
  bool ok = static_cast<bool>(*out_) && werr == 0;
  int err = werr;
  if (!unnamed_) {  // a named temporary: close (NFS reports delayed write errors here), then rename
    if (::close(fd_) != 0 && ok) ok = false, err = errno;
    fd_ = -1;
  }
  if (!ok)  // the destructor removes a named temporary; an unnamed file vanishes with its descriptor
    throw InputError(path_ + ": write failed: " + (err ? std::strerror(err) : "stream error") +
                     " (nothing written under that name)");
  link_into_place();
  done_ = true;
}

// The file is complete: give it the final name. An unnamed file is linked through
// /proc/self/fd straight to the destination when that does not exist (no temporary name ever),
// else to a hidden temporary name that is renamed over the destination (atomic replacement).
// That rename is the one moment a kill leaves a (complete) hidden copy, so it is made short:
// the new file's writeback is started while it is still unnamed, and the old file is held open
// across the rename, so that freeing its blocks happens at close() after it, not inside it
// (ext4, 20 MB: the rename took about 20 ms, now about 20 us).
void AtomicFile::link_into_place() {
  if (unnamed_) {
    ::sync_file_range(fd_, 0, 0, SYNC_FILE_RANGE_WRITE);
    const std::string self = proc_fd_path(fd_);
    if (::linkat(AT_FDCWD, self.c_str(), AT_FDCWD, path_.c_str(), AT_SYMLINK_FOLLOW) == 0) return;
    if (errno != EEXIST)
      throw InputError(path_ + ": cannot give the finished file its name: " + std::strerror(errno));
  }
  const int old = ::open(path_.c_str(), O_PATH | O_NOFOLLOW | O_CLOEXEC);  // -1 is fine: nothing to hold
  if (unnamed_) {
    const std::string self = proc_fd_path(fd_), base = std::filesystem::path(path_).filename().string();
    for (int attempt = 0; attempt < 100; ++attempt) {
      tmp_ = hidden_temp_name(dir_, base);
      if (::linkat(AT_FDCWD, self.c_str(), AT_FDCWD, tmp_.c_str(), AT_SYMLINK_FOLLOW) == 0) break;
      if (errno != EEXIST) {
        const int e = errno;
        if (old >= 0) ::close(old);
        throw InputError(path_ + ": cannot link the finished file into its folder: " + std::strerror(e));
      }
    }
  }
  const int rc = std::rename(tmp_.c_str(), path_.c_str()), e = errno;
  if (old >= 0) ::close(old);
  if (rc != 0) {
    std::remove(tmp_.c_str());
    throw InputError(path_ + ": cannot rename the finished file onto it: " + std::strerror(e));
  }
}

}  // namespace vpm::detail
