// mesh-image: NIfTI reading, mask topology (Euler / handle repair or refusal), surface quality,
// TetGen bounds, four-boundary-vertex tets, atlas labels, surface input, bad inputs.
#include <catch2/catch.hpp>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>

#include "support/process.hpp"
#include "vpm/config.hpp"
#include "vpm/error.hpp"
#include "vpm/geometry.hpp"
#include "vpm/image.hpp"
#include "vpm/mesh_image.hpp"
#include "vpm/voxelize.hpp"
#include "vpm/topology.hpp"

using namespace vpm;
namespace fs = std::filesystem;

namespace {

const std::string kTmp = VPM_TEST_TMP;
const std::string kMricron = "/usr/share/mricron/templates/";

// n^3 image, 1 mm voxels (or the given affine), filled by fn(i,j,k).
template <class Fn>
Image make_image(int nx, int ny, int nz, Fn fn, Eigen::Matrix4d affine = Eigen::Matrix4d::Identity()) {
  Image img;
  img.dims = {nx, ny, nz};
  img.affine = affine;
  for (int d = 0; d < 3; ++d) img.spacing[d] = affine.col(d).head<3>().norm();
  img.affine_source = "sform";
  img.data.resize(img.size());
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) img.data[img.index(i, j, k)] = float(fn(i, j, k));
  return img;
}

Image ball_image(int n, double r) {
  const double c = (n - 1) / 2.0;
  return make_image(n, n, n, [&](int i, int j, int k) {
    return (i - c) * (i - c) + (j - c) * (j - c) + (k - c) * (k - c) <= r * r ? 100.0 : 0.0;
  });
}

// A raw NIfTI-1 single file (.nii) with float32 data of the given dims (any dim[0]), data
// bytes possibly cut short.
void write_raw_nifti(const std::string& path, std::vector<short> dims, size_t data_bytes_written) {
  unsigned char h[352];
  std::memset(h, 0, sizeof h);
  auto put_i32 = [&](int off, int v) { std::memcpy(h + off, &v, 4); };
  auto put_i16 = [&](int off, short v) { std::memcpy(h + off, &v, 2); };
  auto put_f32 = [&](int off, float v) { std::memcpy(h + off, &v, 4); };
  put_i32(0, 348);
  put_i16(40, short(dims.size()));
  for (size_t d = 0; d < dims.size(); ++d) put_i16(42 + 2 * int(d), dims[d]);
  for (size_t d = dims.size(); d < 7; ++d) put_i16(42 + 2 * int(d), 1);
  put_i16(70, 16);  // DT_FLOAT32
  put_i16(72, 32);
  for (int d = 0; d < 8; ++d) put_f32(76 + 4 * d, 1.f);
  put_f32(108, 352.f);
  put_f32(112, 1.f);  // scl_slope
  std::memcpy(h + 344, "n+1\0", 4);
  std::ofstream out(path, std::ios::binary);
  out.write(reinterpret_cast<const char*>(h), sizeof h);
  std::vector<char> zeros(data_bytes_written, 0);
  out.write(zeros.data(), std::streamsize(zeros.size()));
}

int euler_of_boundary(const TetMesh& m) {
  const Triangles bf = boundary_faces(m.tets);
  return surface_topology(m.num_vertices(), bf).euler;
}

template <class Fn>
std::string input_error_of(Fn fn) {
  try {
    fn();
  } catch (const InputError& e) {
    return e.what();
  }
  return "(no InputError)";
}

bool have_pipeline() { return VPM_HAVE_NIFTI && VPM_HAVE_CGAL && VPM_HAVE_TETGEN; }

}  // namespace

TEST_CASE("NIfTI round trip keeps dims, affine and values") {
  if (!VPM_HAVE_NIFTI) { WARN("built without nifti_clib: skipped"); return; }
  Eigen::Matrix4d a = Eigen::Matrix4d::Identity();
  a(0, 0) = -1.5, a(1, 1) = 2.0, a(2, 2) = 0.5, a(0, 3) = 10, a(1, 3) = -20, a(2, 3) = 5;
  const Image img = make_image(5, 4, 3, [](int i, int j, int k) { return i + 10 * j + 100 * k; }, a);
  for (const std::string ext : {".nii", ".nii.gz"}) {
    const std::string p = kTmp + "/nifti_roundtrip" + ext;
    write_nifti(p, img);
    const Image r = read_nifti(p);
    CHECK(r.dims == img.dims);
    CHECK(r.affine_source == "sform");
    CHECK((r.affine - a).cwiseAbs().maxCoeff() < 1e-5);
    CHECK(r.spacing[0] == Approx(1.5));
    CHECK(r.at(4, 3, 2) == 234.f);
    CHECK(r.to_world(Eigen::Vector3d(1, 1, 1)).isApprox(Eigen::Vector3d(8.5, -18, 5.5)));
  }
}

TEST_CASE("bad NIfTI inputs are InputErrors that say what and where") {
  if (!VPM_HAVE_NIFTI) { WARN("built without nifti_clib: skipped"); return; }
  const std::string text = std::string(VPM_TEST_DATA) + "/bad/nifti_text.nii";
  CHECK(input_error_of([&] { read_nifti(text); }).find("not a NIfTI") != std::string::npos);
  CHECK(input_error_of([&] { read_nifti(kTmp + "/nifti_missing.nii"); }).find("no such file") != std::string::npos);

  // 4-D image with 3 volumes
  const std::string four = kTmp + "/nifti_4d.nii";
  write_raw_nifti(four, {4, 4, 4, 3}, 4 * 4 * 4 * 3 * 4);
  const std::string e4 = input_error_of([&] { read_nifti(four); });
  CHECK(e4.find("4-D") != std::string::npos);
  CHECK(e4.find("nifti_4d.nii") != std::string::npos);
  // a 4-D header with a single volume is a 3-D image
  const std::string one = kTmp + "/nifti_4d_one.nii";
  write_raw_nifti(one, {4, 4, 4, 1}, 4 * 4 * 4 * 4);
  CHECK(read_nifti(one).dims == std::array<int, 3>{4, 4, 4});

  // truncated uncompressed data
  const std::string cut = kTmp + "/nifti_truncated.nii";
  write_raw_nifti(cut, {8, 8, 8}, 100);
  CHECK(input_error_of([&] { read_nifti(cut); }).find("truncated") != std::string::npos);

  // truncated gzip stream
  const Image img = ball_image(24, 8);
  const std::string gz = kTmp + "/nifti_cut.nii.gz";
  write_nifti(gz, img);
  const auto size = fs::file_size(gz);
  fs::resize_file(gz, size / 2);
  const std::string eg = input_error_of([&] { read_nifti(gz); });
  CHECK(eg.find("nifti_cut.nii.gz") != std::string::npos);
  CHECK(eg != "(no InputError)");

  // the command exits 2 and writes nothing
  const std::string out = kTmp + "/nifti_bad_out.vtu";
  fs::remove(out);
  const int rc = std::system((std::string(VPM_BINARY) + " mesh-image " + text + " -o " + out + " 2>/dev/null").c_str());
  CHECK(WEXITSTATUS(rc) == 2);
  CHECK(!fs::exists(out));
}

TEST_CASE("bad masks: empty, touching the border, atlas on another grid") {
  if (!have_pipeline()) { WARN("built without NIfTI/CGAL/TetGen: skipped"); return; }
  MeshImageOptions o;
  o.target_vertices = 300;
  const Image ball = ball_image(30, 9);
  o.threshold = 1000;
  CHECK(input_error_of([&] { mesh_image(ball, o); }).find("mask is empty") != std::string::npos);
  o.threshold = 0;
  const Image touch = make_image(20, 20, 20, [](int i, int j, int k) { return i < 10 && j > 3 && j < 15 && k > 3 && k < 15; });
  const std::string et = input_error_of([&] { mesh_image(touch, o); });
  CHECK(et.find("touches the image border") != std::string::npos);
  CHECK(et.find("voxel (0,") != std::string::npos);
  {  // with close_at_border the cut is capped and the mesh is a genus-0 solid
    MeshImageOptions oc = o;
    oc.close_at_border = true;
    MeshImageReport rep;
    const TetMesh m = mesh_image(touch, oc, &rep);
    CHECK(rep.input.border_voxels > 0);
    CHECK(euler_of_boundary(m) == 2);
  }
  const Image other = ball_image(31, 9);
  CHECK(input_error_of([&] { mesh_image(ball, o, nullptr, &other); }).find("atlas grid") != std::string::npos);
  Image shifted = ball;
  shifted.affine(0, 3) += 2;
  CHECK(input_error_of([&] { mesh_image(ball, o, nullptr, &shifted); }).find("affine") != std::string::npos);
}

TEST_CASE("a ball mask gives a genus-0 mesh with quality bounds") {
  if (!have_pipeline()) { WARN("built without NIfTI/CGAL/TetGen: skipped"); return; }
  // flipped, anisotropic affine: orientation and world coordinates must follow it
  Eigen::Matrix4d a = Eigen::Matrix4d::Identity();
  a(0, 0) = -1.0, a(1, 1) = 1.2, a(2, 2) = 0.8, a(0, 3) = 30;
  const double c = 19.5;
  const Image img = make_image(40, 40, 40, [&](int i, int j, int k) {
    const double x = i - c, y = (j - c) * 1.2, z = (k - c) * 0.8;
    return x * x + y * y + z * z <= 13.0 * 13.0 ? 1.0 : 0.0;
  }, a);
  MeshImageOptions o;
  o.target_vertices = 1500;
  MeshImageReport rep;
  const TetMesh m = mesh_image(img, o, &rep);
  CHECK(rep.topology.euler_before == 2);
  CHECK(rep.topology.closing_radius_cells == 0);
  CHECK(rep.surface.euler == 2);
  CHECK(rep.surface.min_angle_deg >= 20.0);   // remeshed, not marching cubes
  // a ball has no gap narrower than an edge: remeshed once, at the edge aimed at
  CHECK(rep.parameters.remesh_retries == 0);
  CHECK(rep.parameters.edge_mm == rep.parameters.target_edge_mm);
  CHECK(euler_of_boundary(m) == 2);
  CHECK(count_four_boundary_vertex_tets(m) == 0);
  const auto dih = dihedral_angles_deg(m.vertices, m.tets);
  CHECK(dih.minCoeff() >= 8.0);
  const Eigen::VectorXd vol = tet_volumes(m.vertices, m.tets);
  CHECK(vol.minCoeff() > 0);
  const double sphere = 4.0 / 3.0 * M_PI * 13 * 13 * 13;
  CHECK(vol.sum() == Approx(sphere).epsilon(0.08));
  CHECK(rep.mesh.surface_volume_mm3 > 0);
  // world coordinates: centre at the affine image of the voxel centre
  const Eigen::Vector3d centre = m.vertices.colwise().mean().transpose();
  CHECK((centre - img.to_world(Eigen::Vector3d(c, c, c))).norm() < 1.0);
  CHECK(m.num_vertices() > 700);
  CHECK(m.num_vertices() < 3000);
}

TEST_CASE("a mask with a handle is repaired by closing, or refused") {
  if (!have_pipeline()) { WARN("built without NIfTI/CGAL/TetGen: skipped"); return; }
  // a 24 x 24 x 10 block with a round hole of radius 2.5 voxels through it: genus 1
  const Image img = make_image(34, 34, 20, [](int i, int j, int k) {
    const bool block = i >= 5 && i < 29 && j >= 5 && j < 29 && k >= 5 && k < 15;
    const double dx = i - 16.5, dy = j - 16.5;
    return block && dx * dx + dy * dy > 2.5 * 2.5 ? 1.0 : 0.0;
  });
  MeshImageOptions o;
  o.max_volume = 2.0;
  o.smooth = 0.0;
  o.max_closing_radius = 0;
  const std::string e = input_error_of([&] { mesh_image(img, o); });
  CHECK(e.find("genus 1") != std::string::npos);
  CHECK(e.find("closing") != std::string::npos);

  o.max_closing_radius = 6;
  MeshImageReport rep;
  const TetMesh m = mesh_image(img, o, &rep);
  CHECK(rep.topology.genus_before == 1);
  CHECK(rep.topology.closing_radius_cells >= 1);
  CHECK(rep.topology.repairs.size() >= 1);
  CHECK(euler_of_boundary(m) == 2);
  CHECK(count_four_boundary_vertex_tets(m) == 0);
}

TEST_CASE("atlas labels: labelled volumes match the voxel counts") {
  if (!have_pipeline()) { WARN("built without NIfTI/CGAL/TetGen: skipped"); return; }
  const int n = 44;
  const double c = (n - 1) / 2.0;
  const Image img = ball_image(n, 18);
  // label 3: a 12^3 cube in the middle; label 5: a slab x in [25, 31); label 1 elsewhere in the ball
  Image atlas = make_image(n, n, n, [&](int i, int j, int k) {
    if (img.at(i, j, k) == 0) return 0;
    if (i >= 12 && i < 24 && j >= 16 && j < 28 && k >= 16 && k < 28) return 3;
    if (i >= 25 && i < 31 && std::abs(j - c) < 8 && std::abs(k - c) < 8) return 5;
    return 1;
  });
  MeshImageOptions o;
  o.max_volume = 1.0;
  MeshImageReport rep;
  const TetMesh m = mesh_image(img, o, &rep, &atlas);
  const Field* cf = m.find_cell_field("label");
  const Field* pf = m.find_point_field("label");
  REQUIRE(cf);
  REQUIRE(pf);
  CHECK(cf->integer);
  CHECK(pf->integer);
  CHECK(pf->values.rows() == m.num_vertices());
  const Eigen::VectorXd vol = tet_volumes(m.vertices, m.tets);
  std::map<int, double> by;
  for (int t = 0; t < m.num_tets(); ++t) by[int(cf->values(t, 0))] += vol[t];
  CHECK(by[3] == Approx(12 * 12 * 12).epsilon(0.10));
  CHECK(by[5] == Approx(rep.labels.at(5).voxels).epsilon(0.10));
  CHECK(rep.labels.at(3).volume_mm3 == Approx(by[3]));
  // vertices deep inside the cube carry its label
  int inside = 0, agree = 0;
  for (int v = 0; v < m.num_vertices(); ++v) {
    const Eigen::Vector3d p = m.vertices.row(v);
    if (p.x() > 14 && p.x() < 21 && p.y() > 18 && p.y() < 25 && p.z() > 18 && p.z() < 25) {
      ++inside;
      agree += pf->values(v, 0) == 3;
    }
  }
  CHECK(inside > 10);
  CHECK(agree == inside);
}

TEST_CASE("a closed surface file is meshed, an open one is refused") {
  if (!(VPM_HAVE_CGAL && VPM_HAVE_TETGEN)) { WARN("built without CGAL/TetGen: skipped"); return; }
  // octahedron subdivided 3 times, projected to a sphere of radius 10
  std::vector<Eigen::Vector3d> P = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  std::vector<std::array<int, 3>> T = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4},
                                       {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
  for (int s = 0; s < 3; ++s) {
    std::map<std::pair<int, int>, int> mid;
    auto M = [&](int a, int b) {
      auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      P.push_back(((P[a] + P[b]) / 2).normalized());
      return mid[key] = int(P.size()) - 1;
    };
    std::vector<std::array<int, 3>> U;
    for (auto t : T) {
      const int ab = M(t[0], t[1]), bc = M(t[1], t[2]), ca = M(t[2], t[0]);
      U.push_back({t[0], ab, ca}), U.push_back({ab, t[1], bc}), U.push_back({ca, bc, t[2]}), U.push_back({ab, bc, ca});
    }
    T = U;
  }
  const std::string path = kTmp + "/nifti_sphere.off";
  {
    std::ofstream out(path);
    out << "OFF\n" << P.size() << ' ' << T.size() << " 0\n";
    for (auto& p : P) out << 10 * p.x() << ' ' << 10 * p.y() << ' ' << 10 * p.z() << '\n';
    for (auto& t : T) out << "3 " << t[0] << ' ' << t[1] << ' ' << t[2] << '\n';
  }
  MeshImageOptions o;
  o.target_vertices = 600;
  MeshImageReport rep;
  const TetMesh m = mesh_image_file(path, o, &rep);
  CHECK(euler_of_boundary(m) == 2);
  CHECK(count_four_boundary_vertex_tets(m) == 0);
  CHECK(tet_volumes(m.vertices, m.tets).sum() == Approx(4.0 / 3.0 * M_PI * 1000).epsilon(0.05));

  TriSurface open;
  open.vertices.resize(int(P.size()), 3);
  for (size_t i = 0; i < P.size(); ++i) open.vertices.row(int(i)) = P[i].transpose();
  open.triangles.resize(int(T.size()) - 1, 3);
  for (size_t i = 0; i + 1 < T.size(); ++i)
    for (int k = 0; k < 3; ++k) open.triangles(int(i), k) = T[i][k];
  CHECK(input_error_of([&] { mesh_surface(open, o); }).find("open edges") != std::string::npos);

  // the same sphere with vertex 4 (the north pole) pulled through to below the south pole: its
  // fan crosses the southern triangles; refused before TetGen sees it, naming a crossing pair
  TriSurface crossed;
  crossed.vertices.resize(int(P.size()), 3);
  for (size_t i = 0; i < P.size(); ++i) crossed.vertices.row(int(i)) = 10 * P[i].transpose();
  crossed.vertices.row(4) << 0, 0, -14;
  crossed.triangles.resize(int(T.size()), 3);
  for (size_t i = 0; i < T.size(); ++i)
    for (int k = 0; k < 3; ++k) crossed.triangles(int(i), k) = T[i][k];
  const std::string msg = input_error_of([&] { mesh_surface(crossed, o, nullptr, "crossed.off"); });
  CHECK(msg.find("crossed.off: the surface self-intersects") != std::string::npos);
  CHECK(msg.find("pairs of triangles cross (e.g. triangles") != std::string::npos);
  CHECK(msg.find("voxelize_mm") != std::string::npos);

  // ... meshed through a voxel mask instead: the solid it encloses, genus 0, voxelize stage timed
  MeshImageOptions vo = o;
  vo.voxelize_mm = 0.5;
  MeshImageReport vrep;
  const TetMesh vm = mesh_surface(crossed, vo, &vrep, "crossed.off");
  CHECK(euler_of_boundary(vm) == 2);
  CHECK(vrep.parameters.voxelize_mm == 0.5);
  CHECK(to_json(vrep).find("parameters")->find("voxelize_mm")->number() == 0.5);
  CHECK(vrep.timings.front().stage == "voxelize");
  // and on the command line: the refusal names the remedy, which works
  const std::string crossed_path = kTmp + "/crossed.off", cout = kTmp + "/crossed.vtu", cerr = kTmp + "/crossed.txt";
  {
    std::ofstream f(crossed_path);
    f << "OFF\n" << crossed.vertices.rows() << ' ' << crossed.triangles.rows() << " 0\n";
    for (Eigen::Index i = 0; i < crossed.vertices.rows(); ++i)
      f << crossed.vertices(i, 0) << ' ' << crossed.vertices(i, 1) << ' ' << crossed.vertices(i, 2) << '\n';
    for (Eigen::Index i = 0; i < crossed.triangles.rows(); ++i)
      f << "3 " << crossed.triangles(i, 0) << ' ' << crossed.triangles(i, 1) << ' ' << crossed.triangles(i, 2) << '\n';
  }
  std::filesystem::remove(cout);
  CHECK(test::run_status(std::string(VPM_BINARY) + " mesh-image " + crossed_path + " -o " + cout +
                         " --target-vertices 600 2> " + cerr) == 2);
  CHECK(test::slurp(cerr).find("--voxelize MM meshes the solid") != std::string::npos);
  CHECK(!std::filesystem::exists(cout));
  CHECK(test::run_status(std::string(VPM_BINARY) + " mesh-image " + crossed_path + " -o " + cout +
                         " --target-vertices 600 --voxelize 0.5 2> " + cerr) == 0);
  CHECK(std::filesystem::exists(cout));
  CHECK(test::run_status(std::string(VPM_BINARY) + " mesh-image " + crossed_path + " -o " + cout +
                         " --voxelize 0 2> " + cerr) == 2);

  // TetGen runs in a child process: a crash there (forced by the test hook) is exit 2 with a
  // message, not a crash of vpm, and nothing is written
  const std::string out = kTmp + "/crashed.vtu", err = kTmp + "/crashed.txt";
  std::filesystem::remove(out);
  // (handle_segv=0: in the sanitizer build ASan's SEGV handler would turn the child's crash into exit 1)
  CHECK(test::run_status("ASAN_OPTIONS=${ASAN_OPTIONS}:handle_segv=0 VPM_TEST_TETGEN_CRASH=1 " + std::string(VPM_BINARY) + " mesh-image " + path + " -o " + out +
                         " --target-vertices 600 2> " + err) == 2);
  CHECK(test::slurp(err).find("crashed (signal 11) on this surface") != std::string::npos);
  CHECK(!std::filesystem::exists(out));
}

TEST_CASE("Colin27 at the paper's size with AAL labels") {
  if (!have_pipeline()) { WARN("built without NIfTI/CGAL/TetGen: skipped"); return; }
  if (!fs::exists(kMricron + "ch2bet.nii.gz") || !fs::exists(kMricron + "aal.nii.gz")) {
    WARN("mricron-data is not installed: Colin27 run skipped");
    return;
  }
  MeshImageReport rep;
  const TetMesh m = mesh_image_file(kMricron + "ch2bet.nii.gz", MeshImageOptions{}, &rep, kMricron + "aal.nii.gz");
  CHECK(rep.input.affine_source == "sform");
  CHECK(m.num_vertices() > 4000);
  CHECK(m.num_vertices() < 6500);
  CHECK(euler_of_boundary(m) == 2);
  CHECK(count_four_boundary_vertex_tets(m) == 0);
  CHECK(dihedral_angles_deg(m.vertices, m.tets).minCoeff() >= 8.0);
  CHECK(rep.surface.min_angle_deg >= 20.0);
  const std::map<int, double> voxels = {{71, 7682}, {72, 7941}, {77, 8700}, {78, 8399}};
  for (auto [l, n] : voxels) {
    INFO("label " << l);
    CHECK(rep.labels.at(l).voxels == n);
    CHECK(rep.labels.at(l).volume_mm3 == Approx(n).epsilon(0.10));
  }
}

TEST_CASE("mesh-image --label meshes one structure of a label image: AAL thalamus, volume near its voxel count") {
  if (!have_pipeline()) { WARN("built without NIfTI/CGAL/TetGen: skipped"); return; }
  if (!fs::exists(kMricron + "aal.nii.gz")) {
    WARN("mricron-data is not installed: AAL run skipped");
    return;
  }
  MeshImageOptions o;
  o.select_labels = {77};  // Thalamus_L, 8,700 voxels of 1 mm^3
  o.target_vertices = 1500;
  MeshImageReport rep;
  const TetMesh m = mesh_image_file(kMricron + "aal.nii.gz", o, &rep);
  CHECK(euler_of_boundary(m) == 2);
  CHECK(rep.input.mask_voxels == 8700);
  CHECK(tet_volumes(m.vertices, m.tets).sum() == Approx(8700).epsilon(0.10));
  // its centroid is where the left thalamus is (x < 0 in MNI space), not the whole brain's
  Eigen::RowVector3d c = m.vertices.colwise().mean();
  CHECK(c(0) < -5);
  // two labels (left and right thalamus) form two components: the largest is kept
  o.select_labels = {77, 78};
  MeshImageReport rep2;
  const TetMesh both = mesh_image_file(kMricron + "aal.nii.gz", o, &rep2);
  CHECK(euler_of_boundary(both) == 2);
  // a label the image does not have is a clear error
  o.select_labels = {9999};
  CHECK(input_error_of([&] { mesh_image_file(kMricron + "aal.nii.gz", o); }).find("no voxel has label 9999") !=
        std::string::npos);
  // the command: a malformed label list and --threshold with --label are usage errors (exit 2)
  const std::string out = kTmp + "/label_bad_out.vtu";
  for (const char* bad : {"--label 77,x", "--label 77 --threshold 3", "--label ''"}) {
    INFO(bad);
    const int rc = std::system((std::string(VPM_BINARY) + " mesh-image " + kMricron + "aal.nii.gz " + bad + " -o " +
                                out + " 2>/dev/null").c_str());
    CHECK(WEXITSTATUS(rc) == 2);
  }
  CHECK(!fs::exists(out));
}

TEST_CASE("voxelize_surface: the enclosed solid by winding numbers, overlaps as a union, orientation free") {
  // a closed box as 12 triangles, outward
  auto box = [](Eigen::Vector3d lo, Eigen::Vector3d hi, TriSurface& s) {
    const int base = static_cast<int>(s.vertices.rows());
    s.vertices.conservativeResize(base + 8, 3);
    for (int k = 0; k < 8; ++k)
      s.vertices.row(base + k) << (k & 1 ? hi.x() : lo.x()), (k & 2 ? hi.y() : lo.y()), (k & 4 ? hi.z() : lo.z());
    const int F[12][3] = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                          {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
    const int t0 = static_cast<int>(s.triangles.rows());
    s.triangles.conservativeResize(t0 + 12, 3);
    for (int t = 0; t < 12; ++t)
      for (int c = 0; c < 3; ++c) s.triangles(t0 + t, c) = base + F[t][c];
  };
  auto volume = [](const Image& img) {
    double n = 0;
    for (float v : img.data) n += v;
    return n * img.spacing[0] * img.spacing[1] * img.spacing[2];
  };
  TriSurface one;
  box({0.1, 0.1, 0.1}, {10.1, 10.1, 10.1}, one);
  CHECK(volume(voxelize_surface(one, 0.25)) == Approx(1000).epsilon(0.03));
  // two boxes passing through each other: the union (1500), not the symmetric difference
  TriSurface two = one;
  box({5.1, 0.1, 0.1}, {15.1, 10.1, 10.1}, two);
  const Image u = voxelize_surface(two, 0.25);
  CHECK(volume(u) == Approx(1500).epsilon(0.03));
  // the same with every triangle reversed: the same mask
  TriSurface rev = two;
  rev.triangles.col(1).swap(rev.triangles.col(2));
  CHECK(voxelize_surface(rev, 0.25).data == u.data);
  // world positions: a voxel at the box centre is inside, one beyond the box is not
  const Eigen::Vector3d c = u.to_voxel(Eigen::Vector3d(7.6, 5.1, 5.1)).array().round();
  CHECK(u.at(int(c.x()), int(c.y()), int(c.z())) == 1.0f);
  const Eigen::Vector3d o = u.to_voxel(Eigen::Vector3d(16.0, 5.1, 5.1)).array().round();
  CHECK(u.at(int(o.x()), int(o.y()), int(o.z())) == 0.0f);
  CHECK_THROWS_AS(voxelize_surface(one, 0), InputError);
  CHECK_THROWS_AS(voxelize_surface(one, 1e-3), InputError);  // 10^4 per side: too many voxels
}
