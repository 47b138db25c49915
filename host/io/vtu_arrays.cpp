#include "io/vtu_arrays.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <cerrno>
#include <cstdlib>

#include "core/parallel.hpp"
#include "io/text.hpp"
#include "vpm/error.hpp"

namespace vpm::detail {

AsciiPieces ascii_pieces(std::string_view text) {
  constexpr int kPieces = 16;
  AsciiPieces p;
  p.cut.assign(kPieces + 1, text.size());
  p.cut[0] = 0;
  for (int j = 1; j < kPieces; ++j) {
    size_t c = std::max(p.cut[j - 1], text.size() * static_cast<size_t>(j) / kPieces);
    while (c < text.size() && !is_token_space(text[c])) ++c;
    p.cut[j] = c;
  }
  p.first.assign(kPieces + 1, 0);
  static const std::array<unsigned char, 256> blank = [] {
    std::array<unsigned char, 256> t{};
    for (int c = 0; c < 256; ++c) t[static_cast<size_t>(c)] = is_token_space(static_cast<char>(c));
    return t;
  }();
  parallel_for(kPieces, 2, [&](int j0, int j1) {
    for (int j = j0; j < j1; ++j) {
      long long k = 0;
      unsigned prev = 1;  // a piece starts after whitespace (or at the start)
      for (size_t i = p.cut[j]; i < p.cut[j + 1]; ++i) {
        const unsigned b = blank[static_cast<unsigned char>(text[i])];
        k += prev & (b ^ 1u);  // a token starts where a blank is followed by a non-blank
        prev = b;
      }
      p.first[j + 1] = k;
    }
  });
  for (int j = 0; j < kPieces; ++j) p.first[j + 1] += p.first[j];
  return p;
}

namespace {
// The ASCII values of a large array parsed on the host threads, each piece of ascii_pieces into
// its place with the same conversions as the sequential reader (so the same values). False,
// with `out` unspecified, when anything is off (a bad token, a wrong count): the caller then
// reads it sequentially, which names the line of the problem.
bool parse_ascii_parallel(const std::string& path, std::string_view text, const AsciiPieces& p, long long count,
                          bool integer, const std::string& what, std::vector<double>& out) {
  if (p.total() != count) return false;
  std::atomic<bool> ok{true};
  parallel_for(p.pieces(), 2, [&](int j0, int j1) {
    try {
      for (int j = j0; j < j1; ++j) {
        Scanner s(path, text.substr(p.cut[j], p.cut[j + 1] - p.cut[j]), '\0', 1);
        std::string_view tok;
        for (long long i = p.first[j]; s.next(tok); ++i)
          out[static_cast<size_t>(i)] = integer ? static_cast<double>(s.to_int(tok, what)) : s.to_real(tok, what);
      }
    } catch (const InputError&) {
      ok = false;
    }
  });
  return ok;
}
}  // namespace

// A DataArray's binary values into `a` (rows >= 0: exactly rows tuples).
void set_binary_values(const XmlWalker& w, VtuArray& a, const std::vector<unsigned char>& bytes) {
  const std::string shown = a.name.empty() ? std::string("(unnamed)") : a.name;
  const VtkBinaryFail fail = [&](const std::string& what) { w.fail(a.line, "DataArray '" + shown + "': " + what); };
  a.values = vtk_values(bytes, a.type, fail);
  if (a.values.size() % static_cast<size_t>(a.comps) != 0 ||
      (a.rows >= 0 && a.values.size() != static_cast<size_t>(a.rows * a.comps)))
    fail("has " + std::to_string(a.values.size()) + " values, expected " +
         (a.rows >= 0 ? std::to_string(a.rows * a.comps) : "whole tuples of " + std::to_string(a.comps)) + " (wrong count)");
}

bool is_integer_type(const std::string& t) {
  return t.rfind("Int", 0) == 0 || t.rfind("UInt", 0) == 0;
}

long long attr_count(const XmlWalker& w, const Tag& tag, const std::string& key, bool required,
                     long long fallback) {
  auto it = tag.attrs.find(key);
  if (it == tag.attrs.end()) {
    if (required) w.fail(tag.line, "<" + tag.name + "> has no " + key + " attribute");
    return fallback;
  }
  const std::string& v = it->second;
  char* end = nullptr;
  errno = 0;
  const long long x = std::strtoll(v.c_str(), &end, 10);
  if (v.empty() || *end != '\0' || errno)
    w.fail(tag.line, key + "=\"" + v + "\" is not an integer (not a number)");
  if (x < 0) w.fail(tag.line, "negative count " + key + "=\"" + v + "\"");
  if (x > 2147483647LL) w.fail(tag.line, key + "=\"" + v + "\" is too large");
  return x;
}

// Position of the "</DataArray" closing `tag`; `label` names the array in the message if absent.
size_t array_close(const XmlWalker& w, const Tag& tag, const std::string& label) {
  const size_t close = w.data().find("</DataArray", tag.end);
  if (close == std::string_view::npos) w.fail(tag.line, label + " is not closed (truncated file?)");
  return close;
}

// A DataArray's values: its text up to its first child element (VTK 9 puts <InformationKey>
// elements after the values of Points) or its closing tag at `close`.
std::string_view array_text(const XmlWalker& w, const Tag& tag, size_t close) {
  const std::string_view text = w.data().substr(tag.end, close - tag.end);
  return text.substr(0, text.find('<'));
}

// Reads a DataArray: exactly `rows` tuples of its components (rows < 0: any number, binary
// forms only). ASCII and inline binary now; appended arrays get their offset, and their values
// when <AppendedData> is read.
VtuArray read_array(const std::string& path, XmlWalker& w, const Tag& tag, long long rows, const VtkBinaryLayout& layout,
                    const char* unnamed, const AsciiPieces* pieces) {
  VtuArray a;
  a.line = tag.line;
  a.name = tag.attrs.count("Name") ? tag.attrs.at("Name") : "";
  const std::string shown = a.name.empty() ? std::string(unnamed) : a.name;
  a.type = tag.attrs.count("type") ? tag.attrs.at("type") : "";
  if (a.type.empty()) w.fail(tag.line, "<DataArray Name=\"" + a.name + "\"> has no type attribute");
  a.comps = static_cast<int>(attr_count(w, tag, "NumberOfComponents", false, 1));
  if (a.comps < 1 || a.comps > 1000)
    w.fail(tag.line, "DataArray '" + shown + "': NumberOfComponents=" + std::to_string(a.comps) +
                         " is out of range");
  const std::string fmt = tag.attrs.count("format") ? tag.attrs.at("format") : "ascii";
  a.rows = rows;
  if (fmt == "appended") {
    a.appended_offset = attr_count(w, tag, "offset", true, 0);
    if (!tag.self_closing) w.set_pos(array_close(w, tag, "DataArray '" + shown + "'"));
    return a;
  }
  if (fmt == "binary") {
    const size_t close = tag.self_closing ? tag.end : array_close(w, tag, "DataArray '" + shown + "'");
    const VtkBinaryFail fail = [&](const std::string& what) { w.fail(tag.line, "DataArray '" + shown + "': " + what); };
    set_binary_values(w, a, vtk_base64_blob(tag.self_closing ? std::string_view() : array_text(w, tag, close), layout, fail));
    w.set_pos(close);
    return a;
  }
  if (fmt != "ascii")
    w.fail(tag.line, "DataArray '" + shown + "' has format=\"" + fmt + "\" (expected ascii, binary or appended)");
  if (rows < 0) rows = 0;  // the caller counts ASCII tuples itself
  if (tag.self_closing) {
    if (rows != 0) w.fail(tag.line, "DataArray '" + shown + "' is empty, expected " + std::to_string(rows) + " tuples");
    return a;
  }
  const size_t close = array_close(w, tag, "DataArray '" + shown + "'");
  const std::string_view text = array_text(w, tag, close);
  Scanner s(path, text, '\0', w.line_at(tag.end));
  const long long count = rows * a.comps;
  s.check_fits(count, 1, "values in DataArray '" + shown + "'");
  a.values.resize(static_cast<size_t>(count));
  const bool integer = is_integer_type(a.type);
  std::string_view tok;
  const std::string what = "DataArray '" + shown + "'";
  if (count >= (1 << 16) &&
      parse_ascii_parallel(path, text, pieces ? *pieces : ascii_pieces(text), count, integer, what, a.values)) {
    w.set_pos(close);
    return a;
  }
  for (long long i = 0; i < count; ++i) {
    if (!s.next(tok))
      s.fail("DataArray '" + shown + "' has " + std::to_string(i) + " values, expected " +
             std::to_string(count) + " (wrong count or truncated)");
    a.values[static_cast<size_t>(i)] = integer ? static_cast<double>(s.to_int(tok, what)) : s.to_real(tok, what);
  }
  if (s.next(tok))
    s.fail("DataArray '" + shown + "' has more than the " + std::to_string(count) +
           " values expected (wrong count)");
  w.set_pos(close);
  return a;
}

}  // namespace vpm::detail
