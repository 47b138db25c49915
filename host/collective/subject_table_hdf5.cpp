// Subject tables in HDF5 (vpm/sampling.hpp, TableFormat::hdf5).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>

#include "collective/subject_table_formats.hpp"
#include "io/hdf5.hpp"
#include "vpm/error.hpp"

namespace vpm::detail {

namespace {

constexpr const char* kFormat = "vpm element table";
constexpr std::int64_t kFormatVersion = 1;
// The most label columns, and label values, one table may hold (a level-6 table of the 116 AAL
// labels holds 251 million)
constexpr std::size_t kMaxLabels = 1 << 16;
constexpr double kMaxLabelValues = double(1 << 29);

// A feature's standard deviation keeps this many significant bits of float32's 24 (a relative
// precision of 1/4096): a spread over S samples is itself uncertain by far more, and the bits
// dropped are noise that no compressor shrinks (a level-6 table of two features: 26.5 -> 20 MB).
constexpr int kSpreadBits = 12;

std::string feature_group(const std::string& name) { return "/features/" + name; }

// `values` as float32 rounded to the nearest value with kSpreadBits significant bits (NaN and
// infinities kept).
std::vector<double> spread_values(const std::vector<double>& values) {
  std::vector<double> out(values.size());
  constexpr std::uint32_t drop = 24 - kSpreadBits, half = 1u << (drop - 1), mask = ~((1u << drop) - 1);
  for (size_t i = 0; i < values.size(); ++i) {
    const float f = static_cast<float>(values[i]);
    std::uint32_t bits;
    std::memcpy(&bits, &f, sizeof bits);
    if ((bits & 0x7f800000u) != 0x7f800000u) bits = (bits + half) & mask;  // finite: round the mantissa
    float r;
    std::memcpy(&r, &bits, sizeof r);
    out[i] = r;
  }
  return out;
}

void write_features(h5::Writer& w, const ElementTable& t, std::size_t n) {
  w.group("/features");
  for (const ElementFeature& f : t.features) {
    const std::string g = feature_group(f.name);
    w.group(g);
    w.attribute(g, "source", f.source);
    w.attribute(g, "interpolation", std::string("trilinear"));
    w.dataset(g + "/mean", f.mean.data(), n, 1, h5::Stored::f32);
    const std::vector<double> spread = spread_values(f.std);
    w.dataset(g + "/std", spread.data(), n, 1, h5::Stored::f32);
    w.dataset(g + "/count", f.count.data(), n, 1, h5::Stored::u16);
  }
}

void write_labels(h5::Writer& w, const ElementTable& t, std::size_t n) {
  w.group("/labels");
  for (std::size_t k = 0; k < t.label_images.size(); ++k) {
    const ElementLabels& l = t.label_images[k];
    const std::string g = "/labels/" + std::to_string(k);
    w.group(g);
    w.attribute(g, "source", l.source);
    w.dataset(g + "/ids", l.labels.data(), l.labels.size(), 1, h5::Stored::i32);
    std::vector<double> fraction(l.labels.size() * n);  // labels x elements, row-major
    for (std::size_t i = 0; i < l.labels.size(); ++i) std::copy(l.fraction[i].begin(), l.fraction[i].end(), fraction.begin() + static_cast<std::ptrdiff_t>(i * n));
    if (!l.labels.empty()) w.dataset(g + "/fraction", fraction.data(), l.labels.size(), n, h5::Stored::f32);
  }
}

void read_feature(const h5::Reader& r, ElementFeature& f, std::size_t n, int samples, bool spread) {
  const std::string g = feature_group(f.name);
  f.mean = r.doubles(g + "/mean", n);
  if (spread) f.std = r.doubles(g + "/std", n);
  const std::vector<std::int64_t> count = r.integers(g + "/count", n);
  f.count.resize(n);
  for (std::size_t e = 0; e < n; ++e) {
    if (count[e] < 0 || count[e] > samples)
      throw InputError(r.path() + ": " + g + "/count: element " + std::to_string(e) + " has " + std::to_string(count[e]) +
                       " samples, the definition " + std::to_string(samples));
    f.count[e] = static_cast<int>(count[e]);
  }
}

ElementLabels read_labels(const h5::Reader& r, std::size_t k, std::size_t n) {
  const std::string g = "/labels/" + std::to_string(k);
  ElementLabels l;
  l.source = r.string_attribute(g, "source").value_or("");
  const std::vector<std::size_t> shape = r.shape(g + "/ids");
  if (shape.size() != 1 || shape[0] > kMaxLabels || double(shape[0]) * double(n) > kMaxLabelValues)
    throw InputError(r.path() + ": " + g + "/ids: too many labels for " + std::to_string(n) + " elements");
  const std::size_t count = shape[0];
  for (std::int64_t id : r.integers(g + "/ids", count)) {
    if (id == 0 || id < INT32_MIN || id > INT32_MAX || (!l.labels.empty() && id <= l.labels.back()))
      throw InputError(r.path() + ": " + g + "/ids: label " + std::to_string(id) + " is 0, not ascending or out of range");
    l.labels.push_back(static_cast<int>(id));
  }
  if (count == 0) return l;
  const std::vector<double> fraction = r.doubles(g + "/fraction", count, n);
  l.fraction.assign(count, std::vector<double>(n));
  for (std::size_t i = 0; i < count; ++i)
    std::copy(fraction.begin() + static_cast<std::ptrdiff_t>(i * n), fraction.begin() + static_cast<std::ptrdiff_t>((i + 1) * n),
              l.fraction[i].begin());
  return l;
}

}  // namespace

void write_subject_table_hdf5(const std::string& path, const ElementTable& t) {
  const std::size_t n = static_cast<std::size_t>(checked_table_size(path, t));
  h5::Writer w(path);
  w.attribute("/", "format", std::string(kFormat));
  w.attribute("/", "format_version", kFormatVersion);
  w.attribute("/", "metadata", table_metadata(t).dump(-1));
  w.attribute("/", "subject", t.subject);
  w.attribute("/", "level", std::int64_t{t.definition.level});
  w.attribute("/", "shells", std::int64_t{t.definition.shells});
  w.attribute("/", "samples", std::int64_t{t.definition.samples});
  w.attribute("/", "layout", std::string(to_string(t.definition.layout)));
  write_features(w, t, n);
  write_labels(w, t, n);
  w.commit();
}

ElementTable read_subject_table_hdf5(const std::string& path, const TableColumns& columns) {
  const h5::Reader r(path);
  if (r.string_attribute("/", "format", 256) != kFormat)
    throw InputError(path + ": not a vpm element table (no root attribute format = '" + kFormat + "')");
  const std::optional<std::int64_t> version = r.integer_attribute("/", "format_version");
  if (version != kFormatVersion)
    throw InputError(path + ": element table format version " + (version ? std::to_string(*version) : "missing") +
                     ", this vpm reads " + std::to_string(kFormatVersion));
  const std::optional<std::string> meta = r.string_attribute("/", "metadata");
  if (!meta) throw InputError(path + ": no metadata attribute");
  Json j;
  try {
    j = Json::parse(*meta);
  } catch (const std::exception& e) {
    throw InputError(path + ": the metadata attribute: " + e.what());
  }
  ElementTable t;
  read_table_metadata(j, path + ": metadata", t, true);
  const std::size_t n = static_cast<std::size_t>(t.definition.elements());
  if (!columns.features.empty())
    std::erase_if(t.features, [&](const ElementFeature& f) {
      return std::find(columns.features.begin(), columns.features.end(), f.name) == columns.features.end();
    });
  for (ElementFeature& f : t.features) read_feature(r, f, n, t.definition.samples, columns.spread);
  const Json* labels = j.find("label_images");
  if (columns.labels && labels && labels->type() == Json::Type::Array) {
    if (labels->size() > 64) throw InputError(path + ": metadata: more than 64 label images");
    for (std::size_t k = 0; k < labels->size(); ++k) t.label_images.push_back(read_labels(r, k, n));
  }
  return t;
}

}  // namespace vpm::detail
