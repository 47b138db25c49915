// ChunkPack (collective/view_pack.hpp): arrays into named chunks of the page's data.
#include "collective/view_pack.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "vpm/error.hpp"

namespace vpm::detail {

Quantiser Quantiser::over(double lo, double hi) {
  Quantiser q;
  q.base = std::isfinite(lo) ? lo : 0;
  q.step = std::isfinite(hi) && hi > lo ? (hi - lo) / 65534.0 : 1.0;
  return q;
}

std::uint16_t Quantiser::code(float v) const {
  if (!std::isfinite(v)) return 65535;
  const long c = std::lround((v - base) / step);
  return static_cast<std::uint16_t>(std::clamp(c, 0L, 65534L));
}

void ChunkPack::begin(const std::string& name) {
  end();
  chunk_ = name;
}

void ChunkPack::end() {
  if (chunk_.empty()) return;
  Json c = Json::object();
  c["bytes"] = static_cast<long long>(blob_.size());
  c["hash"] = content_hash(blob_);
  chunks_[chunk_] = c;
  bytes_ += static_cast<long long>(blob_.size());
  sink_.put(chunk_, blob_, c["hash"].string());
  chunk_.clear();
  blob_.clear();
}

std::string ChunkPack::add_bytes(const std::string& name, const void* data, size_t n, size_t size, const char* type) {
  if (chunk_.empty()) throw NumericalError("view page: buffer " + name + " outside a chunk");
  while (blob_.size() % 8) blob_.push_back('\0');
  Json b = Json::object();
  b["chunk"] = chunk_;
  b["offset"] = static_cast<long long>(blob_.size());
  b["length"] = static_cast<long long>(n);
  b["type"] = type;
  buffers_[name] = b;
  const char* p = static_cast<const char*>(data);
  blob_.append(p, p + n * size);
  ++count_;
  return name;
}

std::string ChunkPack::add_q16(const std::string& name, const std::vector<float>& values, const Quantiser& q) {
  std::vector<std::uint16_t> code(values.size());
  for (size_t i = 0; i < values.size(); ++i) code[i] = q.code(values[i]);
  add(name, code, "q16");
  buffers_[name]["base"] = q.base;
  buffers_[name]["step"] = q.step;
  return name;
}

std::string content_hash(const std::string& bytes) {
  std::uint64_t h = 14695981039346656037ull;
  for (unsigned char c : bytes) h = (h ^ c) * 1099511628211ull;
  char buf[20];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h));
  return buf;
}


}  // namespace vpm::detail
