#pragma once
// The collective view as one self-contained web page (docs/view.md): the browser application
// (web/, bundled with three.js at build time and embedded in the library) and the cohort's data
// in it: a JSON manifest of names and shapes, and every array in one binary buffer (base64).
// It opens from disk in any current browser; nothing is fetched.
#include <string>

#include "vpm/cohort_view.hpp"

namespace vpm {

/// Whether this build carries the browser application (it needs Node.js and the npm packages
/// of web/ at build time: scripts/setup.sh).
bool view_page_available();

/// Size of the page's parts, for reports.
struct ViewPageStats {
  long long bytes = 0;         ///< the whole file
  long long data_bytes = 0;    ///< the binary buffer before base64
  long long script_bytes = 0;  ///< the application
  int buffers = 0;
};

/// Writes `view` as a web page at `html_path` (atomically). InputError when the page cannot be
/// written or this build has no browser application.
ViewPageStats write_view_page(const std::string& html_path, const CohortView& view);

}  // namespace vpm
