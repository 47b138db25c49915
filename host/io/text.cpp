#include "io/text.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <climits>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <ostream>

#include "vpm/error.hpp"
#include "vpm/memory.hpp"

namespace vpm::detail {

std::string read_whole_file(const std::string& path) {
  std::error_code ec;
  auto st = std::filesystem::status(path, ec);
  if (ec || !std::filesystem::exists(st))
    throw InputError(path + ": cannot open: no such file");
  if (std::filesystem::is_directory(st)) throw InputError(path + ": cannot open: is a folder");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot open: permission denied");
  std::string data;
  in.seekg(0, std::ios::end);
  const auto size = in.tellg();
  if (size < 0) throw InputError(path + ": cannot read");
  require_memory(double(size), path, "the whole file is read before parsing");  // before allocating it
  data.resize(static_cast<size_t>(size));
  in.seekg(0, std::ios::beg);
  in.read(data.data(), static_cast<std::streamsize>(data.size()));
  if (static_cast<size_t>(in.gcount()) != data.size()) throw InputError(path + ": read error");
  return data;
}

std::vector<std::string> split_tabs(std::string_view line) {
  if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
  std::vector<std::string> out;
  size_t start = 0;
  while (true) {
    const size_t tab = line.find('\t', start);
    out.emplace_back(line.substr(start, tab == std::string_view::npos ? std::string_view::npos : tab - start));
    if (tab == std::string_view::npos) break;
    start = tab + 1;
  }
  if (line.empty()) out.clear();
  return out;
}

std::string extension_of(const std::string& path) {
  std::string ext = std::filesystem::path(path).extension().string();
  for (auto& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

std::string show(std::string_view tok) {
  std::string s = "'";
  size_t n = std::min<size_t>(tok.size(), 24);
  for (size_t i = 0; i < n; ++i) {
    unsigned char c = static_cast<unsigned char>(tok[i]);
    s.push_back(std::isprint(c) ? static_cast<char>(c) : '?');
  }
  if (tok.size() > n) s += "...";
  return s + "'";
}

Scanner::Scanner(std::string path, std::string_view data, char comment, size_t first_line)
    : path_(std::move(path)), data_(data), comment_(comment), line_(first_line),
      tok_line_(first_line) {}

void Scanner::fail(const std::string& what) const { fail_at(tok_line_, what); }

void Scanner::fail_at(size_t line, const std::string& what) const {
  throw InputError(path_ + ":" + std::to_string(line) + ": " + what);
}

void Scanner::skip_space() {
  const size_t n = data_.size();
  while (pos_ < n) {
    char c = data_[pos_];
    if (c == '\n') {
      ++line_;
      ++pos_;
    } else if (is_token_space(c)) {
      ++pos_;
    } else if (comment_ && c == comment_) {
      const void* nl = std::memchr(data_.data() + pos_, '\n', n - pos_);
      pos_ = nl ? static_cast<size_t>(static_cast<const char*>(nl) - data_.data()) : n;
    } else {
      break;
    }
  }
}

size_t Scanner::eof_line() const {
  // The last line that has characters (a final '\n' does not start a new line).
  if (!data_.empty() && data_.back() == '\n' && line_ > 1) return line_ - 1;
  return line_;
}

bool Scanner::at_end() {
  skip_space();
  if (pos_ >= data_.size()) {
    tok_line_ = eof_line();
    return true;
  }
  tok_line_ = line_;  // the line of the data that follows
  return false;
}

bool Scanner::next(std::string_view& tok) {
  skip_space();
  const size_t n = data_.size();
  if (pos_ >= n) {
    tok_line_ = eof_line();
    return false;
  }
  const size_t start = pos_;
  while (pos_ < n && !is_token_space(data_[pos_]) && !(comment_ && data_[pos_] == comment_)) ++pos_;
  tok = data_.substr(start, pos_ - start);
  tok_line_ = line_;
  return true;
}

std::string_view Scanner::need(const std::string& what) {
  std::string_view tok;
  if (!next(tok)) fail("unexpected end of file (truncated?): expected " + what);
  return tok;
}

long long Scanner::need_int(const std::string& what) { return to_int(need(what), what); }
double Scanner::need_real(const std::string& what) { return to_real(need(what), what); }
int Scanner::need_count(const std::string& what) { return to_count(need(what), what); }

bool Scanner::next_line(std::vector<std::string_view>& toks) {
  toks.clear();
  const size_t n = data_.size();
  while (pos_ < n) {
    // tokens up to the end of this line
    size_t line_start_line = line_;
    while (pos_ < n && data_[pos_] != '\n') {
      char c = data_[pos_];
      if (is_token_space(c)) {
        ++pos_;
      } else if (comment_ && c == comment_) {
        const void* nl = std::memchr(data_.data() + pos_, '\n', n - pos_);
        pos_ = nl ? static_cast<size_t>(static_cast<const char*>(nl) - data_.data()) : n;
      } else {
        const size_t start = pos_;
        while (pos_ < n && !is_token_space(data_[pos_]) && !(comment_ && data_[pos_] == comment_))
          ++pos_;
        toks.push_back(data_.substr(start, pos_ - start));
      }
    }
    if (pos_ < n) {  // consume '\n'
      ++pos_;
      ++line_;
    }
    if (!toks.empty()) {
      tok_line_ = line_start_line;
      return true;
    }
  }
  tok_line_ = eof_line();
  return false;
}

void Scanner::need_line(std::vector<std::string_view>& toks, const std::string& what) {
  if (!next_line(toks)) fail("unexpected end of file (truncated?): expected " + what);
}

long long Scanner::to_int(std::string_view tok, const std::string& what) const {
  std::string_view t = tok;
  if (!t.empty() && t[0] == '+') t.remove_prefix(1);
  long long v = 0;
  auto r = std::from_chars(t.data(), t.data() + t.size(), v);
  if (r.ec == std::errc::result_out_of_range)
    fail("integer " + show(tok) + " for " + what + " is out of range");
  if (r.ec != std::errc() || r.ptr != t.data() + t.size() || t.empty()) {
    // Accept integral reals like "3.0" written by some tools.
    double d = 0;
    auto r2 = std::from_chars(t.data(), t.data() + t.size(), d);
    if (r2.ec == std::errc() && r2.ptr == t.data() + t.size() && std::isfinite(d) &&
        d == std::floor(d) && std::fabs(d) < 9e15)
      return static_cast<long long>(d);
    fail("expected an integer for " + what + ", found " + show(tok) + " (not a number)");
  }
  return v;
}

double Scanner::to_real(std::string_view tok, const std::string& what) const {
  std::string_view t = tok;
  if (!t.empty() && t[0] == '+') t.remove_prefix(1);
  double v = 0;
  auto r = std::from_chars(t.data(), t.data() + t.size(), v);
  if (r.ec == std::errc::result_out_of_range) {
    // underflow to 0 / overflow to inf: parse leniently via strtod
    std::string s(t);
    return std::strtod(s.c_str(), nullptr);
  }
  if (r.ec != std::errc() || r.ptr != t.data() + t.size() || t.empty())
    fail("expected a number for " + what + ", found " + show(tok) + " (not a number)");
  return v;
}

int Scanner::to_count(std::string_view tok, const std::string& what) const {
  long long v = to_int(tok, what);
  if (v < 0) fail("negative count " + std::to_string(v) + " for " + what);
  if (v > INT_MAX) fail("count " + std::to_string(v) + " for " + what + " is too large");
  return static_cast<int>(v);
}

void Scanner::check_fits(long long count, long long min_bytes, const std::string& what) const {
  const long long left = static_cast<long long>(remaining());
  if (count > 0 && (count > left / std::max(1LL, min_bytes)))
    fail("declares " + std::to_string(count) + " " + what + ", more than the file's " +
         std::to_string(left) + " remaining bytes could hold (truncated or wrong count)");
}

TextOut& TextOut::real(double x) {
  char tmp[40];
  auto r = std::to_chars(tmp, tmp + sizeof tmp, x);  // shortest form that reads back exactly
  buf_.append(tmp, r.ptr);
  maybe_flush();
  return *this;
}

TextOut& TextOut::integer(long long x) {
  char tmp[24];
  auto r = std::to_chars(tmp, tmp + sizeof tmp, x);
  buf_.append(tmp, r.ptr);
  maybe_flush();
  return *this;
}

void TextOut::flush() {
  if (!buf_.empty()) out_.write(buf_.data(), static_cast<std::streamsize>(buf_.size()));
  buf_.clear();
}

std::vector<int> integer_labels(const TetMesh& mesh) {
  const Field* f = mesh.find_cell_field("label");
  if (!f || f->values.cols() != 1 || f->values.rows() != mesh.tets.rows()) return {};
  std::vector<int> out(static_cast<size_t>(f->values.rows()));
  for (Eigen::Index i = 0; i < f->values.rows(); ++i) {
    double v = f->values(i, 0);
    if (!(v == std::floor(v)) || std::fabs(v) > INT_MAX) return {};
    out[static_cast<size_t>(i)] = static_cast<int>(v);
  }
  return out;
}

}  // namespace vpm::detail
