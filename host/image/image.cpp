// Image reading without nifti_clib: a clear error (the real reader is host/with_nifti/).
#include "vpm/config.hpp"
#include "vpm/error.hpp"
#include "vpm/image.hpp"

namespace vpm {
#if !VPM_HAVE_NIFTI
Image read_nifti(const std::string& path) {
  throw InputError(path + ": this vpm was built without nifti_clib: NIfTI input is unavailable");
}
void write_nifti(const std::string& path, const Image&) {
  throw InputError(path + ": this vpm was built without nifti_clib: NIfTI output is unavailable");
}
#endif
}  // namespace vpm
