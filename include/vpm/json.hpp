#pragma once
// A small JSON value for reports: objects keep insertion order, numbers are doubles
// (non-finite numbers are written as null), strings are escaped.
#include <cstdint>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace vpm {

class Json {
 public:
  enum class Type { Null, Bool, Number, String, Array, Object };

  Json() = default;  ///< null
  Json(bool b) : type_(Type::Bool), bool_(b) {}
  Json(double x) : type_(Type::Number), number_(x) {}
  Json(int x) : type_(Type::Number), number_(x) {}
  Json(long x) : type_(Type::Number), number_(static_cast<double>(x)) {}
  Json(long long x) : type_(Type::Number), number_(static_cast<double>(x)) {}
  Json(unsigned long x) : type_(Type::Number), number_(static_cast<double>(x)) {}
  Json(const char* s) : type_(Type::String), string_(s) {}
  Json(std::string s) : type_(Type::String), string_(std::move(s)) {}

  static Json array() { Json j; j.type_ = Type::Array; return j; }
  static Json object() { Json j; j.type_ = Type::Object; return j; }

  Type type() const { return type_; }
  /// Object access: inserts a null member on first use (turns a null value into an object).
  Json& operator[](const std::string& key);
  /// Object lookup without insertion; nullptr if absent or not an object.
  const Json* find(const std::string& key) const;
  /// Appends to an array (turns a null value into an array).
  Json& push_back(Json value);
  size_t size() const;
  const Json& at(size_t i) const { return items_.at(i); }
  double number() const { return number_; }
  bool boolean() const { return bool_; }
  const std::string& string() const { return string_; }

  /// Serialises; indent < 0 gives one line.
  std::string dump(int indent = 2) const;
  /// Parses a JSON text; throws std::runtime_error with the offset on malformed input.
  static Json parse(const std::string& text);

 private:
  void dump_to(std::string& out, int indent, int depth) const;
  Type type_ = Type::Null;
  bool bool_ = false;
  double number_ = 0;
  std::string string_;
  std::vector<Json> items_;                           // array items or object values
  std::vector<std::string> keys_;                     // object keys, parallel to items_
};

/// Writes `json.dump()` to `path` atomically (temporary name in the same folder, then rename).
/// Throws InputError naming the path when it cannot be written.
void write_json_file(const std::string& path, const Json& json);

/// Reads and parses the JSON file at `path`. Throws InputError naming the path when it cannot be
/// read or is not JSON (with the offset of the problem).
Json read_json_file(const std::string& path);

}  // namespace vpm
