// The ranges of CompareOptions (vpm/statistics.hpp), checked once for every caller: the library's
// compare_to_reference, the command line, the Python binding and the view's sidecar reader.
#include "vpm/statistics.hpp"

#include <cmath>

namespace vpm {

std::optional<CompareOptionError> compare_option_error(const CompareOptions& o) {
  // written as !(in range) so that NaN is out of every range
  if (!(o.threshold > 0)) return CompareOptionError{"threshold", "must be positive"};
  if (!(o.fdr_q >= 0 && o.fdr_q < 1)) return CompareOptionError{"fdr_q", "must be in (0, 1) (or 0: off)"};
  if (o.min_cluster < 1) return CompareOptionError{"min_cluster", "must be >= 1"};
  if (!(o.extend >= 0)) return CompareOptionError{"extend", "must be positive (or 0: off)"};
  if (!(o.relative_extent >= 0 && o.relative_extent <= 1))
    return CompareOptionError{"relative_extent", "must be in (0, 1] (or 0: off)"};
  if (!(o.peak >= 0)) return CompareOptionError{"peak", "must be positive (or 0: off)"};
  if (!(o.tfce_level >= 0 && o.tfce_level < HUGE_VAL))
    return CompareOptionError{"tfce_level", "must be positive and finite (or 0: off)"};
  if (o.sign < -1 || o.sign > 1) return CompareOptionError{"sign", "must be -1 (hypo), 0 (both) or 1 (hyper)"};
  return std::nullopt;
}

}  // namespace vpm
