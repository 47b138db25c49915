#include "core/atomic_file.hpp"

#include <unistd.h>

#include <cstdio>
#include <filesystem>

#include "vpm/error.hpp"

namespace vpm::detail {

AtomicFile::AtomicFile(const std::string& path, bool binary) : path_(path) {
  std::filesystem::path p(path);
  std::filesystem::path dir = p.parent_path();
  if (!dir.empty() && !std::filesystem::is_directory(dir))
    throw InputError(path + ": cannot write: folder '" + dir.string() + "' does not exist");
  tmp_ = (dir / ("." + p.filename().string() + ".tmp." + std::to_string(::getpid()))).string();
  out_.open(tmp_, binary ? std::ios::out | std::ios::binary : std::ios::out);
  if (!out_) throw InputError(path + ": cannot write: permission denied or invalid path");
  out_.precision(17);
}

AtomicFile::~AtomicFile() {
  if (!done_) {
    out_.close();
    std::remove(tmp_.c_str());
  }
}

void AtomicFile::commit() {
  out_.flush();
  bool ok = static_cast<bool>(out_);
  out_.close();
  if (!ok) {
    std::remove(tmp_.c_str());
    done_ = true;
    throw InputError(path_ + ": write failed (disk full?)");
  }
  if (std::rename(tmp_.c_str(), path_.c_str()) != 0) {
    std::remove(tmp_.c_str());
    done_ = true;
    throw InputError(path_ + ": cannot rename the temporary file onto it");
  }
  done_ = true;
}

}  // namespace vpm::detail
