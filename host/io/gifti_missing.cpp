// GIfTI without expat: a clear error (the real reader and writer are host/with_gifti/).
#include "io/formats.hpp"
#include "vpm/config.hpp"
#include "vpm/error.hpp"

namespace vpm::detail {
#if !VPM_HAVE_GIFTI
TriSurface read_gifti(const std::string& path) {
  throw InputError(path + ": this vpm was built without expat: GIfTI input is unavailable");
}
Eigen::VectorXd read_gifti_values(const std::string& path) {
  throw InputError(path + ": this vpm was built without expat: GIfTI input is unavailable");
}
void write_gifti(const std::string& path, const TriSurface&) {
  throw InputError(path + ": this vpm was built without expat: GIfTI output is unavailable");
}
#endif
}  // namespace vpm::detail
