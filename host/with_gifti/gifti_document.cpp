// The DataArrays of a GIfTI file, read with expat: the element tree checked against the GIfTI
// DTD as it streams, the attributes of each <DataArray> checked for form, its <Data> text kept
// for gifti_decode.cpp.
#include <expat.h>

#include <array>
#include <cstdio>
#include <memory>
#include <new>
#include <string>
#include <vector>

#include "vpm/error.hpp"
#include "with_gifti/gifti_document.hpp"

namespace vpm::detail {

long long GiftiArray::values() const {
  long long n = 1;
  for (long long d : dims) n = (d != 0 && n > (1LL << 62) / d) ? (1LL << 62) : n * d;
  return n;
}

namespace {

// Each GIfTI element and the parents it may have ("" is the document itself).
struct Rule {
  const char* name;
  std::array<const char*, 2> parents;
};
constexpr std::array<Rule, 13> kRules{{
    {"GIFTI", {""}},
    {"MetaData", {"GIFTI", "DataArray"}},
    {"MD", {"MetaData"}},
    {"Name", {"MD"}},
    {"Value", {"MD"}},
    {"LabelTable", {"GIFTI"}},
    {"Label", {"LabelTable"}},
    {"DataArray", {"GIFTI"}},
    {"CoordinateSystemTransformMatrix", {"DataArray"}},
    {"Data", {"DataArray"}},
    {"DataSpace", {"CoordinateSystemTransformMatrix"}},
    {"TransformedSpace", {"CoordinateSystemTransformMatrix"}},
    {"MatrixData", {"CoordinateSystemTransformMatrix"}},
}};

constexpr std::array<const char*, 10> kTypes{
    "NIFTI_TYPE_UINT8", "NIFTI_TYPE_INT8",  "NIFTI_TYPE_INT16",  "NIFTI_TYPE_UINT16",  "NIFTI_TYPE_INT32",
    "NIFTI_TYPE_UINT32", "NIFTI_TYPE_INT64", "NIFTI_TYPE_UINT64", "NIFTI_TYPE_FLOAT32", "NIFTI_TYPE_FLOAT64"};
constexpr std::array<const char*, 4> kEncodings{"ASCII", "Base64Binary", "GZipBase64Binary", "ExternalFileBinary"};

bool allowed(const std::string& name, const std::string& parent) {
  for (const Rule& r : kRules)
    if (name == r.name) {
      for (const char* p : r.parents)
        if (p && parent == p) return true;
      return false;
    }
  return false;
}

template <size_t N>
bool one_of(const std::string& s, const std::array<const char*, N>& names) {
  for (const char* n : names)
    if (s == n) return true;
  return false;
}

struct Reader {
  XML_Parser parser = nullptr;
  std::vector<std::string> open;  // the elements enclosing the parser's position
  std::vector<GiftiArray> arrays;
  bool has_data = false;          // the current DataArray has had its <Data>
  std::string problem;            // set, and the parser stopped, on the first fault

  size_t line() const { return XML_GetCurrentLineNumber(parser); }
  void stop(const std::string& what) {
    if (problem.empty()) problem = "line " + std::to_string(line()) + ": " + what;
    XML_StopParser(parser, XML_FALSE);
  }
};

// A Dim attribute: a whole number in [0, 2^31).
bool parse_dim(const char* s, long long& out) {
  if (!*s) return false;
  long long v = 0;
  for (; *s; ++s) {
    if (*s < '0' || *s > '9') return false;
    v = v * 10 + (*s - '0');
    if (v >= (1LL << 31)) return false;
  }
  out = v;
  return true;
}

// A <DataArray>'s attributes into `a`; the fault, or "" when they are well formed.
std::string read_attributes(const char** attr, GiftiArray& a) {
  std::string dimensionality, dim[6], order = "RowMajorOrder", endian = "LittleEndian";
  a.intent = "NIFTI_INTENT_NONE";
  for (const char** p = attr; p[0] && p[1]; p += 2) {
    const std::string key = p[0];
    if (key == "Intent") a.intent = p[1];
    else if (key == "DataType") a.data_type = p[1];
    else if (key == "ArrayIndexingOrder") order = p[1];
    else if (key == "Dimensionality") dimensionality = p[1];
    else if (key == "Encoding") a.encoding = p[1];
    else if (key == "Endian") endian = p[1];
    else if (key.size() == 4 && key.compare(0, 3, "Dim") == 0 && key[3] >= '0' && key[3] <= '5') dim[key[3] - '0'] = p[1];
  }
  if (!one_of(a.data_type, kTypes)) return "DataType=\"" + a.data_type.substr(0, 40) + "\" is not a GIfTI data type";
  if (!one_of(a.encoding, kEncodings)) return "Encoding=\"" + a.encoding.substr(0, 40) + "\" is not a GIfTI encoding";
  if (order != "RowMajorOrder" && order != "ColumnMajorOrder")
    return "ArrayIndexingOrder=\"" + order.substr(0, 40) + "\" (expected RowMajorOrder or ColumnMajorOrder)";
  if (endian != "LittleEndian" && endian != "BigEndian") return "Endian=\"" + endian.substr(0, 40) + "\" (expected LittleEndian or BigEndian)";
  if (dimensionality.size() != 1 || dimensionality[0] < '1' || dimensionality[0] > '6')
    return "Dimensionality=\"" + dimensionality.substr(0, 40) + "\" (expected 1 to 6)";
  a.dims.resize(static_cast<size_t>(dimensionality[0] - '0'));
  for (size_t k = 0; k < a.dims.size(); ++k)
    if (!parse_dim(dim[k].c_str(), a.dims[k]))
      return "Dim" + std::to_string(k) + "=\"" + dim[k].substr(0, 40) + "\" (expected a whole number below 2^31)";
  a.column_major = order == "ColumnMajorOrder";
  a.big_endian = endian == "BigEndian";
  return "";
}

void XMLCALL on_start(void* data, const char* name, const char** attr) {
  Reader& r = *static_cast<Reader*>(data);
  const std::string parent = r.open.empty() ? "" : r.open.back();
  if (!allowed(name, parent))
    return r.stop("element <" + std::string(name).substr(0, 40) + "> " +
                  (parent.empty() ? std::string("is not a GIfTI root (<GIFTI>)") : "may not appear in <" + parent + ">"));
  r.open.emplace_back(name);
  if (r.open.back() == "DataArray") {
    GiftiArray a;
    a.index = static_cast<int>(r.arrays.size());
    a.line = r.line();
    const std::string fault = read_attributes(attr, a);
    if (!fault.empty()) return r.stop("DataArray " + std::to_string(a.index) + ": " + fault);
    r.arrays.push_back(std::move(a));
    r.has_data = false;
  } else if (r.open.back() == "Data") {
    if (r.has_data) return r.stop("DataArray " + std::to_string(r.arrays.size() - 1) + " has a second <Data>");
    r.has_data = true;
  }
}

void XMLCALL on_end(void* data, const char* /*name*/) {
  Reader& r = *static_cast<Reader*>(data);
  if (!r.open.empty()) r.open.pop_back();
}

void XMLCALL on_text(void* data, const char* s, int len) {
  Reader& r = *static_cast<Reader*>(data);
  if (r.open.empty() || r.open.back() != "Data" || r.arrays.empty()) return;
  std::string& text = r.arrays.back().data;
  // 40 characters a value is more than any ASCII number or base64 needs
  if (static_cast<long long>(text.size()) + len > 40 * kGiftiMaxValues)
    return r.stop("DataArray " + std::to_string(r.arrays.size() - 1) + ": more data than vpm reads");
  text.append(s, static_cast<size_t>(len));
}

struct ParserFree {
  void operator()(XML_ParserStruct* p) const { XML_ParserFree(p); }
};
struct FileClose {
  void operator()(std::FILE* f) const { std::fclose(f); }
};

}  // namespace

std::vector<GiftiArray> read_gifti_document(const std::string& path) {
  std::unique_ptr<std::FILE, FileClose> f(std::fopen(path.c_str(), "rb"));
  if (!f) throw InputError(path + ": cannot open it");
  std::unique_ptr<XML_ParserStruct, ParserFree> parser(XML_ParserCreate(nullptr));
  if (!parser) throw std::bad_alloc();
  Reader r;
  r.parser = parser.get();
  XML_SetUserData(r.parser, &r);
  XML_SetElementHandler(r.parser, on_start, on_end);
  XML_SetCharacterDataHandler(r.parser, on_text);
  std::vector<char> buf(1 << 16);
  for (bool done = false; !done;) {
    const size_t n = std::fread(buf.data(), 1, buf.size(), f.get());
    done = n < buf.size();
    if (XML_Parse(r.parser, buf.data(), static_cast<int>(n), done) != XML_STATUS_OK) {
      if (r.problem.empty())
        r.problem = "line " + std::to_string(r.line()) + ": " + XML_ErrorString(XML_GetErrorCode(r.parser));
      throw InputError(path + ": not a GIfTI file (" + r.problem + ")");
    }
  }
  return std::move(r.arrays);
}

}  // namespace vpm::detail
