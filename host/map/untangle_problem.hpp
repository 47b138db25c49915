#pragma once
// Private to the untangler (host/map/untangle*.cpp): the optimisation problem and the
// evaluation of the energy and its gradient (see vpm/untangle.hpp for the energy).
#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <memory>
#include <vector>

#include "vpm/mesh.hpp"

namespace vpm {

class Device;

/// chi(D, eps) = (D + sqrt(eps^2 + D^2)) / 2, evaluated without cancellation for D < 0.
inline double untangle_chi(double d, double eps) {
  const double s = std::sqrt(eps * eps + d * d);
  return d >= 0 ? 0.5 * (d + s) : 0.5 * eps * eps / (s - d);
}

/// The next eps of the outer loop (Garanzha et al. 2021) after a minimisation that took the
/// energy from `e_prev` to `e` and left the smallest det J `min_det` at `eps`:
/// sigma = max(1 - e / e_prev, sigma_min), mu = (1 - sigma) chi(min_det, eps), then
/// 2 sqrt(mu (mu - min_det)) while min_det < mu, else 1e-10.
inline double untangle_next_eps(double e, double e_prev, double min_det, double eps, double sigma_min) {
  const double sigma = std::max(1.0 - e / e_prev, sigma_min);
  const double mu = (1 - sigma) * untangle_chi(min_det, eps);
  return min_det < mu ? 2 * std::sqrt(mu * (mu - min_det)) : 1e-10;
}

class UntangleDeviceEval;
class UntangleHostEval;

/// Active tets (with inverse reference edge matrices and weights) and free vertices (their
/// coordinates are the unknowns z, 3 per free vertex).
struct UntangleProblem {
  const Tets* tets = nullptr;
  std::vector<int> active;               ///< tet indices
  std::vector<Eigen::Matrix3d> rinv;     ///< R^-1 per active tet (R: scaled reference edges)
  std::vector<double> weight;            ///< normalised reference volume per active tet
  std::vector<int> var;                  ///< per vertex: index of its first unknown, or -1
  std::vector<int> free_vertices;
  double theta = 1.0 / 128.0;
  UntangleDeviceEval* device = nullptr;  ///< OpenCL evaluation when set
  UntangleHostEval* host = nullptr;      ///< host threads when set (else one thread)
};

/// Energy, smallest det J and number of det J <= 0 over the active tets.
struct UntangleEval {
  double energy = 0;
  double min_det = 0;
  int nonpositive = 0;
};

/// Energy at positions `x` (n x 3) and eps, and its gradient with respect to the unknowns if
/// `g` is given (resized by the caller to 3 * free vertices). On p.device when set, else on
/// the host: over p.host's threads when set, else on the calling thread (the same numbers).
UntangleEval evaluate(const UntangleProblem& p, const Points& x, double eps, Eigen::VectorXd* g);

/// Host evaluation over a pool of threads: the per-tet energies and dE/dX are computed in
/// parallel into arrays, the gradient gathered per free vertex in tet order and the
/// energy summed in tet order, so the result is the one-thread result bit for bit whatever the
/// number of threads. Small problems run on the calling thread. The problem's active tets,
/// rinv, weights, var and theta must be final when this is constructed.
class UntangleHostEval {
 public:
  /// `threads`: how many (the caller's included); 0: one per 512 active tets, at most the
  /// hardware's (core/parallel.hpp host_threads).
  explicit UntangleHostEval(const UntangleProblem& p, int threads = 0);
  ~UntangleHostEval();
  UntangleEval run(const Points& x, double eps, Eigen::VectorXd* grad);

 private:
  struct State;
  std::unique_ptr<State> s_;
};

/// OpenCL evaluation: kernels/untangle.cl computes per-tet energies, determinants and corner
/// gradients, then gathers the gradient per free vertex; the host sums the energies (fixed
/// order) and reads everything back with one synchronisation per evaluation. The problem's
/// active tets, rinv, weights and theta must be final when this is constructed.
class UntangleDeviceEval {
 public:
  UntangleDeviceEval(Device& device, const UntangleProblem& p, int num_vertices);
  ~UntangleDeviceEval();
  UntangleEval run(const Points& x, double eps, Eigen::VectorXd* grad);

 private:
  struct State;
  std::unique_ptr<State> s_;
};

}  // namespace vpm
