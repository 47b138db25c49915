#include "linalg/amg_state.hpp"

#include "vpm/timing.hpp"

namespace vpm::detail {

double AmgState::prepare(Device* dev, const CsrMatrix& a, const std::vector<char>& m,
                         const AmgOptions& o) {
  const auto t0 = Clock::now();
  const bool rebuild = !host || m != mask || !(o == options);
  if (!rebuild && !stale) return 0.0;
  if (rebuild) {
    host = std::make_unique<AmgHierarchy>(a, m, o);
    mask = m;
    options = o;
  } else {
    host->update_values(a);
  }
  if (dev && !dev->is_host()) {
    if (!device) device = std::make_unique<ClAmg>(*dev);
    device->upload(*host, rebuild);
  }
  stale = false;
  return seconds_since(t0);
}

}  // namespace vpm::detail
