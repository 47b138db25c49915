// fuzz_seeds OUT TESTDATA: writes the seed corpus of every fuzz target to OUT/<target>/ (OUT is
// emptied first): small valid files written by vpm's own writers, and the bad inputs of TESTDATA
// (tests/data) for the format. Run by scripts/fuzz.sh before fuzzing and by ctest before the replays.
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "cohort_fixture.hpp"
#include "fuzz_target.hpp"
#include "vpm/elements.hpp"
#include "vpm/image.hpp"
#include "vpm/config.hpp"
#include "vpm/io.hpp"
#include "vpm/landmarks.hpp"
#include "vpm/map_back.hpp"
#include "vpm/reference_sums.hpp"
#include "vpm/sampling.hpp"
#include "vpm/topology.hpp"

namespace fs = std::filesystem;
using namespace vpm;

namespace {

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

void put(const fs::path& out, const std::string& target, const std::string& name, const std::string& bytes) {
  fs::create_directories(out / target);
  std::ofstream(out / target / name, std::ios::binary) << bytes;
}

// Moves a file a writer wrote into the target's seeds.
void take(const fs::path& out, const std::string& target, const fs::path& written) {
  put(out, target, written.filename().string(), slurp(written));
  fs::remove(written);
}

// The fixture's octahedron with a label per tet and a point field, as vpm writes them.
TetMesh seed_mesh() {
  TetMesh m = fuzz::octahedron();
  FieldValues label(8, 1);
  for (int i = 0; i < 8; ++i) label(i, 0) = 1 + i % 3;
  m.set_cell_field("label", label, true);
  m.set_point_field("original_position", m.vertices * 40.0);
  return m;
}

void mesh_seeds(const fs::path& out, const fs::path& tmp) {
  const TetMesh m = seed_mesh();
  for (const char* ext : {".mesh", ".msh"}) {
    write_mesh((tmp / "octahedron").string() + ext, m);
    take(out, ext == std::string(".mesh") ? "medit" : "msh", tmp / (std::string("octahedron") + ext));
  }
  write_mesh((tmp / "octahedron_binary.vtu").string(), m, VtuEncoding::binary);
  take(out, "vtu", tmp / "octahedron_binary.vtu");
  write_mesh((tmp / "octahedron_ascii.vtu").string(), m, VtuEncoding::ascii);
  take(out, "vtu", tmp / "octahedron_ascii.vtu");
  write_mesh((tmp / "octahedron.node").string(), m);
  put(out, "tetgen", "octahedron", slurp(tmp / "octahedron.node") + std::string(fuzz::kSplit) + slurp(tmp / "octahedron.ele"));
  const TriSurface s = boundary_surface(m);
  for (const char* f : {"off", "obj", "stl", "vtp"}) {
    write_surface((tmp / "octahedron.").string() + f, s);
    take(out, f, tmp / (std::string("octahedron.") + f));
  }
  write_surface_stl_binary((tmp / "octahedron_binary.stl").string(), s);
  take(out, "stl", tmp / "octahedron_binary.stl");
  write_surface((tmp / "lh.white").string(), s);
  take(out, "freesurfer", tmp / "lh.white");
  {  // a FreeSurfer per-vertex file of 6 values (magic FF FF FF, counts, big-endian float32)
    std::string b("\xFF\xFF\xFF", 3);
    for (const std::uint32_t v : {6u, 8u, 1u, 0x3F800000u, 0xBF800000u, 0u, 0x40000000u, 0x3F000000u, 0x41200000u})
      for (int k = 24; k >= 0; k -= 8) b.push_back(static_cast<char>(v >> k));
    put(out, "curv", "lh.curv", b);
  }
  if (VPM_HAVE_GIFTI) {
    write_surface((tmp / "lh.surf.gii").string(), s);
    take(out, "gifti", tmp / "lh.surf.gii");
  }
}

// tests/data/bad and tests/data/vtk, each file to the target of its extension; a TetGen .node
// with its .ele (same stem) as one input.
void test_data_seeds(const fs::path& out, const fs::path& data) {
  const std::map<std::string, std::string> target_of = {{".mesh", "medit"}, {".vtu", "vtu"}, {".msh", "msh"},
                                                        {".off", "off"},    {".obj", "obj"}, {".stl", "stl"},
                                                        {".nii", "nifti"}};
  for (const char* folder : {"bad", "vtk"})
    for (const auto& e : fs::directory_iterator(data / folder)) {
      const fs::path p = e.path();
      if (const auto t = target_of.find(p.extension().string()); t != target_of.end()) {
        put(out, t->second, p.filename().string(), slurp(p));
      } else if (p.extension() == ".node") {
        fs::path ele = p;
        ele.replace_extension(".ele");
        const std::string rest = fs::exists(ele) ? std::string(fuzz::kSplit) + slurp(ele) : "";
        put(out, "tetgen", p.stem().string(), slurp(p) + rest);
      }
    }
}

void image_seeds(const fs::path& out, const fs::path& tmp) {
  Image img;
  img.dims = {4, 3, 2};
  img.affine.topLeftCorner<3, 3>() = Eigen::Vector3d(2, 2, 3).asDiagonal();
  img.affine.topRightCorner<3, 1>() << -4, -3, 10;
  for (size_t i = 0; i < img.size(); ++i) img.data.push_back(static_cast<float>(i % 7));
  write_nifti((tmp / "image.nii").string(), img);
  take(out, "nifti", tmp / "image.nii");
  write_nifti((tmp / "image.nii.gz").string(), img);
  take(out, "nifti", tmp / "image.nii.gz");
  // MGH (big-endian header of 284 bytes, then the voxels): one volume of each voxel type
  // (0 uchar, 1 int, 3 float, 4 short), 3 x 2 x 2 voxels, LIA direction cosines as FreeSurfer's
  for (const int type : {0, 1, 3, 4}) {
    std::string b;
    const auto be32 = [&b](std::uint32_t v) { for (int s = 24; s >= 0; s -= 8) b.push_back(static_cast<char>(v >> s)); };
    const auto bef = [&be32](float f) { std::uint32_t u; std::memcpy(&u, &f, 4); be32(u); };
    for (const int v : {1, 3, 2, 2, 1, type, 0}) be32(static_cast<std::uint32_t>(v));
    b += std::string("\0\1", 2);  // goodRASflag
    for (const float v : {1.f, 1.5f, 2.f, -1.f, 0.f, 0.f, 0.f, 0.f, -1.f, 0.f, 1.f, 0.f, 5.f, -7.f, 11.f}) bef(v);
    b.resize(284, '\0');
    const int bytes = type == 0 ? 1 : type == 4 ? 2 : 4;
    for (int i = 0; i < 12; ++i) {
      b.append(static_cast<size_t>(bytes - 1), '\0');
      b.push_back(static_cast<char>(i));
    }
    put(out, "mgh", "type" + std::to_string(type) + ".mgh", b);
  }
}

void landmark_seeds(const fs::path& out, const fs::path& tmp) {
  Points p(3, 3);
  p << 0.1, 0.2, 0.3, -0.5, 0, 0.25, 0, 0, -0.999;
  write_landmarks_csv((tmp / "points.csv").string(), p);
  take(out, "landmarks", tmp / "points.csv");
  put(out, "landmarks", "ids.csv", "vertex_id\n0\n# a comment\n7\r\n3\n");
}

// A subject table with a feature and a label image (level 0: 20 elements), its sidecar after
// the kSplit line; the sidecar and an element table's also seed the JSON target.
void table_seeds(const fs::path& out, const fs::path& tmp) {
  ElementTable t;
  t.definition = ElementDefinition{0, 1, 4, ElementLayout::shells};
  t.subject = "sub-01";
  t.mesh = "sub-01_registered.vtu";
  const int n = t.definition.elements();
  ElementFeature f;
  f.name = "pet";
  f.source = "sub-01_pet.nii.gz";
  ElementLabels l;
  l.source = "sub-01_aal.nii.gz";
  l.labels = {3, 17};
  l.fraction.assign(2, std::vector<double>(n, 0.5));
  for (int e = 0; e < n; ++e) {
    f.mean.push_back(1.0 + 0.125 * e);
    f.std.push_back(0.25);
    f.count.push_back(4 - e % 2);
  }
  t.features.push_back(f);
  t.label_images.push_back(l);
  const fs::path tsv = tmp / "sub-01.tsv";
  write_subject_table(tsv.string(), t);
  const std::string side = slurp(sidecar_path(tsv.string()));
  put(out, "subject_table", "sub-01", slurp(tsv) + std::string(fuzz::kSplit) + side);
  put(out, "json", "subject_table.json", side);
  fs::remove(tsv);
  fs::remove(sidecar_path(tsv.string()));
  const fs::path h5 = tmp / "sub-01.h5";  // the same table in HDF5
  write_subject_table(h5.string(), t);
  take(out, "table_hdf5", h5);
  ReferenceRecipe recipe;  // the sums of three normals made from it, with an age covariate
  recipe.feature = "pet";
  recipe.covariates = recipe.covariate_columns = {"age"};
  ReferenceSums sums(t.definition, recipe);
  for (int i = 0; i < 3; ++i)
    sums.add("n" + std::to_string(i) + ".h5", normal_values(nullptr, t, "n", recipe), {30.0 + 10 * i});
  const fs::path sums_path = tmp / "sums.h5";
  write_reference_sums(sums_path.string(), sums);
  take(out, "reference_sums", sums_path);
  const fs::path elements = tmp / "elements.tsv";
  write_element_table(elements.string(), CanonicalElements(ElementDefinition{1, 2, 4, ElementLayout::shells}));
  take(out, "json", sidecar_path(elements.string()));
  fs::remove(elements);
}

void view_seeds(const fs::path& out, const fs::path& tmp) {
  const std::string side = fuzz::comparison_sidecar(tmp.string());
  put(out, "view_compare", "sub-P1_pet.json", side);
  put(out, "json", "comparison.json", side);
  std::vector<NativeFocus> foci(2);
  foci[0] = {1, 120, 960.0, Eigen::Vector3d(12.5, -30, 4), 5.25, 7, 0.75};
  foci[1] = {2, 8, 64.0, Eigen::Vector3d(-40, 2, 18), -3.5, 0, 0};
  write_native_foci((tmp / "sub-P1_pet_foci.tsv").string(), foci);
  take(out, "view_foci", tmp / "sub-P1_pet_foci.tsv");
  put(out, "label_names", "aal.nii.txt", "1 Precentral_L 2001\n2 Precentral_R 2002\n# comment\n\n45 Cuneus_L 5001\r\n");
  put(out, "label_names", "FreeSurferColorLUT.txt",
      "#$Id: FreeSurferColorLUT.txt\n0   Unknown            0   0   0   0\n17  Left-Hippocampus  220 216  20   0\n"
      "1035 ctx-lh-insula     255 192  32   0\n");
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: fuzz_seeds OUT TESTDATA\n");
    return 2;
  }
  const fs::path out = argv[1], tmp = fs::path(fuzz::scratch_dir());
  try {
    fs::remove_all(out);
    mesh_seeds(out, tmp);
    test_data_seeds(out, argv[2]);
    image_seeds(out, tmp);
    landmark_seeds(out, tmp);
    table_seeds(out, tmp);
    view_seeds(out, tmp);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "fuzz_seeds: %s\n", e.what());
    return 1;
  }
  return 0;
}
