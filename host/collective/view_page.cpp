// write_view_page (vpm/view_page.hpp): the manifest and the chunks of the cohort's data
// (collective/view_manifest.hpp) and the browser application in a web page, with the chunks inside
// it or in a folder beside it (layout: docs/view.md).
#include "vpm/view_page.hpp"

#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <regex>

#include "collective/view_manifest.hpp"
#include "core/atomic_file.hpp"
#include "io/vtk_binary.hpp"
#include "vpm/error.hpp"
#include "vpm/json.hpp"

namespace vpm {

namespace detail {
// generated at build time from web/ (cmake/embed_view.cmake); empty strings without Node.js
const char* embedded_view_script();
const char* embedded_view_page();
const char* embedded_view_style();
}  // namespace detail

namespace fs = std::filesystem;

namespace {

/// `text` with every "</" written as "<\/" (so it cannot end its <script> element early).
std::string script_safe(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  for (size_t i = 0; i < text.size(); ++i) {
    out += text[i];
    if (text[i] == '<' && i + 1 < text.size() && text[i + 1] == '/') out += '\\';
  }
  return out;
}

std::string html_escape(const std::string& text) {
  std::string out;
  for (char c : text) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

/// The template with each marker /*VPM_NAME*/ replaced by parts[NAME] (in one pass: a part's
/// text is never searched for markers).
std::string fill(const std::string& page, const std::map<std::string, std::string>& parts) {
  std::string out;
  size_t at = 0;
  for (size_t m; (m = page.find("/*VPM_", at)) != std::string::npos;) {
    const size_t end = page.find("*/", m);
    const auto it = parts.find(page.substr(m + 6, end - m - 6));
    if (end == std::string::npos || it == parts.end()) throw NumericalError("view page template: unknown marker at " + std::to_string(m));
    out.append(page, at, m - at);
    out += it->second;
    at = end + 2;
  }
  return out.append(page, at, std::string::npos);
}

/// Chunks as <script> elements of the page (base64).
class EmbeddedSink : public detail::ChunkSink {
 public:
  void put(const std::string& name, const std::string& bytes, const std::string&) override {
    text += "<script type=\"application/octet-stream\" id=\"vpm-chunk-" + name + "\">" + detail::encode_base64(bytes) + "</script>\n";
  }
  std::string text;
};

/// Chunks as files NAME.js of a folder, each calling vpmChunk(hash, name, base64): a <script>
/// element reads them from file:// (fetch cannot); the page checks the hash against its manifest.
class FolderSink : public detail::ChunkSink {
 public:
  explicit FolderSink(fs::path dir) : dir_(std::move(dir)) {}
  void put(const std::string& name, const std::string& bytes, const std::string& hash) override {
    const fs::path path = dir_ / (name + ".js");
    std::ofstream out(path, std::ios::binary);
    out << "vpmChunk(\"" << hash << "\",\"" << name << "\",\"" << detail::encode_base64(bytes) << "\");\n";
    out.close();
    if (!out) throw InputError(path.string() + ": cannot be written");
    bytes_ += static_cast<long long>(fs::file_size(path));
  }
  long long bytes() const { return bytes_; }

 private:
  fs::path dir_;
  long long bytes_ = 0;
};

/// Whether `dir` holds only files a write of the page's data makes (NAME.js).
bool ours(const fs::path& dir) {
  static const std::regex name("[a-z0-9-]+\\.js");
  for (const auto& entry : fs::directory_iterator(dir))
    if (!entry.is_regular_file() || !std::regex_match(entry.path().filename().string(), name)) return false;
  return true;
}

/// Removes a data folder a write made; InputError, before anything is written, if it holds more.
void remove_data_folder(const fs::path& dir) {
  if (!fs::exists(dir)) return;
  if (!fs::is_directory(dir) || !ours(dir))
    throw InputError(dir.string() + ": holds files vpm view did not write; move them, or the folder, away");
  fs::remove_all(dir);
}

/// The complete folder `tmp` replaces `data` (the page's earlier one, if any).
void replace_folder(const fs::path& tmp, const fs::path& data) {
  const fs::path old = data.string() + ".old";
  try {
    remove_data_folder(old);
    if (fs::exists(data)) fs::rename(data, old);
    fs::rename(tmp, data);
    remove_data_folder(old);
  } catch (const fs::filesystem_error& e) {
    throw InputError(data.string() + ": cannot be replaced (" + e.code().message() + ")");
  }
}

std::string page_text(const Json& manifest, const std::string& title, const std::string& chunks) {
  return fill(detail::embedded_view_page(), {{"STYLE", detail::embedded_view_style()},
                                             {"TITLE", html_escape(title)},
                                             {"MANIFEST", script_safe(manifest.dump(-1))},
                                             {"SCRIPT", script_safe(detail::embedded_view_script())},
                                             {"CHUNKS", chunks}});
}

}  // namespace

ViewData parse_view_data(const std::string& name) {
  if (name == "auto") return ViewData::automatic;
  if (name == "file") return ViewData::embedded;
  if (name == "folder") return ViewData::folder;
  throw InputError("view data '" + name + "': expected auto, file or folder");
}

const char* to_string(ViewData d) {
  return d == ViewData::embedded ? "file" : d == ViewData::folder ? "folder" : "auto";
}

bool view_page_available() { return std::strlen(detail::embedded_view_script()) > 0; }

long long estimated_view_bytes(const CohortView& v) {
  long long n = 0;
  for (const ViewSubject& s : v.subjects) {
    n += static_cast<long long>(s.native.size()) + 2LL * static_cast<long long>(s.centres.size());
    for (const auto& [f, x] : s.values) n += 2LL * static_cast<long long>(x.size());
    for (const auto& [f, x] : s.z) n += 2LL * static_cast<long long>(x.size());
    for (const auto& [f, x] : s.cluster) n += 2LL * static_cast<long long>(x.size());
    for (const auto& [f, x] : s.slices) n += static_cast<long long>(x.image.size() + x.z.size());
  }
  return n;
}

ViewPageStats write_view_page(const std::string& html_path, const CohortView& v, const ViewPageOptions& o) {
  if (!view_page_available())
    throw InputError("this vpm was built without the browser view (web/ needs Node.js and its npm packages at "
                     "build time: run scripts/setup.sh, then rebuild)");
  const bool folder = o.data == ViewData::folder ||
                      (o.data == ViewData::automatic && (static_cast<int>(v.subjects.size()) > o.folder_above ||
                                                         estimated_view_bytes(v) > o.folder_above_bytes));
  const fs::path page = fs::absolute(html_path).lexically_normal();
  const std::string dir_name = page.stem().string() + "_data";
  const fs::path data = page.parent_path() / dir_name, tmp = page.parent_path() / (dir_name + ".tmp");
  detail::ManifestOptions mo;
  mo.rows_per_chunk = o.rows_per_chunk;
  mo.column_elements = o.column_elements;
  mo.columns = folder;
  mo.page_dir = page.parent_path().string();
  EmbeddedSink embedded;
  std::unique_ptr<FolderSink> files;
  if (folder) {  // a folder in the way that holds other files is refused before anything is written
    if (fs::exists(data) && (!fs::is_directory(data) || !ours(data)))
      throw InputError(data.string() + ": holds files vpm view did not write; move them, or the folder, away");
    remove_data_folder(tmp);
    std::error_code ec;
    if (!fs::create_directories(tmp, ec)) throw InputError(tmp.string() + ": cannot be created");
    files = std::make_unique<FolderSink>(tmp);
  }
  detail::ChunkPack pack(folder ? static_cast<detail::ChunkSink&>(*files) : embedded);
  Json m;
  try {
    m = detail::view_manifest(pack, v, mo);
  } catch (...) {
    if (folder) remove_data_folder(tmp);
    throw;
  }
  m["layout"] = folder ? "folder" : "file";
  if (folder) m["data_dir"] = dir_name;
  m["chunks"] = pack.chunks();
  m["buffers"] = pack.buffers();
  if (folder) replace_folder(tmp, data);  // then the page
  else if (fs::is_directory(data) && ours(data)) fs::remove_all(data);  // the page's earlier data folder
  const std::string text = page_text(m, v.title, embedded.text);
  detail::AtomicFile file(html_path);
  file.stream() << text;
  file.commit();
  ViewPageStats st;
  st.bytes = static_cast<long long>(text.size()) + (files ? files->bytes() : 0);
  st.data_bytes = pack.bytes();
  st.script_bytes = static_cast<long long>(std::strlen(detail::embedded_view_script()));
  st.buffers = pack.count();
  st.chunks = static_cast<int>(pack.chunks().size());
  st.data_dir = folder ? data.string() : "";
  return st;
}

}  // namespace vpm
