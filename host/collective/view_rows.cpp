// The subjects' chunks of the page's data (collective/view_rows.hpp).
#include "collective/view_rows.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>

namespace vpm::detail {

namespace {

std::string numbered(const char* prefix, size_t n) {
  char buf[48];
  std::snprintf(buf, sizeof buf, "%s-%03zu", prefix, n);
  return buf;
}

/// A subject's shape as 8-bit differences from the mean shape (its centre removed): code * scale
/// mm, the scale set by its largest difference (0.1-0.2 mm for brains that differ by 13-25 mm).
Json native_entry(ChunkPack& pack, const std::string& key, const ViewSubject& s, const std::array<double, 3>& centre,
                  const std::vector<float>& mean) {
  std::vector<double> diff(s.native.size());
  double worst = 1e-6;
  for (size_t i = 0; i < diff.size(); ++i) {
    diff[i] = s.native[i] - centre[i % 3] - mean[i];
    worst = std::max(worst, std::abs(diff[i]));
  }
  const double scale = worst / 127.0;
  std::vector<std::int8_t> q(diff.size());
  for (size_t i = 0; i < q.size(); ++i) q[i] = static_cast<std::int8_t>(std::clamp(std::lround(diff[i] / scale), -127L, 127L));
  Json j = Json::object(), c = Json::array();
  for (double x : centre) c.push_back(x);
  j["buffer"] = pack.add(key + "_native", q, "i8");
  j["scale"] = scale;
  j["centre"] = c;
  return j;
}

/// The element where the page turns a row to face focus `id`: on the shell where the focus is
/// widest (most elements; the outer one of a tie), its element of the largest |z| there.
int face_element(const std::vector<std::int32_t>& cluster, const std::vector<float>& z, const std::vector<long>& offsets, int id) {
  const auto shell = [&](size_t e) {
    return static_cast<int>(std::upper_bound(offsets.begin(), offsets.end(), static_cast<long>(e)) - offsets.begin()) - 1;
  };
  std::vector<int> count(offsets.size(), 0);
  for (size_t e = 0; e < cluster.size(); ++e)
    if (cluster[e] == id) ++count[static_cast<size_t>(shell(e))];
  const int widest = static_cast<int>(std::max_element(count.rbegin(), count.rend()) - count.rbegin());
  const int k = static_cast<int>(count.size()) - 1 - widest;
  int best = -1;
  for (size_t e = 0; e < cluster.size(); ++e)
    if (cluster[e] == id && shell(e) == k && (best < 0 || std::abs(z[e]) > std::abs(z[static_cast<size_t>(best)])))
      best = static_cast<int>(e);
  return best;
}

Json foci_entry(const ViewSubject& s, const std::string& f, const CohortView& v, const std::vector<long>& offsets) {
  Json rows = Json::array();
  const auto cl = s.cluster.find(f);
  const auto z = s.z.find(f);
  for (const ViewFocus& focus : s.foci.at(f)) {
    Json r = Json::object(), c = Json::array();
    for (int a = 0; a < 3; ++a) c.push_back(focus.centroid[a]);
    r["id"] = focus.id;
    r["volume_mm3"] = focus.volume_mm3;
    r["peak_z"] = focus.peak_z;
    r["peak_element"] = focus.peak_element;
    r["face_element"] = cl != s.cluster.end() && z != s.z.end() ? face_element(cl->second, z->second, offsets, focus.id) : -1;
    r["centroid"] = c;
    r["label"] = focus.label;
    const auto it = v.label_names.find(focus.label);
    r["region"] = focus.label == 0 ? "" : it != v.label_names.end() ? it->second : "label " + std::to_string(focus.label);
    rows.push_back(r);
  }
  return rows;
}

/// One subject's entry; its row data (shape, values, patients' z and foci) into the open chunk.
Json row_entry(ChunkPack& pack, const CohortView& v, size_t i, const Shapes& shapes, const FeatureCodes& codes,
               const std::vector<long>& offsets) {
  const ViewSubject& s = v.subjects[i];
  const std::string key = "s" + std::to_string(i);
  Json j = Json::object(), values = Json::object(), z = Json::object();
  j["id"] = s.id;
  j["group"] = s.patient ? "patient" : "normal";
  j["native"] = native_entry(pack, key, s, shapes.centre[i], shapes.mean);
  for (const auto& [f, x] : s.values) values[f] = pack.add_q16(key + "_value_" + f, x, codes.values.at(f));
  j["values"] = values;
  if (!s.patient) return j;
  for (const auto& [f, x] : s.z) z[f] = pack.add_q16(key + "_z_" + f, x, codes.z.at(f));
  j["z"] = z;
  Json count = Json::object(), table = Json::object(), cluster = Json::object();
  for (const auto& [f, n] : s.foci_count) count[f] = n;
  for (const auto& [f, ids] : s.cluster) {
    std::vector<std::uint16_t> id(ids.size());
    for (size_t e = 0; e < ids.size(); ++e) id[e] = static_cast<std::uint16_t>(std::clamp(ids[e], 0, 65535));
    cluster[f] = pack.add(key + "_cluster_" + f, id, "u16");
  }
  for (const auto& [f, list] : s.foci) table[f] = foci_entry(s, f, v, offsets);
  j["cluster"] = cluster;
  j["foci"] = count;
  j["foci_table"] = table;
  return j;
}

/// `path` relative to the page's folder (the page never shows where the user's files are).
std::string relative_to(const std::string& path, const std::string& dir) {
  namespace fs = std::filesystem;
  const fs::path p = fs::absolute(path).lexically_normal();
  const fs::path rel = dir.empty() ? fs::path() : p.lexically_relative(fs::absolute(dir).lexically_normal());
  return rel.empty() ? p.filename().generic_string() : rel.generic_string();
}

Json slices_entry(ChunkPack& pack, const std::string& key, const ViewSlices& s, const std::string& page_dir) {
  Json j = Json::object(), dims = Json::array(), affine = Json::array();
  for (int a = 0; a < 3; ++a) dims.push_back(s.dims[a]);
  for (int r = 0; r < 4; ++r)
    for (int c = 0; c < 4; ++c) affine.push_back(s.affine(r, c));
  j["dims"] = dims;
  j["affine"] = affine;
  j["step"] = s.step;
  j["image_source"] = relative_to(s.source, page_dir);
  j["image"] = pack.add(key + "_image", s.image, "u8");
  j["z"] = pack.add(key + "_zmap", s.z, "i8");
  j["z_scale"] = s.z_scale;
  return j;
}

/// A patient's detail chunk: element centres (16-bit in its bounding box) and slices.
void detail_chunk(ChunkPack& pack, const ViewSubject& s, size_t i, Json& entry, const std::string& page_dir) {
  const std::string key = "s" + std::to_string(i), chunk = numbered("detail", i);
  pack.begin(chunk);
  double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
  for (size_t k = 0; k < s.centres.size(); ++k) {
    lo[k % 3] = std::min(lo[k % 3], double(s.centres[k]));
    hi[k % 3] = std::max(hi[k % 3], double(s.centres[k]));
  }
  double half = 1e-9;
  Json offset = Json::array();
  for (int a = 0; a < 3; ++a) {
    half = std::max(half, 0.5 * (hi[a] - lo[a]));
    offset.push_back(std::isfinite(lo[a]) ? 0.5 * (hi[a] + lo[a]) : 0.0);
  }
  const double scale = half / 32767.0;
  std::vector<std::int16_t> q(s.centres.size());
  for (size_t k = 0; k < q.size(); ++k) q[k] = static_cast<std::int16_t>(std::lround((s.centres[k] - offset.at(k % 3).number()) / scale));
  Json c = Json::object(), slices = Json::object();
  c["buffer"] = pack.add(key + "_centres", q, "i16");
  c["scale"] = scale;
  c["offset"] = offset;
  entry["centres"] = c;
  for (const auto& [f, sl] : s.slices) slices[f] = slices_entry(pack, key + "_" + f, sl, page_dir);
  if (!s.slices.empty()) entry["slices"] = slices;
  entry["detail"] = chunk;
  pack.end();
}

}  // namespace

Shapes subject_shapes(const CohortView& v) {
  Shapes out;
  const size_t K = static_cast<size_t>(v.definition.shells), V = static_cast<size_t>(v.display.vertices.rows());
  out.mean.assign(K * V * 3, 0.0f);
  out.shell_radius.assign(K, 0.0);
  std::vector<double> sum(K * V * 3, 0.0);
  int normals = 0;
  for (const ViewSubject& s : v.subjects) {
    std::array<double, 3> c{0, 0, 0};
    for (size_t p = (K - 1) * V; p < K * V; ++p)
      for (int a = 0; a < 3; ++a) c[a] += s.native[3 * p + a] / double(V);
    out.centre.push_back(c);
    for (size_t k = 0; k < K; ++k)
      for (size_t p = k * V; p < (k + 1) * V; ++p)
        out.shell_radius[k] = std::max(out.shell_radius[k], std::hypot(s.native[3 * p] - c[0], s.native[3 * p + 1] - c[1], s.native[3 * p + 2] - c[2]));
    if (s.patient) continue;
    ++normals;
    for (size_t i = 0; i < sum.size(); ++i) sum[i] += s.native[i] - c[i % 3];
  }
  for (size_t i = 0; i < sum.size(); ++i) out.mean[i] = static_cast<float>(sum[i] / std::max(1, normals));
  return out;
}

Json subject_chunks(ChunkPack& pack, const CohortView& v, const Shapes& shapes, const FeatureCodes& codes, const ManifestOptions& o) {
  const std::vector<long> offsets = shell_offsets(v.definition);
  const size_t per = static_cast<size_t>(std::max(1, o.rows_per_chunk));
  std::vector<Json> entries;
  for (size_t i = 0; i < v.subjects.size(); ++i) {
    if (i % per == 0) pack.begin(numbered("rows", i / per));
    entries.push_back(row_entry(pack, v, i, shapes, codes, offsets));
    entries.back()["chunk"] = numbered("rows", i / per);
  }
  pack.end();
  for (size_t i = 0; i < v.subjects.size(); ++i)
    if (v.subjects[i].patient) detail_chunk(pack, v.subjects[i], i, entries[i], o.page_dir);
  Json out = Json::array();
  for (Json& e : entries) out.push_back(std::move(e));
  return out;
}

Json column_chunks(ChunkPack& pack, const CohortView& v, const FeatureCodes& codes, int elements) {
  Json out = Json::object();
  std::vector<size_t> normals;
  for (size_t i = 0; i < v.subjects.size(); ++i)
    if (!v.subjects[i].patient) normals.push_back(i);
  const size_t n = normals.size(), E = static_cast<size_t>(v.definition.elements()), per = static_cast<size_t>(std::max(1, elements));
  for (size_t fi = 0; fi < v.features.size(); ++fi) {
    const std::string& f = v.features[fi].name;
    Json buffers = Json::array(), idx = Json::array();
    for (size_t i : normals) idx.push_back(static_cast<long long>(i));
    for (size_t c = 0; c * per < E; ++c) {
      const size_t e0 = c * per, e1 = std::min(E, e0 + per);
      std::vector<std::uint16_t> code((e1 - e0) * n);
      for (size_t j = 0; j < n; ++j) {
        const std::vector<float>& x = v.subjects[normals[j]].values.at(f);
        for (size_t e = e0; e < e1; ++e) code[(e - e0) * n + j] = codes.values.at(f).code(x[e]);
      }
      pack.begin(numbered(("cols-" + std::to_string(fi)).c_str(), c));
      buffers.push_back(pack.add(numbered(("cols_" + f).c_str(), c), code, "u16"));
      pack.end();
    }
    Json entry = Json::object();
    entry["elements"] = static_cast<long long>(per);
    entry["buffers"] = buffers;
    entry["normals"] = idx;
    out[f] = entry;
  }
  return out;
}

}  // namespace vpm::detail
