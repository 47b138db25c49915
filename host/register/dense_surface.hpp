#pragma once
// Private: what the dense registrations on the sphere (sphere_match.cpp) and in the disk
// (disk_match.cpp) share: the vertices' area shares, the scalars' standardisation and
// correlation, the Gauss-Newton weights of a step's field, the repair of flipped faces, and the
// rules that keep or end a step.
#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <cmath>
#include <vector>

#include "core/parallel.hpp"
#include "map/surface_polish.hpp"
#include "register/point_bins.hpp"
#include "vpm/mesh.hpp"
#include "vpm/surface_registration.hpp"

namespace vpm::detail {

/// A step is kept when it lowers the mismatch by this fraction at least; a level ends when the
/// gain is below kLevelGain; a step is halved at most kHalvings times.
constexpr double kMinGain = 1e-4, kLevelGain = 1e-3;
constexpr int kHalvings = 4;
/// A step whose flipped slivers were repaired is kept only if the repaired step changes the face
/// areas (mean |r - 1| against the positions before it) by at most this.
constexpr double kRepairAreaChange = 0.001;
/// A dense step in the disk may not press a face below this fraction of its input area (unless
/// the smallest was already there): the face counts as crushed, as a flip the repair cannot mend
/// does (crushes).
constexpr double kCrushedArea = 0.1;
/// A disk level whose step crushes faces at every halving brings the face areas back towards the
/// input's (relieve_areas, kReliefRounds polish steps) and goes on, at most kReliefs times a
/// level: the discrete motion of an area-preserving flow shears slivers until they collapse, and
/// without this the finer levels refuse nearly every step. On the sphere, whose deformations
/// shear less, the same rule lowered the curvature-only gap to the ideal but not the landmarks'
/// and took three times as long: not used there (bench/results/LEDGER.md).
constexpr int kReliefs = 4, kReliefRounds = 5;
/// Below this correlation of the smoothed scalars a registration without landmarks first searches
/// a rotation; maps that correlate better are not searched: the coarse scalar then has flat
/// directions (turns that barely change it) along which the search slides to a wrong rotation (on
/// the sphere's development surface 12-27 degrees, one seed's distance to the truth 0.11 -> 0.38
/// rad); the maps to search start far below (vpm demo's two brains: 0.08, 0.34; the development
/// and report surfaces: 0.87-0.98). The rotation found is applied when it shrinks 1 - correlation
/// to kRotationGain of what it was.
constexpr double kAligned = 0.75, kRotationGain = 0.5;

using SparseRows = Eigen::SparseMatrix<double, Eigen::RowMajor>;

/// A third of the areas of each vertex's faces.
Eigen::VectorXd vertex_areas(const Points& x, const Triangles& f);
/// The area-weighted Gaussian average of the rows of x's `values`,
/// sum_j a_j k(p - x_j) f_j / sum_j a_j k(p - x_j) with k(r) = exp(-|r|^2 / (2 sigma^2)) over the
/// rows within 3 sigma, at the `count` points node(0), ..., node(count - 1) (0 where no row is
/// within reach): the smoothing of the dense iterations' scalars, independent of how the surface
/// is triangulated.
template <class Node>
Eigen::VectorXd gaussian_average(const Points& x, const Eigen::VectorXd& values, const Eigen::VectorXd& area, double sigma,
                                 int count, Node&& node) {
  const double radius = 3 * sigma, inv = 1 / (2 * sigma * sigma);
  const PointBins bins(x, radius);
  Eigen::VectorXd at(count);
  parallel_for(count, 64, [&](int i0, int i1) {
    for (int i = i0; i < i1; ++i) {
      const Eigen::Vector3d p = node(i);
      double num = 0, den = 0;
      bins.visit(p, [&](int j) {
        const double d2 = (x.row(j).transpose() - p).squaredNorm();
        if (d2 > radius * radius) return;
        const double w = area(j) * std::exp(-d2 * inv);
        num += w * values(j);
        den += w;
      });
      at(i) = den > 0 ? num / den : 0;
    }
  });
  return at;
}

/// The area-weighted mean and spread of a scalar (InputError naming `what` when it is constant).
struct Spread {
  double mean = 0, sd = 1;
};
Spread spread(const Eigen::VectorXd& v, const Eigen::VectorXd& area, const char* what);
/// Area-weighted standardisation: mean 0, spread 1 (InputError naming `what` for a constant scalar).
Eigen::VectorXd standardise(const Eigen::VectorXd& v, const Eigen::VectorXd& area, const char* what);
/// Area-weighted correlation of two scalars.
double correlation(const Eigen::VectorXd& a, const Eigen::VectorXd& b, const Eigen::VectorXd& w);
/// The area-weighted mean squared residual.
inline double mismatch(const Eigen::VectorXd& e, const Eigen::VectorXd& area) {
  return area.dot(e.cwiseProduct(e)) / area.sum();
}

/// The levels of `widths` that run: with landmarks (L x 3, their current positions), those
/// narrower than the landmarks' mean nearest-neighbour distance, at least the finest; of those, the
/// ones at least 1.5 of the subject's mean edges wide (`reference`, `faces`), at least the widest.
std::vector<double> dense_widths(const std::vector<double>& widths, const Points& landmarks, const Points& reference,
                                 const Triangles& faces);

/// InputError naming `who` unless every width is in (0, 2], smoothing and max_move positive (max_move
/// at most 1), ridge non-negative, iterations non-negative (all finite).
void check_match_options(const SphereMatchOptions& options, const char* who);

/// The weights a of a step's field: the minimum of sum_i w_i (e_i + J_i a)^2 + mu a^T K a. The
/// first area.size() rows of J are the vertices' (w_i their area shares, e their residuals), the
/// rest hold the field at the landmarks at zero (weighted together 100 x the data term, so the
/// dense steps keep what they matched); mu = ridge x the data term's trace over K's. NumericalError
/// naming `who` when the normal equations cannot be factored.
Eigen::VectorXd gauss_newton_weights(const SparseRows& J, const Eigen::VectorXd& area, const Eigen::VectorXd& e,
                                     const Eigen::SparseMatrix<double>& K, double ridge, const char* who);

/// The restoration (vpm/surface_registration.hpp step 6): when res.points has no flipped face and
/// its face areas miss options.restore_tolerance, at most options.restore_rounds steps of the
/// surface map's polish towards the areas of `reference`, domain.fixed held still; fills
/// res.restore_rounds and res.held_vertices.
void restore_areas(const SurfaceDomainMoves& domain, const Points& reference, const Triangles& faces,
                   const SurfaceRegistrationOptions& options, SurfaceRegistrationResult& res);

/// The index of the point of x at `d` (within 1e-12: a landmark given as a vertex id), or x.size().
template <class V>
size_t vertex_at(const std::vector<V>& x, const V& d) {
  for (size_t i = 0; i < x.size(); ++i)
    if ((x[i] - d).squaredNorm() <= 1e-24) return i;
  return x.size();
}

/// The smallest face area ratio of x against the input's areas `area0`.
double smallest_area_ratio(const Eigen::VectorXd& area0, const Points& x, const Triangles& faces);

/// Whether a move to `after` presses the smallest face area ratio below kCrushedArea and below
/// `least`, the smallest before the move (smallest_area_ratio).
bool crushes(const Eigen::VectorXd& area0, double least, const Points& after, const Triangles& faces);

/// Face areas brought back towards the input's `area0` where the dense steps crushed them: at
/// most `rounds` steps of the surface map's polish (domain.fixed held). Returns whether x moved.
bool relieve_areas(const SurfaceDomainMoves& domain, const Eigen::VectorXd& area0, const Triangles& faces, int rounds, Points& x);

/// Faces flipped at x (slivers sheared past their width) unflipped: each corner of a flipped
/// face, but those domain.fixed holds and the disk's boundary loop, moved part of the way to the
/// mean of its neighbours and put back on the domain, sweeps until none is flipped (at most 50).
/// With the input's face areas `area0`, the part (of kRepairFractions) that leaves the fewest of
/// the corner's faces flipped and, of those, their areas nearest area0 (the least sum of
/// abs(log(area / area0))): a sliver of the input stays near its own area. With `area0` empty,
/// the whole way: the dense steps' repair, which gives a sliver a whole face's area, so that a
/// step sheared that far costs area and is refused (kRepairAreaChange); the area-keeping repair
/// there let the coarse levels run on and drift from the truth. Returns the number of faces
/// found flipped at first; domain.flipped says what is left.
int repair_flips(const SurfaceDomainMoves& domain, const Triangles& f, const Eigen::VectorXd& area0, Points& x);

}  // namespace vpm::detail
