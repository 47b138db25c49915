#pragma once
// Private helper of the .vtu reader/writer: a minimal XML tag walker (elements, attributes,
// comments, declarations; no DTDs, no namespaces) that keeps line numbers for messages.
#include <algorithm>
#include <cstring>
#include <map>
#include <string>
#include <string_view>

#include "vpm/error.hpp"

namespace vpm::detail {

struct Tag {
  std::string name;
  std::map<std::string, std::string> attrs;
  bool closing = false, self_closing = false;
  size_t end = 0;   // offset just past '>'
  size_t line = 1;  // line of '<'
};

inline std::string xml_unescape(std::string_view s) {
  std::string out;
  for (size_t i = 0; i < s.size(); ++i) {
    if (s[i] == '&') {
      static const std::pair<const char*, char> ents[] = {
          {"&lt;", '<'}, {"&gt;", '>'}, {"&amp;", '&'}, {"&quot;", '"'}, {"&apos;", '\''}};
      bool done = false;
      for (auto& [e, c] : ents)
        if (s.substr(i, std::strlen(e)) == e) {
          out.push_back(c);
          i += std::strlen(e) - 1;
          done = true;
          break;
        }
      if (done) continue;
    }
    out.push_back(s[i]);
  }
  return out;
}

inline std::string xml_escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '&': out += "&amp;"; break;
      case '"': out += "&quot;"; break;
      case '\n': case '\r': case '\t': out += ' '; break;
      default: out.push_back(c);
    }
  }
  return out;
}

// Walks the tags of an XML text, keeping line numbers.
class XmlWalker {
 public:
  XmlWalker(const std::string& path, std::string_view d) : path_(path), d_(d) {}
  [[noreturn]] void fail(size_t line, const std::string& what) const {
    throw InputError(path_ + ":" + std::to_string(line) + ": " + what);
  }
  size_t line_at(size_t pos) {  // incremental: pos never decreases between calls
    if (pos < counted_) counted_ = 0, line_ = 1;
    const size_t end = std::max(counted_, std::min(pos, d_.size()));
    line_ += static_cast<size_t>(std::count(d_.begin() + static_cast<std::ptrdiff_t>(counted_),
                                            d_.begin() + static_cast<std::ptrdiff_t>(end), '\n'));
    counted_ = end;
    return line_;
  }
  // Next element tag from `pos_`; false at the end of the text.
  bool next(Tag& tag) {
    while (true) {
      const size_t lt = d_.find('<', pos_);
      if (lt == std::string_view::npos) return false;
      const size_t line = line_at(lt);
      if (d_.substr(lt, 4) == "<!--") {
        const size_t e = d_.find("-->", lt + 4);
        if (e == std::string_view::npos) fail(line, "unterminated XML comment (truncated file?)");
        pos_ = e + 3;
        continue;
      }
      if (d_.substr(lt, 2) == "<?" || d_.substr(lt, 2) == "<!") {
        const size_t e = d_.find('>', lt);
        if (e == std::string_view::npos) fail(line, "unterminated XML declaration (truncated file?)");
        pos_ = e + 1;
        continue;
      }
      const size_t gt = d_.find('>', lt);
      if (gt == std::string_view::npos) fail(line, "unterminated XML tag (truncated file?)");
      parse_tag(d_.substr(lt + 1, gt - lt - 1), line, tag);
      tag.end = gt + 1;
      pos_ = gt + 1;
      return true;
    }
  }
  size_t pos() const { return pos_; }
  void set_pos(size_t p) { pos_ = p; }
  std::string_view data() const { return d_; }

 private:
  void parse_tag(std::string_view s, size_t line, Tag& tag) {
    tag = Tag{};
    tag.line = line;
    if (!s.empty() && s[0] == '/') {
      tag.closing = true;
      s.remove_prefix(1);
    }
    if (!s.empty() && s.back() == '/') {
      tag.self_closing = true;
      s.remove_suffix(1);
    }
    size_t i = 0;
    auto space = [](char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r'; };
    while (i < s.size() && !space(s[i])) ++i;
    tag.name = std::string(s.substr(0, i));
    if (tag.name.empty()) fail(line, "malformed XML tag");
    while (true) {
      while (i < s.size() && space(s[i])) ++i;
      if (i >= s.size()) break;
      const size_t k0 = i;
      while (i < s.size() && s[i] != '=' && !space(s[i])) ++i;
      std::string key(s.substr(k0, i - k0));
      while (i < s.size() && space(s[i])) ++i;
      if (i >= s.size() || s[i] != '=') fail(line, "malformed XML attribute '" + key + "' in <" + tag.name + ">");
      ++i;
      while (i < s.size() && space(s[i])) ++i;
      if (i >= s.size() || (s[i] != '"' && s[i] != '\''))
        fail(line, "XML attribute '" + key + "' in <" + tag.name + "> has no quoted value");
      const char q = s[i++];
      const size_t v0 = i;
      while (i < s.size() && s[i] != q) ++i;
      if (i >= s.size()) fail(line, "unterminated XML attribute '" + key + "' in <" + tag.name + ">");
      tag.attrs[key] = xml_unescape(s.substr(v0, i - v0));
      ++i;
    }
  }
  const std::string& path_;
  std::string_view d_;
  size_t pos_ = 0, counted_ = 0, line_ = 1;
};


}  // namespace vpm::detail
