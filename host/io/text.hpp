#pragma once
// Private helpers of the file readers/writers: whole-file reading, a small tokenizer that
// tracks line numbers and reports errors as InputError("PATH:LINE: problem"), exact number
// parsing/formatting, and a buffered writer over AtomicFile.
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "vpm/mesh.hpp"

namespace vpm::detail {

/// Reads the whole file; InputError("PATH: cannot open ...") if missing, a folder or unreadable.
std::string read_whole_file(const std::string& path);

/// Lower-case extension with the dot (".vtu"), "" if none.
std::string extension_of(const std::string& path);

/// `tok` quoted for messages: at most 24 characters, non-printable bytes as '?'.
std::string show(std::string_view tok);

/// The tab-separated cells of one line of a TSV table (an empty last cell after a trailing tab
/// kept; a line ending "\r\n" read without its '\r').
std::vector<std::string> split_tabs(std::string_view line);

/// The whitespace that separates tokens (Scanner's, and the threaded .vtu array reader's).
inline bool is_token_space(char c) {
  return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\f' || c == '\v';
}

/// Tokenizer over a file's contents. Whitespace (including '\r') separates tokens, `comment`
/// (if not '\0') starts a comment running to the end of the line.
class Scanner {
 public:
  Scanner(std::string path, std::string_view data, char comment = '#', size_t first_line = 1);

  // ---- token mode (tokens may span lines) ----
  /// Next token, or false at the end of the file.
  bool next(std::string_view& tok);
  /// Next token; InputError "unexpected end of file: expected WHAT" at the end.
  std::string_view need(const std::string& what);
  long long need_int(const std::string& what);
  double need_real(const std::string& what);
  /// A count: an integer in [0, INT_MAX]. Negative -> "negative count".
  int need_count(const std::string& what);

  /// need() building the message only on failure.
  template <class F>
  std::string_view need_lazy(F&& what) {
    std::string_view tok;
    if (!next(tok)) fail("unexpected end of file (truncated?): expected " + what());
    return tok;
  }

  // ---- line mode ----
  /// Tokens of the rest of the current line, skipping lines with no tokens. False at the end.
  bool next_line(std::vector<std::string_view>& toks);
  /// Like next_line(), InputError "unexpected end of file: expected WHAT" at the end.
  void need_line(std::vector<std::string_view>& toks, const std::string& what);
  /// Same, building the message only on failure (for hot loops): `what()` returns a string.
  template <class F>
  void need_line_lazy(std::vector<std::string_view>& toks, F&& what) {
    if (!next_line(toks)) fail("unexpected end of file (truncated?): expected " + what());
  }

  // ---- conversions (errors reported at line()) ----
  long long to_int(std::string_view tok, const std::string& what) const;
  double to_real(std::string_view tok, const std::string& what) const;
  int to_count(std::string_view tok, const std::string& what) const;

  /// Line (1-based) of the last token or line returned; the last line at the end of the file.
  size_t line() const { return tok_line_; }
  void set_line(size_t line) { tok_line_ = line; }
  /// Bytes not consumed yet.
  size_t remaining() const { return data_.size() - pos_; }
  size_t position() const { return pos_; }
  /// True if only whitespace and comments remain.
  bool at_end();
  /// InputError unless `count` items of at least `min_bytes` each fit in the bytes left.
  /// Callers pass the number of tokens an item has at least (a token and its separator take
  /// two bytes, so this is a 2x safety margin: it rejects absurd counts before allocating and
  /// leaves small shortfalls to the precise "end of file" messages).
  void check_fits(long long count, long long min_bytes, const std::string& what) const;

  const std::string& path() const { return path_; }
  [[noreturn]] void fail(const std::string& what) const;
  [[noreturn]] void fail_at(size_t line, const std::string& what) const;

 private:
  void skip_space();
  size_t eof_line() const;
  std::string path_;
  std::string_view data_;
  char comment_;
  size_t pos_ = 0;
  size_t line_ = 1;      // line at pos_
  size_t tok_line_ = 1;  // line of the last token returned
};

/// Output buffer: append numbers (shortest exact decimal form), flush to a stream in chunks.
class TextOut {
 public:
  explicit TextOut(std::ostream& out) : out_(out) { buf_.reserve(1 << 20); }
  ~TextOut() { flush(); }
  TextOut& operator<<(std::string_view s) { buf_.append(s); maybe_flush(); return *this; }
  TextOut& operator<<(char c) { buf_.push_back(c); return *this; }
  TextOut& real(double x);
  TextOut& integer(long long x);
  void flush();

 private:
  void maybe_flush() { if (buf_.size() > (1 << 20)) flush(); }
  std::ostream& out_;
  std::string buf_;
};

/// The label cell field as integers if it is a one-column field with integral values, else empty.
std::vector<int> integer_labels(const TetMesh& mesh);

}  // namespace vpm::detail
