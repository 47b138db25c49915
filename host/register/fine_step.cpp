// The fine steps of dense registration on the mesh itself (fine_step.hpp).
#include "register/fine_step.hpp"

#include <Eigen/IterativeLinearSolvers>
#include <Eigen/Sparse>

#include "vpm/error.hpp"
#include "vpm/topology.hpp"

namespace vpm {

Points fine_displacement(const LocalSystems& local, const Points& ball, const Tets& tets,
                         const std::vector<char>& boundary, double smoothness, double cap) {
  const Eigen::Index n = ball.rows();
  if (static_cast<Eigen::Index>(local.a.size()) != n || local.b.rows() != n || static_cast<Eigen::Index>(boundary.size()) != n)
    throw InputError("fine step: one local system and one boundary flag per vertex expected");
  double trace = 0;
  for (const Eigen::Matrix3d& a : local.a) trace += a.trace();
  const double scale = trace > 0 ? 3.0 * static_cast<double>(n) / trace : 0.0;
  // a little everywhere, so vertices far from any texture are held by their neighbours alone
  // without a singular system where a whole component has none
  const double floor = 1e-3;
  std::vector<Eigen::Triplet<double>> t;
  t.reserve(static_cast<size_t>(n) * 9 + static_cast<size_t>(tets.rows()) * 6 * 12);
  Eigen::VectorXd rhs(3 * n);
  for (Eigen::Index v = 0; v < n; ++v) {
    Eigen::Matrix3d a = scale * local.a[static_cast<size_t>(v)] + floor * Eigen::Matrix3d::Identity();
    Eigen::Vector3d b = scale * local.b.row(v).transpose();
    if (boundary[static_cast<size_t>(v)]) {  // tangential only: project, and pin the normal part
      const Eigen::Vector3d nrm = ball.row(v).transpose().normalized();
      const Eigen::Matrix3d p = Eigen::Matrix3d::Identity() - nrm * nrm.transpose();
      a = p * a * p + 1e3 * nrm * nrm.transpose();
      b = p * b;
    }
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) t.emplace_back(3 * v + i, 3 * v + j, a(i, j));
    rhs.segment<3>(3 * v) = b;
  }
  const auto edges = unique_edges(tets);
  for (Eigen::Index e = 0; e < edges.rows(); ++e) {
    const Eigen::Index i = edges(e, 0), j = edges(e, 1);
    for (int c = 0; c < 3; ++c) {
      t.emplace_back(3 * i + c, 3 * i + c, smoothness);
      t.emplace_back(3 * j + c, 3 * j + c, smoothness);
      t.emplace_back(3 * i + c, 3 * j + c, -smoothness);
      t.emplace_back(3 * j + c, 3 * i + c, -smoothness);
    }
  }
  Eigen::SparseMatrix<double, Eigen::RowMajor> m(3 * n, 3 * n);
  m.setFromTriplets(t.begin(), t.end());
  Eigen::ConjugateGradient<Eigen::SparseMatrix<double, Eigen::RowMajor>, Eigen::Lower | Eigen::Upper> cg(m);
  cg.setTolerance(1e-6);
  cg.setMaxIterations(2000);
  const Eigen::VectorXd u = cg.solve(rhs);
  Points out(n, 3);
  for (Eigen::Index v = 0; v < n; ++v) {
    Eigen::Vector3d d = u.segment<3>(3 * v);
    if (boundary[static_cast<size_t>(v)]) d -= d.dot(ball.row(v).transpose().normalized()) * ball.row(v).transpose().normalized();
    const double len = d.norm();
    if (len > cap) d *= cap / len;
    out.row(v) = d.transpose();
  }
  return out;
}

}  // namespace vpm
