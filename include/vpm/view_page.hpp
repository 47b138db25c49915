#pragma once
// The collective view as a web page (docs/view.md): the browser application (web/, bundled with
// three.js at build time and embedded in the library) and the cohort's data: a JSON manifest of
// names and shapes, and every array in named binary chunks (format vpm-view-2). Small cohorts get
// one self-contained file (the chunks inside, base64); large ones a page and a folder beside it
// (PAGE_data/, one script file per chunk), which the page reads a row at a time. Both open from
// disk in any current browser; nothing is fetched from elsewhere.
#include <string>

#include "vpm/cohort_view.hpp"

namespace vpm {

/// Whether this build carries the browser application (it needs Node.js and the npm packages
/// of web/ at build time: scripts/setup.sh).
bool view_page_available();

/// Where the page's data goes.
enum class ViewData {
  /// embedded up to ViewPageOptions::folder_above subjects and folder_above_bytes of data
  /// (estimated_view_bytes), else a folder
  automatic,
  embedded,   ///< one self-contained file
  folder,     ///< the page and PAGE_data/ beside it
};
ViewData parse_view_data(const std::string& name);  ///< "auto", "file" or "folder"; InputError otherwise
const char* to_string(ViewData d);

struct ViewPageOptions {
  ViewData data = ViewData::automatic;
  int folder_above = 120;     ///< automatic: a folder for more subjects than this
  /// automatic: a folder for more data than this (estimated_view_bytes, before base64): a
  /// browser reads a one-file page whole before it draws, a folder a row at a time (level-5
  /// elements: about 2.4 MB a normal, 7 MB a patient)
  long long folder_above_bytes = 100LL << 20;
  int rows_per_chunk = 8;     ///< subjects per chunk of rows (what the page reads at a time)
  int column_elements = 1024; ///< folder: elements per chunk of the normals' values by element
};

/// The subjects' binary data in a page of `view`, estimated from their arrays as the page encodes
/// them (shells: a byte a coordinate; values, z, clusters and centres: two bytes; slices: a byte
/// a voxel): what grows with the cohort and the element level, most of ViewPageStats::data_bytes
/// in a large cohort's page (the rest: the display sphere, the reference, the atlas).
long long estimated_view_bytes(const CohortView& view);

/// Size of the page's parts, for reports.
struct ViewPageStats {
  long long bytes = 0;         ///< the page, and the data folder's files when there is one
  long long data_bytes = 0;    ///< the binary chunks before base64
  long long script_bytes = 0;  ///< the application
  int buffers = 0;
  int chunks = 0;
  std::string data_dir;        ///< the data folder ("" when embedded)
};

/// Writes `view` as a web page at `html_path` (the page atomically; a data folder is written
/// beside it first, under a temporary name, and replaces an earlier one of the same page only
/// when complete). InputError when the page cannot be written, a folder in the way holds other
/// files, or this build has no browser application.
ViewPageStats write_view_page(const std::string& html_path, const CohortView& view, const ViewPageOptions& options = {});

}  // namespace vpm
