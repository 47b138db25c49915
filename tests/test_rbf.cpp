#include <catch2/catch.hpp>

#include <Eigen/IterativeLinearSolvers>
#include <Eigen/Cholesky>
#include <random>

#include "support/devices.hpp"
#include "vpm/device.hpp"
#include "vpm/error.hpp"
#include "vpm/rbf.hpp"

using namespace vpm;

namespace {

// n random points in the ball of radius `radius` (fixed seed).
Points random_ball(int n, double radius, unsigned seed) {
  std::mt19937 gen(seed);
  std::uniform_real_distribution<double> u(-1, 1);
  Points p(n, 3);
  for (int i = 0; i < n; ++i) {
    Eigen::Vector3d x;
    do x << u(gen), u(gen), u(gen);
    while (x.norm() > 1);
    p.row(i) = radius * x.transpose();
  }
  return p;
}

Points random_vectors(int n, double scale, unsigned seed) {
  std::mt19937 gen(seed);
  std::normal_distribution<double> g(0, scale);
  Points v(n, 3);
  for (int i = 0; i < n; ++i) v.row(i) << g(gen), g(gen), g(gen);
  return v;
}

// Divergence and Jacobian norm of `f` at x by central differences.
std::pair<double, double> divergence(const DivFreeField& f, const Eigen::Vector3d& x, double h) {
  double div = 0, jac = 0;
  for (int k = 0; k < 3; ++k) {
    const Eigen::Vector3d e = h * Eigen::Vector3d::Unit(k);
    const Eigen::Vector3d d = (f(x + e) - f(x - e)) / (2 * h);
    div += d(k);
    jac = std::max(jac, d.cwiseAbs().maxCoeff());
  }
  return {div, jac};
}

}  // namespace

TEST_CASE("free kernel: Phi(0) = 4 lambda I, symmetric, matches the closed form") {
  const double l = 3.0;
  CHECK((divfree_kernel(Eigen::Vector3d::Zero(), l) - 4 * l * Eigen::Matrix3d::Identity()).norm() < 1e-14);
  const Eigen::Vector3d r(0.3, -0.2, 0.5);
  const Eigen::Matrix3d k = divfree_kernel(r, l);
  CHECK((k - k.transpose()).norm() < 1e-14);
  // (grad grad^T - Lap I) psi by finite differences of psi = exp(-l |r|^2)
  auto psi = [l](const Eigen::Vector3d& x) { return std::exp(-l * x.squaredNorm()); };
  const double h = 1e-4;
  Eigen::Matrix3d hess;
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) {
      const Eigen::Vector3d ea = h * Eigen::Vector3d::Unit(a), eb = h * Eigen::Vector3d::Unit(b);
      hess(a, b) = (psi(r + ea + eb) - psi(r + ea - eb) - psi(r - ea + eb) + psi(r - ea - eb)) / (4 * h * h);
    }
  const Eigen::Matrix3d fd = hess - hess.trace() * Eigen::Matrix3d::Identity();
  CHECK((fd - k).norm() < 1e-6 * k.norm());
}

TEST_CASE("tangent kernel: K(x,y) = K(y,x)^T, reduces to tangent vectors on the sphere") {
  const double l = 5.0;
  const Eigen::Vector3d x(0.2, 0.4, -0.3), y(-0.1, 0.5, 0.2);
  CHECK((tangent_kernel(x, y, l) - tangent_kernel(y, x, l).transpose()).norm() < 1e-13);
  const Eigen::Vector3d s = Eigen::Vector3d(1, 2, -2).normalized();
  const Eigen::Matrix3d ks = tangent_kernel(s, y, l);
  CHECK((s.transpose() * ks).norm() < 1e-14 * ks.norm());  // every column tangent at s
}

TEST_CASE("fitted fields interpolate the samples and are divergence-free") {
  const Points p = random_ball(30, 0.9, 1);
  const Points v = random_vectors(30, 0.1, 2);
  const Points probe = random_ball(20, 0.95, 3);
  for (RbfKernel kind : {RbfKernel::Free, RbfKernel::Tangent}) {
    INFO("kernel " << (kind == RbfKernel::Free ? "free" : "tangent"));
    RbfFitOptions opt;
    opt.kernel = kind;
    opt.lambda = 4;
    RbfFitInfo info;
    const DivFreeField f = fit_divfree(p, v, opt, &info);
    CHECK(info.samples == 30);
    CHECK(info.max_residual < 1e-9);
    const Points u = evaluate(f, p);
    CHECK((u - v).cwiseAbs().maxCoeff() < 1e-9);
    double worst = 0, scale = 0;
    for (int i = 0; i < probe.rows(); ++i) {
      const auto [div, jac] = divergence(f, probe.row(i).transpose(), 1e-4);
      worst = std::max(worst, std::fabs(div));
      scale = std::max(scale, jac);
    }
    INFO("max |div| " << worst << ", max |du/dx| " << scale);
    CHECK(scale > 1e-3);
    CHECK(worst < 1e-6 * scale);
  }
}

TEST_CASE("tangent kernel field has zero normal velocity on the sphere, boundary samples make it small") {
  const Points p = random_ball(12, 0.8, 4);
  const Points v = random_vectors(12, 0.2, 5);
  const Points sphere = fibonacci_sphere(2000);
  auto max_normal = [&](const DivFreeField& f) {
    const Points u = evaluate(f, sphere);
    return (u.array() * sphere.array()).rowwise().sum().abs().maxCoeff();
  };
  RbfFitOptions opt;
  opt.lambda = 6;
  opt.kernel = RbfKernel::Tangent;
  const DivFreeField tangent = fit_divfree(p, v, opt);
  opt.kernel = RbfKernel::Free;
  const DivFreeField none = fit_divfree(p, v, opt);
  opt.boundary_samples = fibonacci_sphere(200);
  RbfFitInfo info;
  const DivFreeField samples = fit_divfree(p, v, opt, &info);
  CHECK(info.boundary_constraints == 200);
  CHECK(info.max_residual < 1e-9);  // velocity samples still interpolated exactly
  // normal component cancelled at the boundary samples themselves
  const Points us = evaluate(samples, opt.boundary_samples);
  CHECK((us.array() * opt.boundary_samples.array()).rowwise().sum().abs().maxCoeff() < 1e-8);
  const double mt = max_normal(tangent), mn = max_normal(none), ms = max_normal(samples);
  INFO("max |u.n|: tangent " << mt << ", samples " << ms << ", none " << mn);
  CHECK(mt < 1e-13);
  CHECK(mn > 1e-3);
  CHECK(ms < 0.2 * mn);
}

TEST_CASE("host and device evaluate the same field") {
  const Points p = random_ball(40, 0.9, 6);
  const Points v = random_vectors(40, 0.1, 7);
  const Points x = random_ball(1000, 1.0, 8);
  for (RbfKernel kind : {RbfKernel::Free, RbfKernel::Tangent}) {
    RbfFitOptions opt;
    opt.kernel = kind;
    opt.lambda = 10;
    const DivFreeField f = fit_divfree(p, v, opt);
    const Points host = evaluate(f, x);
    for (auto& dev : test::devices()) {
      INFO("device " << dev->name());
      const Points d = evaluate(*dev, f, x);
      CHECK((d - host).cwiseAbs().maxCoeff() <= 1e-12 * host.cwiseAbs().maxCoeff());
    }
  }
}

TEST_CASE("leave-one-out errors match refitting without the sample") {
  const Points p = random_ball(10, 0.9, 9);
  const Points v = random_vectors(10, 0.1, 10);
  for (RbfKernel kind : {RbfKernel::Free, RbfKernel::Tangent}) {
    const double l = 3;
    const Eigen::VectorXd e = loo_errors(p, v, kind, l);
    for (int j = 0; j < 10; j += 3) {
      Points pj(9, 3), vj(9, 3);
      for (int i = 0, k = 0; i < 10; ++i)
        if (i != j) {
          pj.row(k) = p.row(i);
          vj.row(k++) = v.row(i);
        }
      RbfFitOptions opt;
      opt.kernel = kind;
      opt.lambda = l;
      const DivFreeField f = fit_divfree(pj, vj, opt);
      const double direct = (f(p.row(j).transpose()) - v.row(j).transpose()).norm();
      CHECK(e(j) == Approx(direct).epsilon(1e-6));
    }
  }
}

TEST_CASE("near-duplicate samples are merged, wider Gaussians are worse conditioned") {
  Points p = random_ball(5, 0.5, 11);
  Points v = random_vectors(5, 0.1, 12);
  Points p2(6, 3), v2(6, 3);
  p2 << p, p.row(2) + Eigen::RowVector3d(1e-12, 0, 0);
  v2 << v, v.row(2);
  RbfFitOptions opt;
  opt.lambda = 2;
  RbfFitInfo info;
  fit_divfree(p2, v2, opt, &info);
  CHECK(info.samples == 5);
  CHECK(info.merged == 1);
  CHECK(info.max_residual < 1e-9);

  // docs/design.md 4.3: 200 random points, lambda 1 vs 64
  const Points q = random_ball(200, 1.0, 13);
  const Points w = random_vectors(200, 0.1, 14);
  opt.estimate_condition = true;
  opt.lambda = 64;
  RbfFitInfo sharp, wide;
  fit_divfree(q, w, opt, &sharp);
  opt.lambda = 1;
  fit_divfree(q, w, opt, &wide);
  INFO("cond lambda=64: " << sharp.condition << ", lambda=1: " << wide.condition);
  CHECK(sharp.condition < 1e5);
  CHECK(wide.condition > 1e3 * sharp.condition);
}

TEST_CASE("fit refuses mismatched samples and a non-positive lambda") {
  RbfFitOptions opt;
  CHECK_THROWS_AS(fit_divfree(Points::Zero(3, 3), Points::Zero(2, 3), opt), InputError);
  opt.lambda = 0;
  CHECK_THROWS_AS(fit_divfree(Points::Zero(1, 3), Points::Zero(1, 3), opt), InputError);
}

// The tangent kernel's Gram matrix of `p` with the fit's ridge on its diagonal, and velocities
// stacked into one vector: the system a ridge fit solves.
Eigen::MatrixXd ridge_gram(const Points& p, const RbfFitOptions& fo) {
  const Eigen::Index n = p.rows();
  Eigen::MatrixXd a(3 * n, 3 * n);
  for (Eigen::Index i = 0; i < n; ++i)
    for (Eigen::Index j = 0; j < n; ++j)
      a.block<3, 3>(3 * i, 3 * j) = tangent_kernel(p.row(i).transpose(), p.row(j).transpose(), fo.lambda);
  a.diagonal().array() += fo.ridge * a.diagonal().mean();
  return a;
}

Eigen::VectorXd stacked(const Points& v) {
  Eigen::VectorXd rhs(3 * v.rows());
  for (Eigen::Index i = 0; i < v.rows(); ++i) rhs.segment<3>(3 * i) = v.row(i).transpose();
  return rhs;
}

TEST_CASE("smoothing ridge with thousands of samples: the sparse Gram matrix gives the dense solution") {
  const int n = 1700;  // 5,100 unknowns: the sparse path, whose dense Gram would take 208 MB
  const Points p = random_ball(n, 0.95, 21);
  const Points v = random_vectors(n, 0.1, 22);
  RbfFitOptions fo;
  fo.kernel = RbfKernel::Tangent;
  fo.lambda = 1 / (0.1 * 0.1);
  fo.ridge = 0.3;
  const DivFreeField f = fit_divfree(p, v, fo);
  REQUIRE(f.centres.rows() == n);
  // the full Gram matrix, solved by CG to 1e-12
  const Eigen::MatrixXd a = ridge_gram(p, fo);
  const Eigen::VectorXd rhs = stacked(v);
  Eigen::ConjugateGradient<Eigen::MatrixXd, Eigen::Lower | Eigen::Upper> cg(a);
  cg.setTolerance(1e-12);
  const Eigen::VectorXd c = cg.solve(rhs);
  double worst = 0;
  for (int i = 0; i < n; ++i) worst = std::max(worst, (f.coefficients.row(i).transpose() - c.segment<3>(3 * i)).norm());
  CHECK(worst < 1e-5 * c.cwiseAbs().maxCoeff());
}

TEST_CASE("smoothing ridge: the fit solves (A + ridge mean(diag A) I) c = v, by Cholesky or by CG") {
  // 60 samples take the Cholesky path, 450 (1350 unknowns) the conjugate-gradient path (sparse Gram)
  for (int n : {60, 450}) {
    INFO(n << " samples");
    const Points p = random_ball(n, 0.95, 11);
    const Points v = random_vectors(n, 0.1, 12);
    RbfFitOptions fo;
    fo.kernel = RbfKernel::Tangent;
    fo.lambda = 1 / (0.3 * 0.3);
    fo.ridge = 0.3;
    RbfFitInfo info;
    const DivFreeField f = fit_divfree(p, v, fo, &info);
    const Eigen::VectorXd c = ridge_gram(p, fo).llt().solve(stacked(v));
    double worst = 0;
    for (int i = 0; i < n; ++i) worst = std::max(worst, (f.coefficients.row(i).transpose() - c.segment<3>(3 * i)).norm());
    CHECK(worst < 1e-8 * c.cwiseAbs().maxCoeff());
    CHECK(info.max_residual > 1e-3);  // smoothing: the samples are approximated, not interpolated
    CHECK(!info.regularised);
  }
}
