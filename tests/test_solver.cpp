#include <catch2/catch.hpp>
#include <cmath>
#include <random>

#include "support/devices.hpp"
#include "support/fixtures.hpp"
#include "vpm/error.hpp"
#include "vpm/laplacian.hpp"
#include "vpm/solver.hpp"
#include "vpm/topology.hpp"

using namespace vpm;

namespace {
TetMesh jittered_ball(int n, double amount, unsigned seed = 1) {
  return test::jitter_interior(test::ball_mesh(n), n, amount, seed);
}
}  // namespace

TEST_CASE("Neumann CG: residual reached, zero mean, host and device agree") {
  const TetMesh m = jittered_ball(7, 0.2);
  const int n = m.num_vertices();
  const CsrMatrix k = cotan_laplacian(m.vertices, m.tets);
  const Eigen::VectorXd b = test::zero_sum_random(n, 4);
  Eigen::VectorXd reference;
  for (auto& dev : test::devices()) {
    INFO("device " << dev->name());
    PoissonSolver s(*dev, n, m.tets);
    s.set_positions(m.vertices);
    Eigen::VectorXd x;
    const SolverStats st = s.solve_neumann(b, x);
    CHECK(st.iterations > 5);
    CHECK(st.relative_residual <= 1e-8);
    CHECK((k.multiply(x) - b).norm() <= 1.01e-8 * b.norm());
    CHECK(std::abs(x.mean()) <= 1e-12 * x.cwiseAbs().maxCoeff());
    if (reference.size() == 0) reference = x;
    else CHECK((x - reference).norm() <= 1e-6 * reference.norm());
  }
}

TEST_CASE("both reduction modes (per work item, per work group) give the host's CG and BiCGSTAB") {
  auto cl = test::opencl_device();
  if (!cl) {
    WARN("no OpenCL device: reduction modes not compared");
    return;
  }
  const TetMesh m = jittered_ball(7, 0.2);
  const int n = m.num_vertices();
  const Eigen::VectorXd b = test::zero_sum_random(n, 5);
  auto solve = [&](Device& dev, SolverMethod method) {
    SolverOptions o;
    o.method = method;
    PoissonSolver s(dev, n, m.tets, o);
    s.set_positions(m.vertices);
    Eigen::VectorXd x;
    const SolverStats st = s.solve_neumann(b, x);
    return std::make_pair(st, x);
  };
  for (SolverMethod method : {SolverMethod::cg, SolverMethod::bicgstab}) {
    auto host = Device::host();
    const auto [hs, hx] = solve(*host, method);
    for (bool group : {false, true}) {
      INFO("method " << static_cast<int>(method) << ", group reduce " << group);
      test::GroupReduceScope scope(*cl, group);
      REQUIRE(cl->group_reduce() == group);
      const auto [ds, dx] = solve(*cl, method);
      // round-off differs with the summation order, so the counts differ by a few percent
      CHECK(std::abs(ds.iterations - hs.iterations) <= hs.iterations / 4);
      CHECK(ds.relative_residual <= 1e-8);
      CHECK((dx - hx).norm() <= 1e-6 * hx.norm());
    }
  }
}

TEST_CASE("Dirichlet CG reproduces a linear field (the harmonic map of an affine boundary)") {
  const TetMesh m = jittered_ball(6, 0.25, 9);
  const int n = m.num_vertices();
  const auto bnd = boundary_vertex_mask(n, boundary_faces(m.tets));
  Eigen::Matrix3d a;
  a << 1.0, 0.2, -0.3, 0.1, 2.0, 0.4, -0.5, 0.3, 0.7;
  FieldValues lin = m.vertices * a.transpose();
  lin.col(0).array() += 0.5;
  for (auto& dev : test::devices()) {
    INFO("device " << dev->name());
    PoissonSolver s(*dev, n, m.tets);
    s.set_positions(m.vertices);
    FieldValues x;
    const SolverStats st = s.solve_dirichlet(bnd, lin, x);
    REQUIRE(x.rows() == n);
    REQUIRE(x.cols() == 3);
    CHECK(st.relative_residual <= 1e-8);
    CHECK((x - lin).cwiseAbs().maxCoeff() <= 1e-6);
    for (int i = 0; i < n; ++i)
      if (bnd[i]) CHECK((x.row(i) - lin.row(i)).norm() == 0.0);
    // one-call helper with a right-hand side given: rows of K x equal rhs on free vertices
    FieldValues rhs = FieldValues::Zero(n, 1);
    for (int i = 0; i < n; ++i) rhs(i, 0) = bnd[i] ? 0.0 : 1e-3 * std::cos(1.0 * i);
    FieldValues zero = FieldValues::Zero(n, 1), y;
    s.solve_dirichlet(bnd, zero, y, &rhs);
    const Eigen::VectorXd ky = s.laplacian().matrix().multiply(y.col(0));
    double err = 0;
    for (int i = 0; i < n; ++i)
      if (!bnd[i]) err = std::max(err, std::abs(ky[i] - rhs(i, 0)));
    CHECK(err <= 1e-8 * rhs.norm());
  }
}

TEST_CASE("warm start from the previous step's solution reduces iterations") {
  const TetMesh m = jittered_ball(7, 0.2, 3);
  const int n = m.num_vertices();
  const Eigen::VectorXd b = test::zero_sum_random(n, 8);
  for (auto& dev : test::devices()) {
    INFO("device " << dev->name());
    PoissonSolver s(*dev, n, m.tets);
    s.set_positions(m.vertices);
    Eigen::VectorXd x;
    const int cold = s.solve_neumann(b, x).iterations;
    // the flow moves the vertices a little; solve again from the previous solution
    Points moved = m.vertices;
    for (int i = 0; i < n; ++i) moved.row(i) *= 1.0 + 0.002 * std::sin(5.0 * i);
    s.set_positions(moved);
    Eigen::VectorXd warm_x = x, cold_x;
    const int warm = s.solve_neumann(b, warm_x).iterations;
    const int cold2 = s.solve_neumann(b, cold_x).iterations;
    CHECK(warm < cold2);
    CHECK(cold > 0);
    CHECK((warm_x - cold_x).norm() <= 1e-6 * cold_x.norm());
  }
}

TEST_CASE("non-convergence throws NumericalError with the residual reached") {
  const TetMesh m = jittered_ball(6, 0.2);
  const int n = m.num_vertices();
  const Eigen::VectorXd b = test::zero_sum_random(n, 2);
  for (auto& dev : test::devices()) {
    INFO("device " << dev->name());
    SolverOptions o;
    o.max_iterations = 3;
    PoissonSolver s(*dev, n, m.tets, o);
    s.set_positions(m.vertices);
    Eigen::VectorXd x;
    try {
      s.solve_neumann(b, x);
      FAIL("no exception");
    } catch (const NumericalError& e) {
      const std::string msg = e.what();
      CHECK(msg.find("relative residual") != std::string::npos);
      CHECK(msg.find("3 iterations") != std::string::npos);
    }
  }
}

TEST_CASE("an incompatible Neumann right side is reported, not solved") {
  const TetMesh m = test::ball_mesh(4);
  const int n = m.num_vertices();
  Eigen::VectorXd b = test::zero_sum_random(n, 5);
  b[0] += 1.0;
  for (auto& dev : test::devices()) {
    PoissonSolver s(*dev, n, m.tets);
    s.set_positions(m.vertices);
    Eigen::VectorXd x;
    CHECK_THROWS_AS(s.solve_neumann(b, x), InputError);
    std::vector<char> none(n, 0);
    FieldValues v = FieldValues::Zero(n, 1), y;
    CHECK_THROWS_AS(s.solve_dirichlet(none, v, y), InputError);
  }
}

TEST_CASE("BiCGSTAB on a non-symmetric system and the paper's normal equations") {
  const TetMesh m = jittered_ball(5, 0.2, 6);
  const int n = m.num_vertices();
  // A = -K + I/n + a skew part: non-symmetric, non-singular
  CsrMatrix a = cotan_laplacian(m.vertices, m.tets);
  for (int i = 0; i < n; ++i)
    for (int q = a.row_ptr[i]; q < a.row_ptr[i + 1]; ++q) {
      const int j = a.col[q];
      a.val[q] = -a.val[q] + (i == j ? 0.05 : 0.02 * (i < j ? 1 : -1));
    }
  const Eigen::VectorXd b = test::zero_sum_random(n, 12) + Eigen::VectorXd::Constant(n, 0.3);
  Eigen::VectorXd ref;
  for (auto& dev : test::devices()) {
    INFO("device " << dev->name());
    SolverOptions o;
    o.method = SolverMethod::bicgstab;
    SolverStats st;
    const Eigen::VectorXd x = solve(a, b, o, dev.get(), &st);
    CHECK(st.relative_residual <= 1e-8);
    CHECK((a.multiply(x) - b).norm() <= 1.01e-8 * b.norm());
    if (ref.size() == 0) ref = x;
    else CHECK((x - ref).norm() <= 1e-6 * ref.norm());
    o.method = SolverMethod::paper;
    o.relative_tolerance = 1e-10;
    const Eigen::VectorXd xp = solve(a, b, o, dev.get(), &st);
    CHECK((xp - ref).norm() <= 1e-5 * ref.norm());
    CHECK(st.relative_residual <= 1e-5);
    // CG on a symmetric positive definite matrix through the general interface
    CsrMatrix spd = cotan_laplacian(m.vertices, m.tets);
    for (int i = 0; i < n; ++i)
      for (int q = spd.row_ptr[i]; q < spd.row_ptr[i + 1]; ++q)
        spd.val[q] = -spd.val[q] + (spd.col[q] == i ? 0.01 : 0.0);
    o = SolverOptions{};
    const Eigen::VectorXd xc = solve(spd, b, o, dev.get(), &st);
    CHECK((spd.multiply(xc) - b).norm() <= 1.01e-8 * b.norm());
  }
}

TEST_CASE("paper option and BiCGSTAB solve the Dirichlet harmonic problem too") {
  const TetMesh m = jittered_ball(4, 0.2, 2);
  const int n = m.num_vertices();
  const auto bnd = boundary_vertex_mask(n, boundary_faces(m.tets));
  FieldValues lin = m.vertices.col(1) * 2.0;
  for (auto method : {SolverMethod::bicgstab, SolverMethod::paper}) {
    for (auto& dev : test::devices()) {
      INFO("device " << dev->name() << " method " << to_string(method));
      SolverOptions o;
      o.method = method;
      o.relative_tolerance = 1e-10;
      PoissonSolver s(*dev, n, m.tets, o);
      s.set_positions(m.vertices);
      FieldValues x;
      s.solve_dirichlet(bnd, lin, x);
      CHECK((x - lin).cwiseAbs().maxCoeff() <= 1e-5);
    }
  }
  CHECK(parse_solver_method("paper") == SolverMethod::paper);
  CHECK_THROWS_AS(parse_solver_method("lu"), InputError);
}

TEST_CASE("Dirichlet columns solved as a block equal the one-column solves bit for bit") {
  // Jacobi CG runs up to three columns together (one pass over the matrix per iteration); each
  // column must take exactly its own iterations. Columns converge at different counts here (a
  // smooth, a rough and an all-zero right side), and a fourth column starts a second block.
  const TetMesh m = jittered_ball(7, 0.2, 5);
  const int n = m.num_vertices();
  const auto bnd = boundary_vertex_mask(n, boundary_faces(m.tets));
  FieldValues values = FieldValues::Zero(n, 4), rhs = FieldValues::Zero(n, 4);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int i = 0; i < n; ++i) {
    values(i, 0) = m.vertices(i, 0);                       // smooth boundary data
    values(i, 1) = bnd[i] ? u(rng) : 0.0;                  // rough boundary data
    rhs(i, 1) = bnd[i] ? 0.0 : 1e-2 * u(rng);
    values(i, 3) = m.vertices(i, 1) * m.vertices(i, 2);    // column 2 stays zero: nothing to solve
  }
  std::vector<std::vector<double>> reference;
  for (auto& dev : test::devices()) {
    INFO("device " << dev->name());
    PoissonSolver s(*dev, n, m.tets);
    s.set_positions(m.vertices);
    FieldValues block;
    const SolverStats all = s.solve_dirichlet(bnd, values, block, &rhs);
    int iterations = 0;
    for (int c = 0; c < 4; ++c) {
      FieldValues v = values.col(c), r = rhs.col(c), one;
      iterations += s.solve_dirichlet(bnd, v, one, &r).iterations;
      CHECK(block.col(c) == one.col(0));  // exact
      CHECK(std::isfinite(one.col(0).sum()));
    }
    CHECK(all.iterations == iterations);
    CHECK(all.relative_residual <= 1e-8);
    // and host == device to the tolerance
    std::vector<double> flat(block.data(), block.data() + block.size());
    if (reference.empty()) reference.push_back(flat);
    else
      for (size_t i = 0; i < flat.size(); ++i) CHECK(std::abs(flat[i] - reference[0][i]) <= 1e-7);
  }
}
