// fit_divfree_weighted (vpm/rbf.hpp): divergence-free tangent fields fitted to local
// least-squares systems, the form the dense registration's force takes (DenseFit::systems).
#include <catch2/catch.hpp>

#include <Eigen/Cholesky>
#include <random>

#include "vpm/error.hpp"
#include "vpm/rbf.hpp"

using namespace vpm;

namespace {

// Points of a regular grid of spacing h inside the ball of radius r.
Points grid_in_ball(double h, double r) {
  std::vector<Eigen::Vector3d> pts;
  const int n = static_cast<int>(r / h);
  for (int i = -n; i <= n; ++i)
    for (int j = -n; j <= n; ++j)
      for (int k = -n; k <= n; ++k) {
        const Eigen::Vector3d p(i * h, j * h, k * h);
        if (p.norm() < r) pts.push_back(p);
      }
  Points out(static_cast<Eigen::Index>(pts.size()), 3);
  for (size_t i = 0; i < pts.size(); ++i) out.row(static_cast<Eigen::Index>(i)) = pts[i].transpose();
  return out;
}

// A smooth divergence-free tangent field: three Gaussian centres of width 0.5.
DivFreeField truth() {
  DivFreeField f;
  f.kernel = RbfKernel::Tangent;
  f.lambda = 1 / (0.5 * 0.5);
  f.centres.resize(3, 3);
  f.centres << 0.3, 0, 0, -0.2, 0.3, 0.1, 0, -0.2, -0.3;
  f.coefficients.resize(3, 3);
  f.coefficients << 0, 0.01, 0.004, 0.006, 0, -0.005, -0.004, 0.006, 0;
  return f;
}

RbfFitOptions options(double width, double ridge) {
  RbfFitOptions fo;
  fo.kernel = RbfKernel::Tangent;
  fo.lambda = 1 / (width * width);
  fo.ridge = ridge;
  return fo;
}

double mean_error(const DivFreeField& f, const DivFreeField& g, const Points& at) {
  double e = 0;
  for (Eigen::Index i = 0; i < at.rows(); ++i) e += (f(at.row(i).transpose()) - g(at.row(i).transpose())).norm();
  return e / static_cast<double>(at.rows());
}

}  // namespace

TEST_CASE("weighted fit: isotropic systems alpha I, alpha v give the ridge fit to v") {
  const DivFreeField u = truth();
  for (double h : {0.3, 0.15}) {  // 123 and 1,021 centres
    const Points c = grid_in_ball(h, 0.95);
    INFO(c.rows() << " centres");
    const Points v = evaluate(u, c);
    LocalSystems sys;
    const double alpha = 2.5;
    for (Eigen::Index j = 0; j < c.rows(); ++j) sys.a.push_back(alpha * Eigen::Matrix3d::Identity());
    sys.b = alpha * v;
    const RbfFitOptions fo = options(h, 0.3);
    const DivFreeField w = fit_divfree_weighted(c, sys, fo);
    const DivFreeField r = fit_divfree(c, v, fo);
    const double scale = r.coefficients.cwiseAbs().maxCoeff();
    CHECK((w.coefficients - r.coefficients).cwiseAbs().maxCoeff() < 1e-6 * scale);
  }
}

TEST_CASE("weighted fit: data across edges only (the aperture problem) still recover the field") {
  // Each centre sees the field only along one random direction n_j (a_j = n_j n_j^T,
  // b_j = n_j (n_j . u)), as an image edge shows only the motion across it; a third of the
  // centres see nothing (flat image). Solving each centre alone gives the normal components
  // and zeros; the joint fit, divergence-free and smooth, recovers most of the rest (with
  // Gaussians as wide as the centre spacing it does not: 0.75 |u| error, 0.86 alone).
  const DivFreeField u = truth();
  const Points c = grid_in_ball(0.2, 0.95);
  const Points v = evaluate(u, c);
  std::mt19937 gen(5);
  std::normal_distribution<double> g;
  LocalSystems sys;
  sys.b = Points::Zero(c.rows(), 3);
  Points alone = Points::Zero(c.rows(), 3);  // what each centre asks for on its own
  for (Eigen::Index j = 0; j < c.rows(); ++j) {
    const Eigen::Vector3d n = Eigen::Vector3d(g(gen), g(gen), g(gen)).normalized();
    const bool flat = j % 3 == 0;
    sys.a.push_back(flat ? Eigen::Matrix3d::Zero() : Eigen::Matrix3d(n * n.transpose()));
    if (!flat) sys.b.row(j) = (n * n.dot(v.row(j).transpose())).transpose();
    alone.row(j) = ((sys.a.back() + 0.05 * Eigen::Matrix3d::Identity()).ldlt().solve(sys.b.row(j).transpose())).transpose();
  }
  const RbfFitOptions fo = options(0.4, 0.01);  // Gaussians twice the centre spacing wide
  const DivFreeField joint = fit_divfree_weighted(c, sys, fo);
  const DivFreeField separate = fit_divfree(c, alone, fo);
  const Points check = grid_in_ball(0.13, 0.8);
  double size = 0;
  for (Eigen::Index i = 0; i < check.rows(); ++i) size += u(check.row(i).transpose()).norm();
  size /= static_cast<double>(check.rows());
  const double e_joint = mean_error(joint, u, check), e_separate = mean_error(separate, u, check);
  INFO("mean |u| " << size << ", joint error " << e_joint << ", separate " << e_separate);
  CHECK(e_joint < 0.1 * size);  // measured 0.036
  CHECK(e_separate > 0.5 * size);  // 0.83
  // the field stays tangent to the sphere whatever the data
  const Points sphere = fibonacci_sphere(500);
  const Points un = evaluate(joint, sphere);
  CHECK((un.array() * sphere.array()).rowwise().sum().abs().maxCoeff() < 1e-12);
}

TEST_CASE("weighted fit: no data gives no motion, bad input is refused") {
  const Points c = grid_in_ball(0.3, 0.95);
  LocalSystems none;
  none.a.assign(static_cast<size_t>(c.rows()), Eigen::Matrix3d::Zero());
  none.b = Points::Zero(c.rows(), 3);
  CHECK(fit_divfree_weighted(c, none, options(0.3, 0.3)).coefficients.cwiseAbs().maxCoeff() == 0);
  LocalSystems short_sys = none;
  short_sys.a.pop_back();
  CHECK_THROWS_AS(fit_divfree_weighted(c, short_sys, options(0.3, 0.3)), InputError);
  CHECK_THROWS_AS(fit_divfree_weighted(c, none, options(0.3, 0)), InputError);
}
