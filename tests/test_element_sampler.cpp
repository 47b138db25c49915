// The element sampler (vpm/element_sampler.hpp) and the shared arithmetic under it: the sample
// generator of kernels/element_samples.clh makes the former Eigen points bit for bit and one at
// a time; the image reads of kernels/image_read.clh are Image::to_voxel's and sample_image's;
// the sampler on the host threads equals pull_back_samples + sample_feature /
// sample_label_fractions, and on the OpenCL device the host to round-off, in any block size.
#include <catch2/catch.hpp>
#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <random>

#include "image/image_read.hpp"
#include "support/devices.hpp"
#include "support/fixtures.hpp"
#include "vpm/element_sampler.hpp"
#include "vpm/elements.hpp"
#include "vpm/error.hpp"
#include "vpm/sampling.hpp"

using namespace vpm;

namespace {

using Vec3 = Eigen::Vector3d;

// ---- the generator as CanonicalElements wrote it in Eigen before the shared header -------------

Vec3 orthonormal(const Vec3& x, const Vec3& n) { return (x - x.dot(n) * n).normalized(); }

Vec3 arvo_sample(const Vec3& a, const Vec3& b, const Vec3& c, double u1, double u2) {
  const double alpha = std::acos(std::clamp(orthonormal(b, a).dot(orthonormal(c, a)), -1.0, 1.0));
  const double beta = std::acos(std::clamp(orthonormal(a, b).dot(orthonormal(c, b)), -1.0, 1.0));
  const double gamma = std::acos(std::clamp(orthonormal(a, c).dot(orthonormal(b, c)), -1.0, 1.0));
  const double area = alpha + beta + gamma - M_PI;
  const double sub = u1 * area;
  const double s = std::sin(sub - alpha), t = std::cos(sub - alpha);
  const double cos_c = a.dot(b);
  const double u = t - std::cos(alpha), v = s + std::sin(alpha) * cos_c;
  const double q = std::clamp(((v * t - u * s) * std::cos(alpha) - v) / ((v * s + u * t) * std::sin(alpha)), -1.0, 1.0);
  const Vec3 c_hat = q * a + std::sqrt(std::max(0.0, 1 - q * q)) * orthonormal(c, a);
  const double z = 1 - u2 * (1 - c_hat.dot(b));
  return (z * b + std::sqrt(std::max(0.0, 1 - z * z)) * orthonormal(c_hat, b)).normalized();
}

Vec3 r3(int n) {
  const double phi = 1.2207440845469035;
  const Vec3 alpha(1 / phi, 1 / (phi * phi), 1 / (phi * phi * phi));
  Vec3 x;
  for (int i = 0; i < 3; ++i) x(i) = std::fmod(0.5 + alpha(i) * n, 1.0);
  return x;
}

Vec3 reference_sample(const CanonicalElements& el, int e, int i) {
  const int k = el.shell_of(e), f = el.triangle_of(e);
  const TriSurface& s = el.sphere(el.shell_level(k));
  auto corner = [&](int j) { return Vec3(s.vertices.row(s.triangles(f, j)).transpose()); };
  const double r0 = static_cast<double>(el.id(k, 0)) / el.size();
  const double r1 = k + 1 == el.definition().shells ? 1.0 : static_cast<double>(el.id(k + 1, 0)) / el.size();
  const Vec3 u = r3(i + 1);
  return std::cbrt(r0 + u(2) * (r1 - r0)) * arvo_sample(corner(0), corner(1), corner(2), u(0), u(1));
}

// ---- a subject: a ball mesh mapped non-linearly to native space, and images there -------------

Vec3 to_native(const Vec3& x) {
  const Eigen::Matrix3d A = (Eigen::Matrix3d() << 60, 8, 0, -6, 70, 4, 2, 0, 55).finished();
  return A * x + Vec3(5, -3, 10) + 6.0 * Vec3(std::sin(2 * x.y()), std::sin(3 * x.z()), std::cos(2 * x.x()));
}

TetMesh subject() {
  TetMesh m = test::ball_mesh(9);
  FieldValues native(m.num_vertices(), 3);
  for (int i = 0; i < m.num_vertices(); ++i) native.row(i) = to_native(m.vertices.row(i).transpose()).transpose();
  m.set_point_field("original_position", native);
  return m;
}

// A 3 mm grid rotated about z and shifted: `cover` < 1 leaves part of the subject outside it.
Image image(int kind, double cover) {
  Image im;
  im.dims = {static_cast<int>(52 * cover), 56, 46};
  im.affine.setIdentity();
  im.affine.topLeftCorner<3, 3>() = Eigen::AngleAxisd(0.3, Vec3(0.2, 0.1, 1).normalized()).toRotationMatrix() * 3.0;
  im.affine.topRightCorner<3, 1>() = Vec3(-75, -85, -60);
  im.data.resize(im.size());
  for (int k = 0; k < im.dims[2]; ++k)
    for (int j = 0; j < im.dims[1]; ++j)
      for (int i = 0; i < im.dims[0]; ++i) {
        const Vec3 w = im.to_world(Vec3(i, j, k));
        im.data[im.index(i, j, k)] = kind == 2   ? static_cast<float>((w.x() > 5) + 2 * (w.z() > 12))
                                     : kind == 1 ? static_cast<float>(100 + 20 * std::sin(w.x() / 7) + 0.3 * w.y())
                                                 : static_cast<float>(0.02 * w.squaredNorm() - w.z());
      }
  im.path = "image" + std::to_string(kind) + ".nii";
  return im;
}

ElementDefinition small_definition() {
  ElementDefinition d;
  d.level = 2;
  d.layout = ElementLayout::graded;
  d.shells = graded_shells(2);
  d.samples = 12;
  return d;
}

struct Subject {
  TetMesh mesh = subject();
  Points native = mesh.find_point_field("original_position")->values;
  CanonicalElements el{small_definition()};
  Image smooth = image(1, 1.0), partial = image(0, 0.6), labels = image(2, 1.0);

  ElementTable sample(Device& d, int block = 1 << 18) const {
    ElementSamplerOptions o;
    o.place = ExecutionPlace::device;
    o.block = block;
    const ElementSampler s(el, mesh.vertices, mesh.tets, native, d, o);
    return s.sample({{"smooth", &smooth}, {"partial", &partial}}, {&labels});
  }
};

// How far apart two tables are over elements [0, end): the largest difference of a mean or a
// std, and the numbers of counts and label fractions that differ.
struct Difference {
  double value = 0;
  long counts = 0, fractions = 0;
};

Difference difference(const ElementTable& a, const ElementTable& b, int end = -1) {
  Difference d;
  REQUIRE(a.features.size() == b.features.size());
  for (size_t f = 0; f < a.features.size(); ++f) {
    const ElementFeature &x = a.features[f], &y = b.features[f];
    for (size_t e = 0; e < (end < 0 ? x.mean.size() : static_cast<size_t>(end)); ++e) {
      d.counts += x.count[e] != y.count[e];
      d.value = std::max({d.value, std::abs(x.mean[e] - y.mean[e]), std::abs(x.std[e] - y.std[e])});
    }
  }
  REQUIRE(a.label_images.size() == b.label_images.size());
  for (size_t l = 0; l < a.label_images.size(); ++l) {
    REQUIRE(a.label_images[l].labels == b.label_images[l].labels);
    for (size_t c = 0; c < a.label_images[l].labels.size(); ++c) {
      const std::vector<double>&x = a.label_images[l].fraction[c], &y = b.label_images[l].fraction[c];
      for (size_t e = 0; e < (end < 0 ? x.size() : static_cast<size_t>(end)); ++e) d.fractions += x[e] != y[e];
    }
  }
  return d;
}

// The first element of the outermost shell, whose samples reach into the gap between the
// inscribed mesh and the sphere.
int outer_shell(const CanonicalElements& el) { return el.id(el.definition().shells - 1, 0); }

}  // namespace

TEST_CASE("element samples: the shared generator makes the former Eigen points, bit for bit, one at a time") {
  ElementDefinition graded = small_definition();
  ElementDefinition shells;
  shells.level = 2;
  shells.shells = 3;
  shells.samples = 16;
  for (const ElementDefinition& d : {graded, shells}) {
    const CanonicalElements el(d);
    const Points& all = el.samples();
    REQUIRE(all.rows() == static_cast<Eigen::Index>(el.size()) * d.samples);
    long same = 0;
    for (int e = 0; e < el.size(); ++e)
      for (int s = 0; s < d.samples; ++s) {
        const Vec3 p = all.row(static_cast<Eigen::Index>(e) * d.samples + s).transpose();
        same += p == reference_sample(el, e, s) && el.sample(e, s) == p;
      }
    CHECK(same == all.rows());
    const CanonicalElements copy = el;  // copies share the samples made once
    CHECK(&copy.samples() == &all);
  }
}

TEST_CASE("image reads: the shared reader is Image::to_voxel and sample_image bit for bit") {
  const Image im = image(1, 1.0);
  const detail::IrImage r = detail::ir_image(im);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-100, 100);
  long same = 0, inside = 0;
  for (int k = 0; k < 20000; ++k) {
    const Vec3 x(u(rng), u(rng), u(rng));
    double v[3];
    detail::ir_to_voxel(&r, x.data(), v);
    same += Vec3(v[0], v[1], v[2]) == im.to_voxel(x);
    inside += inside_grid(im, x);
  }
  CHECK(same == 20000);
  CHECK(inside > 1000);
}

TEST_CASE("element sampler: the host equals pull_back_samples + sample_feature and label fractions") {
  const Subject s;
  const std::shared_ptr<Device> host = Device::host();
  const ElementTable t = s.sample(*host);
  CHECK(t.definition == s.el.definition());
  const Points pos = pull_back_samples(s.el, s.mesh.vertices, s.mesh.tets, s.native);
  ElementTable old;
  old.features = {sample_feature(s.el, pos, s.smooth, "smooth"), sample_feature(s.el, pos, s.partial, "partial")};
  old.label_images = {sample_label_fractions(s.el, pos, s.labels)};
  REQUIRE(t.features.size() == 2);
  CHECK(t.features[1].name == "partial");
  CHECK(t.features[1].source == "image0.nii");
  CHECK(t.label_images[0].labels == std::vector<int>{1, 2, 3});
  const auto& count = t.features[1].count;
  CHECK(*std::min_element(count.begin(), count.end()) == 0);  // part of the subject is outside that grid
  CHECK(*std::max_element(count.begin(), count.end()) == s.el.definition().samples);
  // bit for bit inside the inscribed mesh; in the outer shell's gap the walks may end apart
  const Difference inside = difference(t, old, outer_shell(s.el)), all = difference(t, old);
  CHECK(inside.value == 0);
  CHECK(inside.counts + inside.fractions == 0);
  CHECK(all.value < 1e-6);
  CHECK(all.counts + all.fractions == 0);
  // blocks of any size give the same table, bit for bit
  const Difference blocks = difference(s.sample(*host, 37), t);
  CHECK(blocks.value == 0);
  CHECK(blocks.counts + blocks.fractions == 0);
  CHECK_THROWS_AS(ElementSampler(s.el, s.mesh.vertices, s.mesh.tets, s.native.topRows(5), *host), InputError);
  const ElementSampler sampler(s.el, s.mesh.vertices, s.mesh.tets, s.native, *host);
  CHECK_THROWS_AS(sampler.sample({}), InputError);
  CHECK_FALSE(sampler.placement().sampling->on_device);
}

TEST_CASE("element sampler: the OpenCL device equals the host to round-off") {
  const std::shared_ptr<Device> dev = test::opencl_device();
  if (!dev) {
    WARN("no OpenCL device: skipped");
    return;
  }
  const Subject s;
  const ElementTable host = s.sample(*Device::host());
  const ElementTable device = s.sample(*dev);
  for (const ElementTable& d : {device, s.sample(*dev, 100)}) {  // one launch, several
    // inside the inscribed mesh: to round-off
    const Difference inside = difference(d, host, outer_shell(s.el));
    CHECK(inside.value < 1e-9);
    CHECK(inside.counts + inside.fractions == 0);
    // in the gap a sample between two boundary tets whose clamps tie (this structured mesh has
    // exact ties) goes to the one round-off favours: a few samples, each a few mm apart
    const Difference all = difference(d, host);
    CHECK(all.value < 0.2);
    CHECK(all.counts + all.fractions <= 4);
  }
  // automatic: the kernels on GPUs, the host threads on CPU devices (faster there)
  const bool gpu = dev->description().kind == DeviceKind::gpu;
  CHECK(ElementSampler(s.el, s.mesh.vertices, s.mesh.tets, s.native, *dev).placement().sampling->on_device == gpu);
  ElementSamplerOptions o;
  o.place = ExecutionPlace::device;
  const ElementSampler sampler(s.el, s.mesh.vertices, s.mesh.tets, s.native, *dev, o);
  const ElementTable labels_only = sampler.sample({}, {&s.labels});
  CHECK(labels_only.features.empty());
  CHECK(labels_only.label_images[0].fraction == device.label_images[0].fraction);
}
