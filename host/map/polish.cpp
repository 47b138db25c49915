#include "map/polish.hpp"

#include <Eigen/Dense>
#include <boost/compute/algorithm/copy.hpp>
#include <boost/compute/algorithm/fill.hpp>
#include <boost/compute/container/vector.hpp>
#include <algorithm>
#include <cmath>
#include <map>

#include "core/device_cl.hpp"
#include "map/polish_cgls.hpp"
#include "vpm/device.hpp"

namespace vpm::detail {

namespace bc = boost::compute;

std::vector<char> polish_freedom(const std::vector<char>& boundary, bool slide, const std::vector<char>& pinned) {
  std::vector<char> f(boundary.size(), kPolishFree);
  for (size_t v = 0; v < boundary.size(); ++v) {
    if (!pinned.empty() && pinned[v]) f[v] = kPolishFixed;
    else if (boundary[v]) f[v] = slide ? kPolishTangent : kPolishFixed;
  }
  return f;
}

AnchorGroups anchor_groups(const std::vector<VolumeAnchor>& anchors) {
  // union-find over anchors through their vertices
  const int a_n = static_cast<int>(anchors.size());
  std::vector<int> parent(static_cast<size_t>(a_n));
  for (int a = 0; a < a_n; ++a) parent[static_cast<size_t>(a)] = a;
  auto root = [&](int a) {
    while (parent[static_cast<size_t>(a)] != a) a = parent[static_cast<size_t>(a)];
    return a;
  };
  std::map<int, int> owner;  // vertex -> an anchor using it
  for (int a = 0; a < a_n; ++a)
    for (int v : anchors[static_cast<size_t>(a)].vertices) {
      const auto [it, fresh] = owner.emplace(v, a);
      if (!fresh) parent[static_cast<size_t>(root(a))] = root(it->second);
    }
  std::map<int, std::vector<int>> members;  // root -> anchors, in order
  for (int a = 0; a < a_n; ++a) members[root(a)].push_back(a);
  AnchorGroups g;
  for (const auto& [r, list] : members) {
    std::vector<int> verts;
    for (int a : list)
      for (int v : anchors[static_cast<size_t>(a)].vertices) verts.push_back(v);
    std::sort(verts.begin(), verts.end());
    verts.erase(std::unique(verts.begin(), verts.end()), verts.end());
    const int k = static_cast<int>(verts.size());
    Eigen::MatrixXd W = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(list.size()), k);
    for (size_t i = 0; i < list.size(); ++i) {
      const VolumeAnchor& an = anchors[static_cast<size_t>(list[i])];
      for (int c = 0; c < 4; ++c) {
        const auto at = std::lower_bound(verts.begin(), verts.end(), an.vertices[static_cast<size_t>(c)]) - verts.begin();
        W(static_cast<Eigen::Index>(i), at) += an.weights[static_cast<size_t>(c)];
      }
    }
    // P = I - W^+ W: the orthogonal projector onto the null space of W (rank-revealing, so
    // anchors at the same point do not break it)
    const Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd> cod(W);
    const Eigen::MatrixXd P = Eigen::MatrixXd::Identity(k, k) - cod.pseudoInverse() * W;
    g.offset.push_back(static_cast<int>(g.matrix.size()));
    for (int i = 0; i < k; ++i)
      for (int j = 0; j < k; ++j) g.matrix.push_back(P(i, j));
    g.vertices.insert(g.vertices.end(), verts.begin(), verts.end());
    g.ptr.push_back(static_cast<int>(g.vertices.size()));
  }
  return g;
}

// ---- OpenCL ----------------------------------------------------------------------------------

// polish_cgls's OpenCL backend: the vectors in device buffers, the scalars in S on the device,
// every call a kernel launch (the sums stay there as partials that polish_scalars combines).
struct DevicePolisher::Impl {
  Device& dev;
  int n, m;
  int rows;  // m volume rows, then the holds' rows
  size_t G;  // reduction grid
  bc::vector<int> tets, inc_ptr, inc_slot, anchor, anchor_row, group_ptr, group_vertex, group_offset;
  bc::vector<double> group_matrix;
  bc::vector<char> freedom;
  bc::vector<double> x, target, sg, b, r, q, dx, p, s, partial, S;
  bc::kernel k_setup, k_apply, k_start, k_recur, k_scalars, k_update_p, k_apply_dx, k_residual;
  Impl(Device& d, int n_, int m_, int rows_)
      : dev(d), n(n_), m(m_), rows(rows_), tets(d.cl().context), inc_ptr(d.cl().context), inc_slot(d.cl().context),
        anchor(d.cl().context), anchor_row(d.cl().context), group_ptr(d.cl().context), group_vertex(d.cl().context), group_offset(d.cl().context),
        group_matrix(d.cl().context),
        freedom(d.cl().context), x(d.cl().context), target(d.cl().context), sg(d.cl().context), b(d.cl().context),
        r(d.cl().context), q(d.cl().context), dx(d.cl().context), p(d.cl().context), s(d.cl().context),
        partial(d.cl().context), S(d.cl().context) {}
  void scalars(int op) {
    k_scalars.set_arg(1, op);
    dev.cl().launch(k_scalars, dev.combine_items());
  }
  void start() { dev.cl().launch(k_start, G); }       // s = P A^T b; |s|^2, |b|^2
  void apply() { dev.cl().launch(k_apply, G); }       // q = A p; |q|^2
  void update() { dev.cl().launch(k_recur, G); }      // s -= alpha P A^T q, dx += alpha p; |s|^2
  void update_p() { dev.cl().launch(k_update_p, G); } // p = s + beta p
  bool stopped() const { return false; }              // never waits for the device
  PolishDirection result();
  void make_kernels();
};

namespace {

// The rows of A on the device: the m tets, then one row per hold, which has the shape of a tet's
// row (four vertices, a 3-vector each: its weight times its direction, right-hand side 0), so
// the kernels apply both alike. Returns the rows' vertices (4 per row) and the holds' part of sg.
std::pair<std::vector<int>, std::vector<double>> rows_with_holds(const Tets& tets, const std::vector<VolumeHold>& holds) {
  const size_t m = static_cast<size_t>(tets.rows());
  std::vector<int> v(4 * (m + holds.size()));
  for (size_t t = 0; t < m; ++t)
    for (int k = 0; k < 4; ++k) v[4 * t + k] = tets(static_cast<Eigen::Index>(t), k);
  std::vector<double> g(12 * holds.size());
  for (size_t h = 0; h < holds.size(); ++h)
    for (size_t k = 0; k < 4; ++k) {
      v[4 * (m + h) + k] = holds[h].vertices[k];
      for (int c = 0; c < 3; ++c) g[12 * h + 3 * k + c] = holds[h].weights[k] * holds[h].direction(c);
    }
  return {std::move(v), std::move(g)};
}

}  // namespace

DevicePolisher::DevicePolisher(Device& dev, const Tets& tets, int n, const std::vector<char>& freedom,
                               const std::vector<VolumeAnchor>& anchors, const std::vector<VolumeHold>& holds) {
  const int m = static_cast<int>(tets.rows()), rows = m + static_cast<int>(holds.size());
  impl_ = std::make_unique<Impl>(dev, n, m, rows);
  Impl& I = *impl_;
  auto& queue = dev.cl().queue;
  const bool cpu = dev.description().kind == DeviceKind::cpu;
  const size_t ls = dev.local_size();
  const unsigned cu = std::max(1u, dev.description().compute_units);
  I.G = cpu ? ls * std::max<size_t>(4, 2 * cu) : ls * std::max<size_t>(64, 4 * cu);
  // vertex -> row-corner slots (4 t + k) of the tets' and the holds' rows, CSR
  const auto [row_vertex, hold_sg] = rows_with_holds(tets, holds);
  std::vector<int> ptr(static_cast<size_t>(n) + 1, 0), slot(4 * static_cast<size_t>(rows));
  for (int j = 0; j < 4 * rows; ++j) ++ptr[static_cast<size_t>(row_vertex[static_cast<size_t>(j)]) + 1];
  for (int v = 0; v < n; ++v) ptr[v + 1] += ptr[v];
  std::vector<int> fill(ptr.begin(), ptr.end() - 1);
  for (int j = 0; j < 4 * rows; ++j) slot[static_cast<size_t>(fill[row_vertex[static_cast<size_t>(j)]]++)] = j;
  I.tets = bc::vector<int>(row_vertex.begin(), row_vertex.end(), queue);
  I.inc_ptr = bc::vector<int>(ptr.begin(), ptr.end(), queue);
  I.inc_slot = bc::vector<int>(slot.begin(), slot.end(), queue);
  // anchors: kPolishAnchored on their vertices, vertex -> its group and its row there; every buffer gets
  // at least one entry so that it exists
  const AnchorGroups groups = anchor_groups(anchors);
  std::vector<char> flags = freedom;
  std::vector<int> anchor_of(static_cast<size_t>(std::max(n, 1)), -1), row_of(anchor_of.size(), 0);
  for (int gi = 0; gi < groups.groups(); ++gi) {
    const int b = groups.ptr[static_cast<size_t>(gi)], k = groups.ptr[static_cast<size_t>(gi) + 1] - b;
    for (int i = 0; i < k; ++i) {
      const auto v = static_cast<size_t>(groups.vertices[static_cast<size_t>(b + i)]);
      flags[v] = kPolishAnchored;
      anchor_of[v] = gi;
      row_of[v] = i;
    }
  }
  auto at_least_one = [](auto v) {
    if (v.empty()) v.resize(1);
    return v;
  };
  I.freedom = bc::vector<char>(flags.begin(), flags.end(), queue);
  I.anchor = bc::vector<int>(anchor_of.begin(), anchor_of.end(), queue);
  I.anchor_row = bc::vector<int>(row_of.begin(), row_of.end(), queue);
  const auto gv = at_least_one(groups.vertices), go = at_least_one(groups.offset);
  const auto gm = at_least_one(groups.matrix);
  I.group_ptr = bc::vector<int>(groups.ptr.begin(), groups.ptr.end(), queue);
  I.group_vertex = bc::vector<int>(gv.begin(), gv.end(), queue);
  I.group_offset = bc::vector<int>(go.begin(), go.end(), queue);
  I.group_matrix = bc::vector<double>(gm.begin(), gm.end(), queue);
  const size_t n3 = 3 * static_cast<size_t>(std::max(n, 1)), mm = static_cast<size_t>(std::max(rows, 1));
  I.x = bc::vector<double>(n3, dev.cl().context);
  I.target = bc::vector<double>(mm, dev.cl().context);
  I.sg = bc::vector<double>(12 * mm, dev.cl().context);
  I.b = bc::vector<double>(mm, dev.cl().context);
  I.r = bc::vector<double>(mm, dev.cl().context);
  I.q = bc::vector<double>(mm, dev.cl().context);
  I.dx = bc::vector<double>(n3, dev.cl().context);
  I.p = bc::vector<double>(n3, dev.cl().context);
  I.s = bc::vector<double>(n3, dev.cl().context);
  I.partial = bc::vector<double>(2 * I.G, dev.cl().context);
  I.S = bc::vector<double>(P_SLOTS, dev.cl().context);
  for (auto* v : {&I.x, &I.target, &I.sg, &I.b, &I.r, &I.q, &I.dx, &I.p, &I.s, &I.partial, &I.S})
    bc::fill(v->begin(), v->end(), 0.0, queue);
  if (!hold_sg.empty()) bc::copy(hold_sg.begin(), hold_sg.end(), I.sg.begin() + 12 * static_cast<size_t>(m), queue);

  I.make_kernels();
}

DevicePolisher::~DevicePolisher() = default;

// The kernels with their arguments bound (the buffers exist).
void DevicePolisher::Impl::make_kernels() {
  auto& cl = dev.cl();
  k_setup = cl.kernel("polish", "polish_setup");
  k_setup.set_args(m, tets, x, target, sg, b, r);
  k_apply = cl.kernel("polish", "polish_apply");
  k_apply.set_args(rows, tets, sg, p, q, partial);
  // the start reads y = r (b on the tets' rows, 0 on the holds'), the iterations y = q
  k_start = cl.kernel("polish", "polish_apply_t");
  k_start.set_args(n, m, inc_ptr, inc_slot, sg, r, freedom, x, s, partial, anchor, anchor_row, group_ptr,
                   group_vertex, group_offset, group_matrix, 0, S, dx, p);
  k_recur = cl.kernel("polish", "polish_apply_t");
  k_recur.set_args(n, m, inc_ptr, inc_slot, sg, q, freedom, x, s, partial, anchor, anchor_row, group_ptr,
                   group_vertex, group_offset, group_matrix, 1, S, dx, p);
  k_apply_dx = cl.kernel("polish", "polish_apply");  // q = A dx, for the final residual
  k_apply_dx.set_args(rows, tets, sg, dx, q, partial);
  k_residual = cl.kernel("polish", "polish_residual");
  k_residual.set_args(m, b, q, partial);
  k_scalars = cl.kernel("polish", "polish_scalars");
  k_scalars.set_arg(0, static_cast<int>(dev.reduction_partials(G)));
  set_args_at(k_scalars, 2, partial, S);
  k_update_p = cl.kernel("polish", "polish_update_p");
  k_update_p.set_args(3 * n, S, p, s);
}

PolishDirection DevicePolisher::Impl::result() {
  auto& queue = dev.cl().queue;
  dev.cl().launch(k_apply_dx, G);  // q = A dx
  dev.cl().launch(k_residual, G);  // |b - q|^2
  scalars(P_OP_RR);
  PolishDirection res;
  res.dx = Points::Zero(n, 3);
  bc::copy(dx.begin(), dx.begin() + 3 * static_cast<size_t>(n), res.dx.data(), queue);
  double sc[P_SLOTS];
  bc::copy(S.begin(), S.end(), sc, queue);
  res.iterations = static_cast<int>(sc[P_ITER]);
  res.residual = sc[P_BB] > 0 ? std::sqrt(sc[P_RR] / sc[P_BB]) : 0;
  return res;
}

std::unique_ptr<Polisher> make_polisher(Device& device, bool on_device, const Tets& tets, int num_vertices,
                                        const std::vector<char>& freedom, const std::vector<VolumeAnchor>& anchors,
                                        const std::vector<VolumeHold>& holds) {
  if (on_device && !device.is_host())
    return std::make_unique<DevicePolisher>(device, tets, num_vertices, freedom, anchors, holds);
  return std::make_unique<HostPolisher>(tets, freedom, anchors, holds);
}

PolishDirection DevicePolisher::direction(const Points& x, const Eigen::VectorXd& target, int iterations) {
  Impl& I = *impl_;
  auto& queue = I.dev.cl().queue;
  if (I.n == 0 || I.m == 0) {
    PolishDirection none;
    none.dx = Points::Zero(I.n, 3);
    return none;
  }
  bc::copy(x.data(), x.data() + 3 * static_cast<size_t>(I.n), I.x.begin(), queue);
  bc::copy(target.data(), target.data() + I.m, I.target.begin(), queue);
  bc::fill(I.dx.begin(), I.dx.end(), 0.0, queue);
  if (I.rows > I.m) bc::fill(I.r.begin() + I.m, I.r.begin() + I.rows, 0.0, queue);  // the holds' residuals
  I.dev.cl().launch(I.k_setup, static_cast<size_t>(I.m));  // sg, b, r = b of the tets' rows
  return polish_cgls(I, iterations);
}

}  // namespace vpm::detail
