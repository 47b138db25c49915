#include "volume_map_solve.hpp"

#include <Eigen/Dense>
#include <Eigen/IterativeLinearSolvers>
#include <chrono>
#include <cmath>

#include "vpm/device.hpp"
#include "vpm/error.hpp"

namespace vpm::detail {

Eigen::SparseMatrix<double> weighted_stiffness(const Points& x, const Tets& tets,
                                               const Eigen::VectorXd* w) {
  std::vector<Eigen::Triplet<double>> trip;
  trip.reserve(16 * static_cast<size_t>(tets.rows()));
  for (Eigen::Index t = 0; t < tets.rows(); ++t) {
    const Eigen::Vector3d a = x.row(tets(t, 0)).transpose();
    Eigen::Matrix3d M;
    for (int c = 0; c < 3; ++c) M.col(c) = x.row(tets(t, c + 1)).transpose() - a;
    const double vol = M.determinant() / 6.0;
    const Eigen::Matrix3d Mi = M.inverse();
    Eigen::Matrix<double, 4, 3> g;
    g.row(1) = Mi.row(0);
    g.row(2) = Mi.row(1);
    g.row(3) = Mi.row(2);
    g.row(0) = -(g.row(1) + g.row(2) + g.row(3));
    const double s = -vol * (w ? (*w)(t) : 1.0);
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j) trip.emplace_back(tets(t, i), tets(t, j), s * g.row(i).dot(g.row(j)));
  }
  Eigen::SparseMatrix<double> K(x.rows(), x.rows());
  K.setFromTriplets(trip.begin(), trip.end());
  return K;
}

namespace {

using Clock = std::chrono::steady_clock;
double since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// Jacobi PCG on A x = b with A = -K symmetric positive (semi-)definite.
SolveStats pcg(const Eigen::SparseMatrix<double>& A, const Eigen::VectorXd& b, Eigen::VectorXd& x,
               double tol, int max_it, bool project_mean) {
  SolveStats st;
  const Eigen::VectorXd dinv = A.diagonal().cwiseAbs().cwiseMax(1e-300).cwiseInverse();
  const double bn = b.norm();
  if (bn == 0) {
    x.setZero();
    return st;
  }
  Eigen::VectorXd r = b - A * x;
  Eigen::VectorXd z = dinv.cwiseProduct(r);
  Eigen::VectorXd p = z, Ap(b.size());
  double rz = r.dot(z);
  int it = 0;
  double rn = r.norm();
  while (rn > tol * bn && it < max_it) {
    Ap.noalias() = A * p;
    const double alpha = rz / p.dot(Ap);
    x += alpha * p;
    r -= alpha * Ap;
    z = dinv.cwiseProduct(r);
    const double rz2 = r.dot(z);
    p = z + (rz2 / rz) * p;
    rz = rz2;
    rn = r.norm();
    ++it;
  }
  if (project_mean) x.array() -= x.mean();
  st.iterations = it;
  st.residual = (b - A * x).norm() / bn;
  if (!(st.residual <= std::max(10 * tol, 1e-6)))
    throw NumericalError("volume map: CG did not converge: relative residual " +
                         std::to_string(st.residual) + " after " + std::to_string(it) + " iterations");
  return st;
}

SolveStats normal_equations(const Eigen::SparseMatrix<double>& A, const Eigen::VectorXd& b,
                            Eigen::VectorXd& x, double tol, bool project_mean) {
  SolveStats st;
  const Eigen::SparseMatrix<double> AtA = (A.transpose() * A).pruned();
  Eigen::BiCGSTAB<Eigen::SparseMatrix<double>, Eigen::DiagonalPreconditioner<double>> s;
  s.setTolerance(tol * tol);
  s.setMaxIterations(20000);
  s.compute(AtA);
  const Eigen::VectorXd Atb = A.transpose() * b;
  x = s.solveWithGuess(Atb, x);
  if (project_mean) x.array() -= x.mean();
  st.iterations = static_cast<int>(s.iterations());
  const double bn = b.norm();
  st.residual = bn > 0 ? (b - A * x).norm() / bn : 0;
  if (!(st.residual <= std::max(1e3 * tol, 1e-4)))
    throw NumericalError("volume map: BiCGSTAB on the normal equations reached relative residual " +
                         std::to_string(st.residual) + " after " + std::to_string(st.iterations) +
                         " iterations");
  return st;
}

}  // namespace

struct MapSolver::Impl {
  Device& dev;
  int n;
  Tets tets;
  std::string method;
  double tol;
};

MapSolver::MapSolver(Device& device, int n, const Tets& tets, const std::string& method, double tol)
    : impl_(new Impl{device, n, tets, method, tol}) {
  if (method != "cg" && method != "paper")
    throw InputError("--solver: '" + method + "' is not one of cg, paper");
}
MapSolver::~MapSolver() = default;

SolveStats MapSolver::neumann(const Points& x, const Eigen::VectorXd& b_in, Eigen::VectorXd& psi) {
  const auto t0 = Clock::now();
  const Eigen::SparseMatrix<double> A = -weighted_stiffness(x, impl_->tets);
  Eigen::VectorXd b = b_in;
  b.array() -= b.mean();
  if (psi.size() != b.size()) psi = Eigen::VectorXd::Zero(b.size());
  // A = -K, so A psi = -b solves K psi = b.
  Eigen::VectorXd rhs = -b;
  SolveStats st = impl_->method == "paper" ? normal_equations(A, rhs, psi, impl_->tol, true)
                                           : pcg(A, rhs, psi, impl_->tol, 20000, true);
  st.seconds = since(t0);
  return st;
}

SolveStats MapSolver::dirichlet(const Eigen::SparseMatrix<double>& K, const std::vector<char>& fixed,
                                Points& X) {
  const auto t0 = Clock::now();
  const int n = static_cast<int>(K.rows());
  std::vector<int> idx(n, -1);
  int nf = 0;
  for (int i = 0; i < n; ++i)
    if (!fixed[i]) idx[i] = nf++;
  std::vector<Eigen::Triplet<double>> tri, trb;
  Eigen::SparseMatrix<double> Kc = K;  // column-major
  Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(nf, 3);
  for (int j = 0; j < n; ++j)
    for (Eigen::SparseMatrix<double>::InnerIterator it(Kc, j); it; ++it) {
      const int i = static_cast<int>(it.row());
      if (idx[i] < 0) continue;
      if (idx[j] >= 0)
        tri.emplace_back(idx[i], idx[j], -it.value());
      else
        rhs.row(idx[i]) += it.value() * X.row(j);  // -K_II x_I = K_IB x_B
    }
  Eigen::SparseMatrix<double> A(nf, nf);
  A.setFromTriplets(tri.begin(), tri.end());
  SolveStats st;
  for (int c = 0; c < 3; ++c) {
    Eigen::VectorXd xc(nf);
    for (int i = 0; i < n; ++i)
      if (idx[i] >= 0) xc(idx[i]) = X(i, c);
    const Eigen::VectorXd b = rhs.col(c);
    SolveStats s = impl_->method == "paper" ? normal_equations(A, b, xc, impl_->tol, false)
                                            : pcg(A, b, xc, impl_->tol, 20000, false);
    st.iterations += s.iterations;
    st.residual = std::max(st.residual, s.residual);
    for (int i = 0; i < n; ++i)
      if (idx[i] >= 0) X(i, c) = xc(idx[i]);
  }
  st.seconds = since(t0);
  return st;
}

}  // namespace vpm::detail
