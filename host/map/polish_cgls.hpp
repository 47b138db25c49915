#pragma once
// Private: the polish direction's CGLS (map/polish.hpp), written once over a backend. From dx = 0,
// min |A dx - b|^2 (the tets' linearised relative volumes and the holds' rows) over the projected
// moves dx = P dx, early-stopped after `iterations` (the minimum-norm start is the regularisation).
// The host backend (polish_host.cpp) runs it on the host threads, the OpenCL one (polish.cpp,
// DevicePolisher) on the kernels of kernels/polish.cl; both advance the iteration's scalars with
// pl_scalars (kernels/polish_cgls.clh), on their own side.
//
// The tet backends carry the gradient s = P A^T (b - A dx) by its recurrence s -= alpha P A^T A p
// (CG on the normal equations) rather than recompute it from the residual: an iteration then reads
// each row of A once on the host (q = A p and A^T q in one pass over the tets), where the residual
// form reads them twice and updates an m-vector besides; their residual is formed once, at the
// end. The surface backend (surface_polish.cpp) keeps the residual form behind the same calls.
//
// A backend BK, prepared with the rows of A and b, with dx = 0, provides:
//   start()        s = P A^T b, and the sums |s|^2 and |b|^2 (the tets' rows) for scalars()
//   apply()        q = A p and the sum |q|^2 (all rows)
//   scalars(op)    pl_scalars(op, ...) on the last sums (P_OP_INIT, P_OP_ALPHA, P_OP_BETA)
//   update()       dx += alpha p, the new s (s -= alpha P A^T q, or P A^T r after r -= alpha q)
//                  and the sum |s|^2
//   update_p()     p = s + beta p (p = s while beta is 0)
//   stopped()      whether S[P_STOP] is set; a device answers false rather than wait for it (its
//                  iterations then change nothing: alpha is 0)
//   result()       dx, the iterations done and |b - A dx| / |b| (the tets' rows)
#include <cmath>

#include "map/polish.hpp"
#include "mesh/tet_geometry.hpp"  // `real`

namespace vpm::detail {

#include "kernels/polish_cgls.clh"

template <class BK>
PolishDirection polish_cgls(BK& bk, int iterations) {
  bk.start();
  bk.scalars(P_OP_INIT);
  bk.update_p();
  for (int it = 0; it < iterations && !bk.stopped(); ++it) {
    bk.apply();
    bk.scalars(P_OP_ALPHA);
    if (bk.stopped()) break;
    bk.update();
    bk.scalars(P_OP_BETA);
    bk.update_p();
  }
  return bk.result();
}

}  // namespace vpm::detail
