#include "map/volume_map_solve.hpp"

#include <Eigen/Dense>
#include <Eigen/IterativeLinearSolvers>
#include <chrono>
#include <cmath>

#include "vpm/device.hpp"
#include "vpm/error.hpp"
#include "vpm/solver.hpp"
#include "vpm/sparse.hpp"
#include "vpm/timing.hpp"

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


}  // namespace

struct MapSolver::Impl {
  Device& dev;
  int n;
  Tets tets;
  SolverOptions options;
  std::shared_ptr<PoissonSolver> poisson;
};

MapSolver::MapSolver(Device& device, int n, const Tets& tets, SolverMethod method, double tol,
                     PreconditionerChoice preconditioner, std::shared_ptr<PoissonSolver> reuse)
    : impl_(new Impl{device, n, tets, SolverOptions{}, nullptr}) {
  if (method == SolverMethod::bicgstab) throw InputError("volume map: the solver is cg or paper, not bicgstab");
  impl_->options.method = method;
  impl_->options.relative_tolerance = tol;
  impl_->options.preconditioner = choose_preconditioner(preconditioner, device, tets.rows());
  impl_->options.neumann_tolerance = 1e-8;
  if (reuse && &reuse->device() == &device && reuse->laplacian().num_vertices() == n &&
      reuse->laplacian().num_tets() == tets.rows() && reuse->laplacian().tets() == tets) {
    impl_->poisson = std::move(reuse);
    impl_->poisson->release_work_memory();
    impl_->poisson->options() = impl_->options;
  }
}
MapSolver::~MapSolver() = default;

Preconditioner MapSolver::preconditioner() const { return impl_->options.preconditioner; }

SolveStats MapSolver::neumann(const Points& x, const Eigen::VectorXd& b_in, Eigen::VectorXd& psi) {
  const auto t0 = Clock::now();
  if (!impl_->poisson)
    impl_->poisson = std::make_unique<PoissonSolver>(impl_->dev, impl_->n, impl_->tets, impl_->options);
  impl_->poisson->set_positions(x);
  Eigen::VectorXd b = b_in;
  b.array() -= b.mean();  // exact compatibility (the targets are rescaled to the total volume)
  if (psi.size() != b.size()) psi = Eigen::VectorXd::Zero(b.size());
  const SolverStats s = impl_->poisson->solve_neumann(b, psi);
  SolveStats st;
  st.iterations = s.iterations;
  st.residual = s.relative_residual;
  st.seconds = seconds_since(t0);
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
  std::vector<Eigen::Triplet<double>> tri;
  Eigen::MatrixXd rhs = Eigen::MatrixXd::Zero(nf, 3);
  for (int j = 0; j < n; ++j)
    for (Eigen::SparseMatrix<double>::InnerIterator it(K, j); it; ++it) {
      const int i = static_cast<int>(it.row());
      if (idx[i] < 0) continue;
      if (idx[j] >= 0)
        tri.emplace_back(idx[i], idx[j], -it.value());
      else
        rhs.row(idx[i]) += it.value() * X.row(j);  // -K_II x_I = K_IB x_B
    }
  Eigen::SparseMatrix<double> A(nf, nf);
  A.setFromTriplets(tri.begin(), tri.end());
  // a new matrix every call: an AMG hierarchy would be built for three solves, so Jacobi here
  SolverOptions options = impl_->options;
  options.preconditioner = Preconditioner::jacobi;
  SparseSolver solver(impl_->dev, CsrMatrix::from_eigen(A), options);
  SolveStats st;
  for (int c = 0; c < 3; ++c) {
    Eigen::VectorXd xc(nf);
    for (int i = 0; i < n; ++i)
      if (idx[i] >= 0) xc(idx[i]) = X(i, c);
    const Eigen::VectorXd b = rhs.col(c);
    const SolverStats s = solver.solve(b, xc);
    st.iterations += s.iterations;
    st.residual = std::max(st.residual, s.relative_residual);
    for (int i = 0; i < n; ++i)
      if (idx[i] >= 0) X(i, c) = xc(idx[i]);
  }
  st.seconds = seconds_since(t0);
  return st;
}

}  // namespace vpm::detail
