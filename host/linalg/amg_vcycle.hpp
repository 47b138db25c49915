#pragma once
// Private: the smoothed-aggregation V-cycle written once over a backend (as linalg/krylov.hpp's
// solvers): AmgHierarchy::apply (host/linalg/amg.cpp) runs it over loops on the hierarchy's CSR
// levels, ClAmg::apply (host/linalg/amg_device.cpp) over the kernels of kernels/amg.cl.
#include <utility>

namespace vpm::detail {

/// One V-cycle from a zero start on level l: out = M_l^-1 f. `f` and `out` are distinct.
///
/// A backend BK has a vector handle `BK::Vec` (copied and swapped freely) and, on level l with
/// matrix A, smoother diagonal d, restriction R and prolongation P:
/// - `levels()`, `sweeps()`: the hierarchy's depth and its smoothing sweeps (>= 1);
/// - `work(l, x, r, t)`: three distinct scratch vectors of level l's length;
/// - `coarse_vectors(l, f, out)`: the right-hand side and solution vectors of level l (l >= 1);
/// - `first(l, f, x, r)`: x = d f, then r = f - A x (one sweep from zero and its residual);
/// - `scale(l, f, x)`: x = d f;
/// - `sweep(l, f, in, o)`: o = in + d (f - A in), o != in;
/// - `residual(l, f, x, r)`: r = f - A x;
/// - `restrict_to(l, r, fc)`: fc = R r (fc of level l + 1);
/// - `prolong(l, xc, x, t)`: t = x + P xc;
/// - `coarse(l, f, out)`: out = M f with the coarsest level's dense (pseudo-)inverse M.
template <class BK>
void amg_vcycle(BK& bk, int l, typename BK::Vec f, typename BK::Vec out) {
  using Vec = typename BK::Vec;
  if (l + 1 == bk.levels()) {
    bk.coarse(l, f, out);
    return;
  }
  Vec x, r, t;
  bk.work(l, x, r, t);
  if (bk.sweeps() == 1) {
    bk.first(l, f, x, r);
  } else {
    bk.scale(l, f, x);
    for (int s = 1; s < bk.sweeps(); ++s) {
      bk.sweep(l, f, x, t);
      std::swap(x, t);
    }
    bk.residual(l, f, x, r);
  }
  Vec fc, xc;
  bk.coarse_vectors(l + 1, fc, xc);
  bk.restrict_to(l, r, fc);
  amg_vcycle(bk, l + 1, fc, xc);
  bk.prolong(l, xc, x, t);
  for (int s = 1; s < bk.sweeps(); ++s) {
    bk.sweep(l, f, t, r);
    std::swap(t, r);
  }
  bk.sweep(l, f, t, out);
}

}  // namespace vpm::detail
