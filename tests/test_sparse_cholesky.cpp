// The host's sparse Cholesky (linalg/sparse_cholesky.hpp): CHOLMOD's supernodal factor where
// vpm was built with it, Eigen's SimplicialLDLT otherwise and for matrices that are not
// positive definite; both must give Eigen's reference answers.
#include <catch2/catch.hpp>
#include <Eigen/SparseCholesky>
#include <thread>

#include "linalg/sparse_cholesky.hpp"
#include "map/sphere_steps.hpp"
#include "support/shapes.hpp"
#include "vpm/config.hpp"
#include "vpm/topology.hpp"

using namespace vpm;
using detail::BlasThreadsScope;
using detail::SparseCholesky;
using detail::SpMat;

namespace {

// The cotangent Laplacian of an ellipsoid's boundary with vertex 0's row and column removed
// (symmetric positive definite), the boundary scaled by `stretch` along x (new values, same
// pattern).
SpMat pinned_surface_laplacian(double stretch) {
  TriSurface s = boundary_surface(test::ellipsoid_mesh(8));
  s.vertices.col(0) *= stretch;
  const SpMat l = detail::cot_laplacian(s.vertices, s.triangles, 0);
  std::vector<int> used(l.rows(), 0);
  for (Eigen::Index t = 0; t < s.triangles.size(); ++t) used[s.triangles.data()[t]] = 1;
  std::vector<int> keep;
  for (int i = 1; i < static_cast<int>(l.rows()); ++i)
    if (used[i]) keep.push_back(i);
  std::vector<int> id(l.rows(), -1);
  for (size_t j = 0; j < keep.size(); ++j) id[keep[j]] = static_cast<int>(j);
  std::vector<Eigen::Triplet<double>> t;
  for (int c = 0; c < l.outerSize(); ++c)
    for (SpMat::InnerIterator it(l, c); it; ++it)
      if (id[it.row()] >= 0 && id[it.col()] >= 0) t.emplace_back(id[it.row()], id[it.col()], it.value());
  SpMat a(static_cast<Eigen::Index>(keep.size()), static_cast<Eigen::Index>(keep.size()));
  a.setFromTriplets(t.begin(), t.end());
  return a;
}

double relative_residual(const SpMat& a, const Eigen::MatrixXd& x, const Eigen::MatrixXd& b) {
  return (a * x - b).norm() / b.norm();
}

}  // namespace

TEST_CASE("sparse Cholesky: the supernodal factor solves a surface Laplacian as Eigen's LDLT does, "
          "and refactors a matrix of the same pattern") {
  const SpMat a = pinned_surface_laplacian(1.0);
  REQUIRE(a.rows() > 200);
  const Eigen::MatrixXd b = Eigen::MatrixXd::Random(a.rows(), 3);
  SparseCholesky chol;
  REQUIRE(chol.factorize(a));
  CHECK(std::string(chol.backend()) == (VPM_HAVE_CHOLMOD ? "cholmod-supernodal" : "eigen-simplicial-ldlt"));
  const Eigen::MatrixXd x = chol.solve(b);
  const Eigen::MatrixXd ref = Eigen::SimplicialLDLT<SpMat>(a).solve(b);
  CHECK(relative_residual(a, x, b) < 1e-12);
  CHECK((x - ref).norm() < 1e-9 * ref.norm());
  const Eigen::VectorXd x0 = chol.solve(Eigen::VectorXd(b.col(0)));
  CHECK((x0 - x.col(0)).norm() < 1e-14 * x.col(0).norm());

  const SpMat a2 = pinned_surface_laplacian(1.7);  // other values, same pattern
  REQUIRE(chol.factorize(a2, true));
  const Eigen::MatrixXd x2 = chol.solve(b);
  CHECK(relative_residual(a2, x2, b) < 1e-12);
  CHECK(relative_residual(a, x2, b) > 1e-3);  // the new matrix's answer, not the old one's
}

TEST_CASE("sparse Cholesky: a symmetric matrix that is not positive definite falls back to LDLT") {
  SpMat a = pinned_surface_laplacian(1.0);
  for (Eigen::Index i = 0; i < a.rows(); i += 2) a.coeffRef(i, i) = -a.coeff(i, i);  // indefinite
  const Eigen::VectorXd b = Eigen::VectorXd::Random(a.rows());
  SparseCholesky chol;
  REQUIRE(chol.factorize(a));
  CHECK(std::string(chol.backend()) == "eigen-simplicial-ldlt");
  CHECK(relative_residual(a, chol.solve(b), b) < 1e-10);
  // back to a positive definite matrix: the supernodal factor is used again where built
  REQUIRE(chol.factorize(pinned_surface_laplacian(1.0)));
  CHECK(std::string(chol.backend()) == (VPM_HAVE_CHOLMOD ? "cholmod-supernodal" : "eigen-simplicial-ldlt"));
}

TEST_CASE("sparse Cholesky: the BLAS thread bound is one outside a scope, the scope's inside, per thread") {
  CHECK(BlasThreadsScope::current() == 1);
  const SpMat a = pinned_surface_laplacian(1.3);
  const Eigen::MatrixXd b = Eigen::MatrixXd::Random(a.rows(), 2);
  SparseCholesky one;
  REQUIRE(one.factorize(a));
  const Eigen::MatrixXd x1 = one.solve(b);
  {
    const BlasThreadsScope four(4);
    CHECK(BlasThreadsScope::current() == 4);
    int elsewhere = 0;
    std::thread([&] { elsewhere = BlasThreadsScope::current(); }).join();
    CHECK(elsewhere == 1);  // the bound is the calling thread's
    {
      const BlasThreadsScope two(2);
      CHECK(BlasThreadsScope::current() == 2);
    }
    CHECK(BlasThreadsScope::current() == 4);
    SparseCholesky more;
    REQUIRE(more.factorize(a));
    const Eigen::MatrixXd x4 = more.solve(b);
    CHECK(relative_residual(a, x4, b) < 1e-12);
    CHECK((x4 - x1).norm() < 1e-10 * x1.norm());
  }
  CHECK(BlasThreadsScope::current() == 1);
  const BlasThreadsScope none(0);
  CHECK(BlasThreadsScope::current() == 1);  // at least one
}
