#pragma once
// Private to io/hdf5*.cpp: the lock every call into the HDF5 library holds, with the library's
// automatic error printing off for the calling thread (a per-thread setting in a thread-safe build).
#include <hdf5.h>

#include <mutex>

namespace vpm::detail::h5 {

struct Guard {
  Guard() : hold(mutex()) { H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr); }
  static std::recursive_mutex& mutex() {
    static std::recursive_mutex m;
    return m;
  }
  std::lock_guard<std::recursive_mutex> hold;
};

}  // namespace vpm::detail::h5
