// write_view_page (vpm/view_page.hpp): the cohort's arrays packed into one binary buffer, a JSON
// manifest naming them, and the browser application, in one HTML file (layout: docs/view.md).
#include "vpm/view_page.hpp"

#include <cmath>
#include <cstring>

#include "core/atomic_file.hpp"
#include "vpm/error.hpp"
#include "vpm/json.hpp"

namespace vpm {

namespace detail {
// generated at build time from web/ (cmake/embed_view.cmake); empty strings without Node.js
const char* embedded_view_script();
const char* embedded_view_page();
const char* embedded_view_style();
}  // namespace detail

namespace {

/// Arrays appended to one blob, 8-byte aligned, each named in the manifest's "buffers".
class BufferPack {
 public:
  template <class T>
  std::string add(const std::string& name, const std::vector<T>& values, const char* type) {
    while (blob_.size() % 8) blob_.push_back('\0');
    Json b = Json::object();
    b["offset"] = static_cast<long long>(blob_.size());
    b["length"] = static_cast<long long>(values.size());
    b["type"] = type;
    table_[name] = b;
    const char* p = reinterpret_cast<const char*>(values.data());
    blob_.append(p, p + values.size() * sizeof(T));
    ++count_;
    return name;
  }
  /// `values` as 16-bit codes: base + step * code, code 65535 = NaN (type "q16" with "base" and
  /// "step"; the page decodes it to float32). Half the bytes of float32, within step / 2.
  std::string add_q16(const std::string& name, const std::vector<float>& values) {
    float lo = 0, hi = 0;
    bool any = false;
    for (float v : values)
      if (std::isfinite(v)) {
        lo = any ? std::min(lo, v) : v;
        hi = any ? std::max(hi, v) : v;
        any = true;
      }
    const double step = hi > lo ? (static_cast<double>(hi) - lo) / 65534.0 : 1.0;
    std::vector<std::uint16_t> code(values.size());
    for (size_t i = 0; i < values.size(); ++i)
      code[i] = std::isfinite(values[i]) ? static_cast<std::uint16_t>(std::lround((values[i] - lo) / step)) : 65535;
    add(name, code, "q16");
    table_[name]["base"] = static_cast<double>(lo);
    table_[name]["step"] = step;
    return name;
  }
  const std::string& blob() const { return blob_; }
  Json& table() { return table_; }
  int count() const { return count_; }

 private:
  std::string blob_;
  Json table_ = Json::object();
  int count_ = 0;
};

std::string base64(const std::string& in) {
  static const char* A = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((in.size() + 2) / 3 * 4);
  for (size_t i = 0; i < in.size(); i += 3) {
    const unsigned n = (static_cast<unsigned char>(in[i]) << 16) |
                       (i + 1 < in.size() ? static_cast<unsigned char>(in[i + 1]) << 8 : 0) |
                       (i + 2 < in.size() ? static_cast<unsigned char>(in[i + 2]) : 0);
    out += A[(n >> 18) & 63];
    out += A[(n >> 12) & 63];
    out += i + 1 < in.size() ? A[(n >> 6) & 63] : '=';
    out += i + 2 < in.size() ? A[n & 63] : '=';
  }
  return out;
}

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

Json native_entry(BufferPack& pack, const std::string& key, const std::vector<float>& native) {
  float lo[3] = {1e30f, 1e30f, 1e30f}, hi[3] = {-1e30f, -1e30f, -1e30f};
  for (size_t i = 0; i < native.size(); ++i) {
    lo[i % 3] = std::min(lo[i % 3], native[i]);
    hi[i % 3] = std::max(hi[i % 3], native[i]);
  }
  double half = 1e-9;
  Json offset = Json::array();
  for (int a = 0; a < 3; ++a) {
    half = std::max(half, 0.5 * (double(hi[a]) - lo[a]));
    offset.push_back(0.5 * (double(hi[a]) + lo[a]));
  }
  const double scale = half / 32767.0;
  std::vector<std::int16_t> q(native.size());
  for (size_t i = 0; i < native.size(); ++i)
    q[i] = static_cast<std::int16_t>(std::lround((native[i] - offset.at(i % 3).number()) / scale));
  Json j = Json::object();
  j["buffer"] = pack.add(key + "_native", q, "i16");
  j["scale"] = scale;
  j["offset"] = offset;
  return j;
}

Json slices_entry(BufferPack& pack, const std::string& key, const ViewSlices& s) {
  Json j = Json::object(), dims = Json::array(), affine = Json::array();
  for (int a = 0; a < 3; ++a) dims.push_back(s.dims[a]);
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) affine.push_back(s.affine(r, c));
  j["dims"] = dims;
  j["affine"] = affine;
  j["step"] = s.step;
  j["image_source"] = s.source;
  j["image"] = pack.add(key + "_image", s.image, "u8");
  j["z"] = pack.add(key + "_zmap", s.z, "i8");
  j["z_scale"] = s.z_scale;
  return j;
}

Json foci_entry(const std::vector<ViewFocus>& foci, const CohortView& v) {
  Json rows = Json::array();
  for (const ViewFocus& f : foci) {
    Json r = Json::object(), c = Json::array();
    for (int a = 0; a < 3; ++a) c.push_back(f.centroid[a]);
    r["id"] = f.id;
    r["volume_mm3"] = f.volume_mm3;
    r["peak_z"] = f.peak_z;
    r["peak_element"] = f.peak_element;
    r["centroid"] = c;
    r["label"] = f.label;
    const auto it = v.label_names.find(f.label);
    r["region"] = f.label == 0 ? "" : it != v.label_names.end() ? it->second : "label " + std::to_string(f.label);
    rows.push_back(r);
  }
  return rows;
}

Json subject_entry(BufferPack& pack, const ViewSubject& s, size_t i, const CohortView& v) {
  const std::string key = "s" + std::to_string(i);
  Json j = Json::object(), values = Json::object(), z = Json::object();
  j["id"] = s.id;
  j["group"] = s.patient ? "patient" : "normal";
  j["native"] = native_entry(pack, key, s.native);
  for (const auto& [f, x] : s.values) values[f] = pack.add_q16(key + "_value_" + f, x);
  for (const auto& [f, x] : s.z) z[f] = pack.add_q16(key + "_z_" + f, x);
  j["values"] = values;
  j["z"] = z;
  if (s.patient) {
    Json count = Json::object(), table = Json::object(), cluster = Json::object();
    for (const auto& [f, n] : s.foci_count) count[f] = n;
    for (const auto& [f, ids] : s.cluster) cluster[f] = pack.add(key + "_cluster_" + f, ids, "i32");
    j["cluster"] = cluster;
    for (const auto& [f, list] : s.foci) table[f] = foci_entry(list, v);
    j["foci"] = count;
    j["foci_table"] = table;
    j["centres"] = pack.add(key + "_centres", s.centres, "f32");
  }
  if (!s.slices.empty()) {
    Json slices = Json::object();
    for (const auto& [f, sl] : s.slices) slices[f] = slices_entry(pack, key + "_" + f, sl);
    j["slices"] = slices;
  }
  return j;
}

Json manifest(BufferPack& pack, const CohortView& v) {
  Json m = Json::object();
  m["format"] = "vpm-view-1";
  m["title"] = v.title;
  m["definition"] = to_json(v.definition);
  m["shells"] = v.definition.shells;
  m["triangles"] = v.definition.triangles();
  m["elements"] = v.definition.elements();
  Json levels = Json::array(), offsets = Json::array();
  long offset = 0;
  offsets.push_back(offset);
  for (int l : shell_levels(v.definition)) {
    levels.push_back(l);
    offsets.push_back(offset += 20L << (2 * l));
  }
  m["shell_levels"] = levels;    // per shell, innermost first
  m["shell_offsets"] = offsets;  // first element id of each shell, and the element count
  Json radii = Json::array();
  for (double r : v.mid_radii) radii.push_back(r);
  m["radii"] = radii;
  std::vector<std::uint32_t> index(v.display.triangles.size());
  for (Eigen::Index f = 0; f < v.display.triangles.rows(); ++f)
    for (int c = 0; c < 3; ++c) index[3 * f + c] = static_cast<std::uint32_t>(v.display.triangles(f, c));
  std::vector<float> sphere(v.display.vertices.size());
  for (Eigen::Index p = 0; p < v.display.vertices.rows(); ++p)
    for (int c = 0; c < 3; ++c) sphere[3 * p + c] = static_cast<float>(v.display.vertices(p, c));
  Json d = Json::object();
  d["vertices"] = static_cast<long long>(v.display.vertices.rows());
  d["triangles"] = static_cast<long long>(v.display.triangles.rows());
  d["finer"] = v.display.triangles.rows() > v.definition.triangles();  // 4 display triangles per element triangle
  m["display"] = d;
  pack.add("display_index", index, "u32");
  pack.add("display_sphere", sphere, "f32");
  pack.add("display_element_triangle", std::vector<std::uint32_t>(v.display_triangle_element.begin(), v.display_triangle_element.end()), "u32");
  Json features = Json::array(), reference = Json::object();
  for (const ViewFeature& f : v.features) {
    Json j = Json::object(), r = Json::object();
    j["name"] = f.name;
    j["normalisation"] = to_string(f.normalisation);
    j["threshold"] = f.compare.threshold;
    j["fdr_q"] = f.compare.fdr_q;
    j["min_cluster"] = f.compare.min_cluster;
    j["extend"] = f.compare.extend;
    j["peak"] = f.compare.peak;
    j["test"] = to_string(f.compare.test);
    j["smoothing"] = f.smoothing;
    j["sign"] = f.compare.sign;
    j["reference_subjects"] = f.reference_subjects;
    features.push_back(j);
    r["mean"] = pack.add("reference_mean_" + f.name, f.mean, "f32");
    r["std"] = pack.add("reference_std_" + f.name, f.std, "f32");
    reference[f.name] = r;
  }
  m["features"] = features;
  m["reference"] = reference;
  if (!v.element_label.empty()) {
    Json regions = Json::object(), names = Json::object();
    regions["buffer"] = pack.add("element_region", std::vector<std::int32_t>(v.element_label.begin(), v.element_label.end()), "i32");
    for (const auto& [id, name] : v.label_names) names[std::to_string(id)] = name;
    regions["names"] = names;
    m["regions"] = regions;
  }
  Json subjects = Json::array();
  for (size_t i = 0; i < v.subjects.size(); ++i) subjects.push_back(subject_entry(pack, v.subjects[i], i, v));
  m["subjects"] = subjects;
  return m;
}

void replace_once(std::string& text, const std::string& marker, const std::string& with) {
  const size_t at = text.find(marker);
  if (at == std::string::npos) throw NumericalError("view page template has no " + marker);
  text.replace(at, marker.size(), with);
}

}  // namespace

bool view_page_available() { return std::strlen(detail::embedded_view_script()) > 0; }

ViewPageStats write_view_page(const std::string& html_path, const CohortView& v) {
  if (!view_page_available())
    throw InputError("this vpm was built without the browser view (web/ needs Node.js and its npm packages at "
                     "build time: run scripts/setup.sh, then rebuild)");
  BufferPack pack;
  Json m = manifest(pack, v);
  m["buffers"] = pack.table();
  std::string page = detail::embedded_view_page();
  const std::string script = script_safe(detail::embedded_view_script());
  replace_once(page, "/*VPM_STYLE*/", detail::embedded_view_style());
  replace_once(page, "/*VPM_MANIFEST*/", script_safe(m.dump(-1)));
  replace_once(page, "/*VPM_BUFFERS*/", base64(pack.blob()));
  replace_once(page, "/*VPM_SCRIPT*/", script);
  detail::AtomicFile file(html_path);
  file.stream() << page;
  file.commit();
  return {static_cast<long long>(page.size()), static_cast<long long>(pack.blob().size()),
          static_cast<long long>(script.size()), pack.count()};
}

}  // namespace vpm
