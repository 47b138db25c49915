// vpm_bench_hypre: hypre's BoomerAMG-preconditioned CG (Debian's libhypre-dev 2.26, MPI) on a
// problem of vpm_bench_solver: the cotangent Laplacian of the jittered voxel ellipsoid or of a
// mesh file, Neumann, the same right-hand side, relative residual 1e-8. vpm_bench_solver starts
// it under `mpirun -np N` (hypre in Debian is built without OpenMP, so ranks are its only
// parallelism) and reads its JSON back as rows of its own table.
//
//   mpirun -np N vpm_bench_hypre --problem ellipsoid:TETS|MESH --repeats R --json FILE
//
// Every rank builds the whole problem (deterministic, not timed) and owns a contiguous block of
// rows. Each repeat creates BoomerAMG and PCG anew, times the setup (hypre rebuilds the whole
// hierarchy for new matrix values: a flow step's cost) and the solve separately, from x = 0.
// BoomerAMG settings are the ones hypre's documentation recommends for 3-D diffusion: HMIS
// coarsening, extended+i interpolation truncated to 4 entries per row, strong threshold 0.5,
// hypre's default l1 hybrid Gauss-Seidel smoothing (forward down, backward up: a symmetric
// V-cycle), one V-cycle per CG iteration.
#include <HYPRE.h>
#include <HYPRE_IJ_mv.h>
#include <HYPRE_parcsr_ls.h>
#include <mpi.h>

#include <algorithm>
#include <cstdlib>
#include <iostream>
#include <string>
#include <vector>

#include "solver/peers.hpp"
#include "vpm/device.hpp"
#include "vpm/error.hpp"
#include "vpm/json.hpp"

using namespace vpm;
using bench::median;

namespace {

struct Options {
  std::string problem = "ellipsoid:100000";  ///< bench::problem_mesh's source
  int repeats = 5;
  std::string json_path = "hypre.json";
};

Options parse_options(int argc, char** argv) {
  Options o;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) throw InputError(a + ": missing value");
      return argv[++i];
    };
    if (a == "--problem") o.problem = next();
    else if (a == "--repeats") o.repeats = std::max(1, std::stoi(next()));
    else if (a == "--json") o.json_path = next();
    else throw InputError("unknown argument " + a);
  }
  return o;
}

void check(HYPRE_Int err, const char* what) {
  if (err) throw NumericalError(std::string("hypre: ") + what + " returned error " + std::to_string(err));
}

/// The first of rank q's rows when n rows are split into `ranks` contiguous blocks.
int first_row(int n, int q, int ranks) { return int(long(n) * q / ranks); }

/// This rank's rows [lo, hi] (inclusive, hypre's convention) of -K and -b in hypre's IJ form.
struct Distributed {
  HYPRE_IJMatrix A = nullptr;
  HYPRE_IJVector b = nullptr, x = nullptr;
  HYPRE_ParCSRMatrix par_A = nullptr;
  HYPRE_ParVector par_b = nullptr, par_x = nullptr;
  int lo = 0, hi = -1;
  std::vector<HYPRE_Int> rows;  ///< lo .. hi, the indices of this rank's vector entries

  Distributed(const bench::Problem& p, int rank, int ranks) {
    lo = first_row(p.n, rank, ranks);
    hi = first_row(p.n, rank + 1, ranks) - 1;
    for (int r = lo; r <= hi; ++r) rows.push_back(r);
    check(HYPRE_IJMatrixCreate(MPI_COMM_WORLD, lo, hi, lo, hi, &A), "IJMatrixCreate");
    check(HYPRE_IJMatrixSetObjectType(A, HYPRE_PARCSR), "IJMatrixSetObjectType");
    std::vector<HYPRE_Int> sizes(hi - lo + 1);
    for (int r = lo; r <= hi; ++r) sizes[r - lo] = p.K.row_ptr[r + 1] - p.K.row_ptr[r];
    check(HYPRE_IJMatrixSetRowSizes(A, sizes.data()), "IJMatrixSetRowSizes");
    check(HYPRE_IJMatrixInitialize(A), "IJMatrixInitialize");
    for (int r = lo; r <= hi; ++r) {
      HYPRE_Int row = r, count = sizes[r - lo];
      std::vector<HYPRE_Int> cols(p.K.col.begin() + p.K.row_ptr[r], p.K.col.begin() + p.K.row_ptr[r + 1]);
      std::vector<double> vals(count);
      for (int k = 0; k < count; ++k) vals[k] = -p.K.val[p.K.row_ptr[r] + k];
      check(HYPRE_IJMatrixSetValues(A, 1, &count, &row, cols.data(), vals.data()), "IJMatrixSetValues");
    }
    check(HYPRE_IJMatrixAssemble(A), "IJMatrixAssemble");
    check(HYPRE_IJMatrixGetObject(A, reinterpret_cast<void**>(&par_A)), "IJMatrixGetObject");
    make_vector(b, std::vector<double>(p.b_spd.data() + lo, p.b_spd.data() + hi + 1));
    make_vector(x, std::vector<double>(rows.size(), 0.0));
    check(HYPRE_IJVectorGetObject(b, reinterpret_cast<void**>(&par_b)), "IJVectorGetObject");
    check(HYPRE_IJVectorGetObject(x, reinterpret_cast<void**>(&par_x)), "IJVectorGetObject");
  }
  ~Distributed() {
    HYPRE_IJMatrixDestroy(A);
    HYPRE_IJVectorDestroy(b);
    HYPRE_IJVectorDestroy(x);
  }
  Distributed(const Distributed&) = delete;
  Distributed& operator=(const Distributed&) = delete;

  void make_vector(HYPRE_IJVector& v, const std::vector<double>& vals) {
    check(HYPRE_IJVectorCreate(MPI_COMM_WORLD, lo, hi, &v), "IJVectorCreate");
    check(HYPRE_IJVectorSetObjectType(v, HYPRE_PARCSR), "IJVectorSetObjectType");
    check(HYPRE_IJVectorInitialize(v), "IJVectorInitialize");
    check(HYPRE_IJVectorSetValues(v, HYPRE_Int(rows.size()), rows.data(), vals.data()), "IJVectorSetValues");
    check(HYPRE_IJVectorAssemble(v), "IJVectorAssemble");
  }

  void zero_x() {
    const std::vector<double> zeros(rows.size(), 0.0);
    check(HYPRE_IJVectorSetValues(x, HYPRE_Int(rows.size()), rows.data(), zeros.data()), "IJVectorSetValues");
  }

  /// The whole solution on rank 0 (empty elsewhere).
  Eigen::VectorXd gather_x(int n, int rank, int ranks) const {
    std::vector<double> mine(rows.size());
    check(HYPRE_IJVectorGetValues(x, HYPRE_Int(rows.size()), rows.data(), mine.data()), "IJVectorGetValues");
    std::vector<int> counts(ranks), offsets(ranks);
    for (int q = 0; q < ranks; ++q) {
      offsets[q] = first_row(n, q, ranks);
      counts[q] = first_row(n, q + 1, ranks) - offsets[q];
    }
    Eigen::VectorXd all;
    if (rank == 0) all.resize(n);
    MPI_Gatherv(mine.data(), int(mine.size()), MPI_DOUBLE, rank == 0 ? all.data() : nullptr, counts.data(),
                offsets.data(), MPI_DOUBLE, 0, MPI_COMM_WORLD);
    return all;
  }
};

struct Timing {
  std::vector<double> setup_s, solve_s;
  int iterations = 0;
  double final_relative = 0;
};

/// One repeat: new BoomerAMG + PCG, setup and solve timed separately (wall clock, all ranks).
void solve_once(Distributed& d, Timing& t) {
  d.zero_x();
  HYPRE_Solver pcg = nullptr, amg = nullptr;
  MPI_Barrier(MPI_COMM_WORLD);
  const double t0 = MPI_Wtime();
  check(HYPRE_ParCSRPCGCreate(MPI_COMM_WORLD, &pcg), "ParCSRPCGCreate");
  HYPRE_PCGSetTol(pcg, bench::kTolerance);
  HYPRE_PCGSetTwoNorm(pcg, 1);
  HYPRE_PCGSetMaxIter(pcg, 1000);
  HYPRE_PCGSetPrintLevel(pcg, 0);
  check(HYPRE_BoomerAMGCreate(&amg), "BoomerAMGCreate");
  HYPRE_BoomerAMGSetCoarsenType(amg, 10);  // HMIS
  HYPRE_BoomerAMGSetInterpType(amg, 6);    // extended+i
  HYPRE_BoomerAMGSetPMaxElmts(amg, 4);
  HYPRE_BoomerAMGSetStrongThreshold(amg, 0.5);
  HYPRE_BoomerAMGSetMaxIter(amg, 1);
  HYPRE_BoomerAMGSetTol(amg, 0.0);
  HYPRE_BoomerAMGSetPrintLevel(amg, 0);
  HYPRE_PCGSetPrecond(pcg, reinterpret_cast<HYPRE_PtrToSolverFcn>(HYPRE_BoomerAMGSolve),
                      reinterpret_cast<HYPRE_PtrToSolverFcn>(HYPRE_BoomerAMGSetup), amg);
  check(HYPRE_ParCSRPCGSetup(pcg, d.par_A, d.par_b, d.par_x), "ParCSRPCGSetup");
  MPI_Barrier(MPI_COMM_WORLD);
  const double t1 = MPI_Wtime();
  const HYPRE_Int err = HYPRE_ParCSRPCGSolve(pcg, d.par_A, d.par_b, d.par_x);
  MPI_Barrier(MPI_COMM_WORLD);
  const double t2 = MPI_Wtime();
  HYPRE_Int its = 0;
  HYPRE_ParCSRPCGGetNumIterations(pcg, &its);
  HYPRE_ParCSRPCGGetFinalRelativeResidualNorm(pcg, &t.final_relative);
  HYPRE_ParCSRPCGDestroy(pcg);
  HYPRE_BoomerAMGDestroy(amg);
  if (err && err != HYPRE_ERROR_CONV)
    throw NumericalError("hypre: ParCSRPCGSolve returned error " + std::to_string(err));
  HYPRE_ClearAllErrors();
  t.setup_s.push_back(t1 - t0);
  t.solve_s.push_back(t2 - t1);
  t.iterations = its;
}

Json to_json(const Timing& t, const bench::Problem& p, int ranks, double relative_residual) {
  Json j = Json::object();
  j["solver"] = "hypre-boomeramg-cg";
  j["ranks"] = ranks;
  j["tets"] = long(p.mesh.num_tets());
  j["vertices"] = p.n;
  j["nnz"] = p.nnz;
  Json solve = Json::array(), setup = Json::array();
  for (double s : t.solve_s) solve.push_back(s);
  for (double s : t.setup_s) setup.push_back(s);
  j["times_s"] = solve;
  j["setup_times_s"] = setup;
  j["median_s"] = median(t.solve_s);
  j["setup_s"] = median(t.setup_s);
  j["iterations"] = t.iterations;
  j["hypre_final_relative_residual"] = t.final_relative;
  j["relative_residual"] = relative_residual;
  j["settings"] = "BoomerAMG: HMIS, ext+i interpolation (Pmax 4), strong threshold 0.5, default smoothing; PCG two-norm";
  return j;
}

}  // namespace

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  int rank = 0, ranks = 1, status = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &ranks);
  try {
    const Options o = parse_options(argc, argv);
    setenv("VPM_DEVICE", "host", 1);  // the problem is assembled on the host; no OpenCL here
    HYPRE_Init();
    std::string name;
    TetMesh mesh = bench::problem_mesh(o.problem, name);
    bench::Problem p(Device::current(), name, std::move(mesh));
    {
      Distributed d(p, rank, ranks);
      Timing t;
      solve_once(d, t);  // warm-up (first allocations, page faults)
      t = Timing{};
      for (int k = 0; k < o.repeats; ++k) solve_once(d, t);
      const Eigen::VectorXd x = d.gather_x(p.n, rank, ranks);
      if (rank == 0) {
        const double rel = (p.K.multiply(x) - p.b).norm() / p.b.norm();
        write_json_file(o.json_path, to_json(t, p, ranks, rel));
        std::cerr << "hypre " << ranks << " rank(s), " << p.name << ": solve " << median(t.solve_s)
                  << " s, setup " << median(t.setup_s) << " s, " << t.iterations << " iterations, residual "
                  << rel << "\n";
      }
    }
    HYPRE_Finalize();
  } catch (const InputError& e) {
    std::cerr << "vpm_bench_hypre (rank " << rank << "): " << e.what() << "\n";
    status = 2;
  } catch (const std::exception& e) {
    std::cerr << "vpm_bench_hypre (rank " << rank << "): " << e.what() << "\n";
    status = 3;
  }
  // a rank that failed may leave the others inside a collective: abort them all, never hang
  if (status) MPI_Abort(MPI_COMM_WORLD, status);
  MPI_Finalize();
  return status;
}
