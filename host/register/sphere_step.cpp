// One Gauss-Newton step of the dense registration on the sphere (sphere_step.hpp).
#include "register/sphere_step.hpp"

#include <algorithm>
#include <cmath>

#include "core/parallel.hpp"

namespace vpm::detail {

namespace {

// The Gram matrix's blocks with lambda |c_j - c_k|^2 above this (below 1e-10 of the diagonal)
// are left out.
constexpr double kGramCutoff = 25;

}  // namespace

Centres::Centres(const Points& at, double width)
    : c(unit_rows(at)), lambda(1 / (width * width)), system_bins(at, std::sqrt(kSystemCutoff) * width),
      field_bins(at, std::sqrt(kSphereCutoff) * width) {
  for (const Vector3d& y : c) P.push_back(weight_basis(y));
}

Vector3d BinnedField::operator()(const Vector3d& x) const {
  Vector3d w = Vector3d::Zero();
  const double lambda = at->lambda;
  at->field_bins.visit(x, [&](int j) {
    const Vector3d r = x - at->c[static_cast<size_t>(j)];
    const double s = lambda * r.squaredNorm();
    if (s > kSphereCutoff) return;
    const Vector3d& uj = u[static_cast<size_t>(j)];
    w += std::exp(-s) * (2 * lambda * uj - 4 * lambda * lambda * r * r.dot(uj));
  });
  return x.cross(w);
}

// The rows of the Gauss-Newton system: one a vertex, (grad_i x x_i)^T H(x_i, c_j) P_j at each
// centre j within reach (the change of e_i per weight a_j: grad . (x × w) = (grad × x) . w), and
// two a landmark, (b_k × p)^T H(p, c_j) P_j (the field's components along p's tangent basis b_k,
// to be held at zero).
SparseRows system_rows(const std::vector<Vector3d>& x, const std::vector<Vector3d>& grad,
                       const std::vector<Vector3d>& landmarks, const Centres& cs) {
  const int n = static_cast<int>(x.size()), L = static_cast<int>(landmarks.size()), T = host_threads();
  std::vector<std::vector<Eigen::Triplet<double>>> part(static_cast<size_t>(T));
  parallel_for(T, 2, [&](int b0, int b1) {
    for (int blk = b0; blk < b1; ++blk)
      for (int i = blk; i < n + L; i += T) {
        const bool vertex = i < n;
        const Vector3d& p = vertex ? x[static_cast<size_t>(i)] : landmarks[static_cast<size_t>(i - n)];
        Eigen::Matrix<double, 3, 2> s;
        if (vertex) {
          s.col(0) = grad[static_cast<size_t>(i)].cross(p);
        } else {
          const Eigen::Matrix<double, 3, 2> B = tangent_basis(p);
          for (int k = 0; k < 2; ++k) s.col(k) = B.col(k).cross(p);
        }
        const int first = vertex ? i : n + 2 * (i - n), count = vertex ? 1 : 2;
        cs.system_bins.visit(p, [&](int j) {
          const Vector3d r = p - cs.c[static_cast<size_t>(j)];
          if (cs.lambda * r.squaredNorm() > kSystemCutoff) return;
          const Eigen::Matrix3d H = gaussian_hessian(r, cs.lambda);
          for (int k = 0; k < count; ++k) {
            const Eigen::RowVector2d v = s.col(k).transpose() * H * cs.P[static_cast<size_t>(j)];
            part[static_cast<size_t>(blk)].emplace_back(first + k, 2 * j, v(0));
            part[static_cast<size_t>(blk)].emplace_back(first + k, 2 * j + 1, v(1));
          }
        });
      }
  });
  std::vector<Eigen::Triplet<double>> all;
  for (const auto& t : part) all.insert(all.end(), t.begin(), t.end());
  SparseRows J(n + 2 * L, 2 * cs.size());
  J.setFromTriplets(all.begin(), all.end());
  return J;
}

// The centres' Gram matrix K (blocks P_j^T H_jk P_k), the field's smoothness, sparse: blocks with
// lambda |c_j - c_k|^2 above 25 (below 1e-10 of the diagonal) left out.
Eigen::SparseMatrix<double> centre_gram(const Centres& cs) {
  std::vector<Eigen::Triplet<double>> t;
  const PointBins bins(to_matrix(cs.c), std::sqrt(kGramCutoff / cs.lambda));
  for (int j = 0; j < cs.size(); ++j)
    bins.visit(cs.c[static_cast<size_t>(j)], [&](int k) {
      const Vector3d r = cs.c[static_cast<size_t>(j)] - cs.c[static_cast<size_t>(k)];
      if (cs.lambda * r.squaredNorm() > kGramCutoff) return;
      const Eigen::Matrix2d b = cs.P[static_cast<size_t>(j)].transpose() * gaussian_hessian(r, cs.lambda) * cs.P[static_cast<size_t>(k)];
      for (int p = 0; p < 2; ++p)
        for (int q = 0; q < 2; ++q) t.emplace_back(2 * j + p, 2 * k + q, b(p, q));
    });
  Eigen::SparseMatrix<double> K(2 * cs.size(), 2 * cs.size());
  K.setFromTriplets(t.begin(), t.end());
  return K;
}

// The step's weights a (gauss_newton_weights), the field's u_j = P_j a_j.
BinnedField gauss_newton_field(const SparseRows& J, const Eigen::VectorXd& area, const Eigen::VectorXd& e,
                               const Eigen::SparseMatrix<double>& K, const Centres& cs, double ridge) {
  const Eigen::VectorXd a = gauss_newton_weights(J, area, e, K, ridge, "sphere registration");
  BinnedField field{&cs, {}};
  for (int j = 0; j < cs.size(); ++j) field.u.push_back(cs.P[static_cast<size_t>(j)] * a.segment<2>(2 * j));
  return field;
}

// Points moved through `alpha` x the stationary field (two RK4 steps, put back on the sphere).
std::vector<Vector3d> advected(Device& device, const std::vector<Vector3d>& x, const BinnedField& field, double alpha) {
  if (x.empty()) return x;
  Points m = to_matrix(x);
  advect_on_sphere(device, m, {carrier(field.at->lambda, field.at->c, field.u, alpha)}, 2);
  std::vector<Vector3d> out(x.size());
  for (size_t i = 0; i < x.size(); ++i) out[i] = m.row(static_cast<Eigen::Index>(i)).transpose();
  return out;
}

double max_speed(const std::vector<Vector3d>& x, const BinnedField& field) {
  const int T = host_threads(), n = static_cast<int>(x.size());
  std::vector<double> part(static_cast<size_t>(T), 0.0);
  parallel_for(T, 2, [&](int b0, int b1) {
    for (int blk = b0; blk < b1; ++blk)
      for (int i = blk; i < n; i += T)
        part[static_cast<size_t>(blk)] = std::max(part[static_cast<size_t>(blk)], field(x[static_cast<size_t>(i)]).norm());
  });
  return *std::max_element(part.begin(), part.end());
}

}  // namespace vpm::detail
