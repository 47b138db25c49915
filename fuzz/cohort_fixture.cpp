#include "cohort_fixture.hpp"

#include <filesystem>
#include <fstream>
#include <sstream>

#include "vpm/io.hpp"
#include "vpm/statistics.hpp"

namespace vpm::fuzz {

namespace {

const char* kIds[] = {"sub-N1", "sub-N2", "sub-N3", "sub-N4", "sub-P1"};

ElementDefinition definition() { return ElementDefinition{0, 1, 2, ElementLayout::shells}; }

std::string table_name(int s) { return std::string("results/tables/") + kIds[s] + ".tsv"; }

}  // namespace

TetMesh octahedron() {
  TetMesh m;
  m.vertices.resize(7, 3);
  m.vertices << 1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0;
  m.tets.resize(8, 4);
  int t = 0;
  for (int x : {0, 1})
    for (int y : {2, 3})
      for (int z : {4, 5}) {
        const bool flip = (x == 1) != (y == 3) != (z == 5);
        m.tets.row(t++) << 6, x, flip ? z : y, flip ? y : z;
      }
  return m;
}

namespace {

ElementTable table(int s, int elements) {
  ElementTable t;
  t.definition = definition();
  t.subject = kIds[s];
  t.mesh = std::string("results/reg/") + kIds[s] + ".vtu";
  ElementFeature f;
  f.name = "pet";
  f.source = std::string("results/images/") + kIds[s] + "_pet.nii.gz";
  for (int e = 0; e < elements; ++e) {
    const bool focus = s == 4 && e < 3;  // the patient: three elements at twice the normals' level
    f.mean.push_back((focus ? 2.0 : 1.0) + 0.01 * ((e * 7 + s * 3) % 5));
    f.std.push_back(0.1);
    f.count.push_back(2);
  }
  t.features.push_back(f);
  return t;
}

}  // namespace

void write_cohort_fixture(const std::string& dir) {
  namespace fs = std::filesystem;
  fs::create_directories(dir + "/results/tables");
  fs::create_directories(dir + "/results/reg");
  fs::create_directories(dir + "/results/compare");
  const int elements = definition().elements();
  for (int s = 0; s < 5; ++s) {
    write_subject_table(dir + "/" + table_name(s), table(s, elements));
    TetMesh m = octahedron();
    m.set_point_field("original_position", m.vertices * (50.0 + s));
    write_mesh(dir + "/results/reg/" + kIds[s] + ".vtu", m);
  }
}

std::string comparison_sidecar(const std::string& dir) {
  const CanonicalElements el(definition());
  std::vector<ElementTable> normals;
  std::vector<std::string> names;
  for (int s = 0; s < 4; ++s) {
    normals.push_back(table(s, el.size()));
    names.push_back(table_name(s));
  }
  const Reference ref = build_reference(el, normals, names, "pet", Normalisation::proportional, 0);
  CompareOptions opt;
  opt.min_cluster = 1;
  const Comparison c = compare_to_reference(el, ref, table(4, el.size()), opt);
  const std::string tsv = dir + "/seed-comparison.tsv";
  write_comparison(tsv, el, ref, names, table_name(4), opt, c);
  std::ifstream in(sidecar_path(tsv));
  std::stringstream text;
  text << in.rdbuf();
  std::filesystem::remove(tsv);
  std::filesystem::remove(sidecar_path(tsv));
  return text.str();
}

}  // namespace vpm::fuzz
