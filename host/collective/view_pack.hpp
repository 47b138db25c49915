#pragma once
// The page's arrays packed into named binary chunks (docs/view.md, format vpm-view-2): each array
// is 8-byte aligned in its chunk and named in the manifest's "buffers" with its chunk, offset,
// length and type. A chunk goes to a sink as soon as it is complete: into the page (base64 in a
// <script> element) or into a file of the data folder, so a large cohort is never held whole.
#include <cstdint>
#include <string>
#include <vector>

#include "vpm/json.hpp"

namespace vpm::detail {

/// Where finished chunks go; `hash` names the chunk's content (content_hash).
class ChunkSink {
 public:
  virtual ~ChunkSink() = default;
  virtual void put(const std::string& name, const std::string& bytes, const std::string& hash) = 0;
};

/// FNV-1a (64 bits) of `bytes` in hexadecimal: a chunk file carries it, so that the page knows a
/// file of another write (the same data gives the same page, byte for byte).
std::string content_hash(const std::string& bytes);

/// 16-bit codes of float values: value = base + step * code, code 65535 = NaN.
struct Quantiser {
  double base = 0, step = 1;
  /// Codes spanning [lo, hi] (step 1 when the range is empty).
  static Quantiser over(double lo, double hi);
  std::uint16_t code(float v) const;
};

class ChunkPack {
 public:
  explicit ChunkPack(ChunkSink& sink) : sink_(sink) {}
  /// Starts chunk `name` (finishing the one before).
  void begin(const std::string& name);
  /// Hands the current chunk to the sink.
  void end();

  template <class T>
  std::string add(const std::string& name, const std::vector<T>& values, const char* type) {
    return add_bytes(name, values.data(), values.size(), sizeof(T), type);
  }
  /// `values` as q16 codes of `q` (the page decodes them to float32).
  std::string add_q16(const std::string& name, const std::vector<float>& values, const Quantiser& q);

  Json& buffers() { return buffers_; }
  /// {name: {bytes, hash}} of every chunk finished.
  const Json& chunks() const { return chunks_; }
  long long bytes() const { return bytes_; }
  int count() const { return count_; }

 private:
  std::string add_bytes(const std::string& name, const void* data, size_t n, size_t size, const char* type);
  ChunkSink& sink_;
  std::string chunk_, blob_;
  Json buffers_ = Json::object(), chunks_ = Json::object();
  long long bytes_ = 0;
  int count_ = 0;
};


}  // namespace vpm::detail
