// Label tables: AAL's text file or a FreeSurfer colour table (vpm/label_names.hpp).
#include "vpm/label_names.hpp"

#include <fstream>
#include <sstream>
#include <vector>

#include "vpm/error.hpp"

namespace vpm {
namespace {

bool parse_int(const std::string& word, int& out) {
  try {
    size_t used = 0;
    out = std::stoi(word, &used);
    return used == word.size();
  } catch (const std::exception&) {
    return false;
  }
}

}  // namespace

LabelTable read_label_table(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path + ": cannot be read (label names)");
  LabelTable t;
  std::string line;
  int first_kind = -1;  // 0: AAL ("id name [code]"), 1: colour table ("id name R G B A")
  for (int n = 1; std::getline(in, line); ++n) {
    const size_t start = line.find_first_not_of(" \t\r");
    if (start == std::string::npos || line[start] == '#') continue;
    std::stringstream ss(line);
    std::vector<std::string> w;
    for (std::string word; ss >> word;) w.push_back(word);
    if (w.empty()) continue;  // only white space (a vertical tab, a form feed)
    const std::string where = path + ":" + std::to_string(n) + ": ";
    int id = 0;
    if (!parse_int(w[0], id)) throw InputError(where + "label id '" + w[0] + "' is not an integer");
    if (w.size() < 2) throw InputError(where + "label " + w[0] + " has no name");
    int code = 0;
    if (w.size() > 3 && w.size() != 6)
      throw InputError(where + "expected 'id name' (AAL) or 'id name R G B A' (FreeSurfer colour table), got " +
                       std::to_string(w.size()) + " fields");
    if (w.size() == 3 && !parse_int(w[2], code)) throw InputError(where + "third field '" + w[2] + "' is not an integer code");
    const int kind = w.size() == 6 ? 1 : 0;
    if (first_kind >= 0 && kind != first_kind)
      throw InputError(where + (kind ? "a colour (R G B A) in a table whose earlier lines have none"
                                     : "no colour (R G B A) in a colour table whose earlier lines have one"));
    first_kind = kind;
    if (kind == 1) {
      std::array<int, 4> rgba{};
      for (int c = 0; c < 4; ++c)
        if (!parse_int(w[2 + c], rgba[c]) || rgba[c] < 0 || rgba[c] > 255)
          throw InputError(where + "colour value '" + w[2 + c] + "' of label " + w[0] + " is not an integer 0-255");
      t.colours[id] = rgba;
    }
    if (!t.names.emplace(id, w[1]).second) throw InputError(where + "label " + w[0] + " listed twice");
  }
  if (t.names.empty()) throw InputError(path + ": no label names (expected lines 'id name' or 'id name R G B A')");
  t.format = first_kind == 1 ? "freesurfer" : "aal";
  return t;
}

std::map<int, std::string> read_label_names(const std::string& path) { return read_label_table(path).names; }

}  // namespace vpm
