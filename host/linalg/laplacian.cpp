#include "vpm/laplacian.hpp"

#include <Eigen/Geometry>
#include <Eigen/SparseCore>
#include <algorithm>
#include <string>

#include "core/device_alloc.hpp"
#include "linalg/laplacian_device.hpp"
#include "mesh/tet_geometry.hpp"
#include "core/parallel.hpp"
#include "vpm/device.hpp"
#include "vpm/error.hpp"
#include "vpm/topology.hpp"

namespace vpm {

namespace detail {
#include "kernels/cotan_laplacian.clh"  // after tet_geometry.clh (mesh/tet_geometry.hpp)
}  // namespace detail

namespace bc = boost::compute;

namespace {

constexpr int kEdgeEnds[6][2] = {{0, 1}, {0, 2}, {0, 3}, {1, 2}, {1, 3}, {2, 3}};  // cl_edge's order

// The six off-diagonal entries K_ab of tet t and its signed volume (kernels/cotan_laplacian.clh).
inline double tet_weights(const Points& x, const Tets& tets, Eigen::Index t, double w[6]) {
  double e[3][3];
  detail::tet_edges(x, tets, static_cast<int>(t), e);
  return detail::cl_tet_weights(e[0], e[1], e[2], w);
}

void check_tets(int n, const Tets& tets, const char* where) {
  for (Eigen::Index t = 0; t < tets.rows(); ++t)
    for (int c = 0; c < 4; ++c)
      if (tets(t, c) < 0 || tets(t, c) >= n)
        throw InputError(std::string(where) + ": tet " + std::to_string(t) + " has vertex index " +
                         std::to_string(tets(t, c)) + " outside [0, " + std::to_string(n) + ")");
}

}  // namespace

CsrMatrix cotan_laplacian(const Points& x, const Tets& tets) {
  const int n = static_cast<int>(x.rows());
  check_tets(n, tets, "cotan_laplacian");
  std::vector<Eigen::Triplet<double>> trip;
  trip.reserve(static_cast<size_t>(tets.rows()) * 12 + n);
  for (int i = 0; i < n; ++i) trip.emplace_back(i, i, 0.0);
  for (Eigen::Index t = 0; t < tets.rows(); ++t) {
    double w[6];
    tet_weights(x, tets, t, w);
    for (int e = 0; e < 6; ++e) {
      const int i = tets(t, kEdgeEnds[e][0]), j = tets(t, kEdgeEnds[e][1]);
      trip.emplace_back(i, j, w[e]);
      trip.emplace_back(j, i, w[e]);
      trip.emplace_back(i, i, -w[e]);
      trip.emplace_back(j, j, -w[e]);
    }
  }
  CsrMatrix::EigenType k(n, n);
  k.setFromTriplets(trip.begin(), trip.end());
  return CsrMatrix::from_eigen(k);
}

CotanLaplacian::CotanLaplacian(int n, const Tets& tets) : tets_(tets) {
  if (n < 0) throw InputError("CotanLaplacian: negative vertex count");
  check_tets(n, tets, "CotanLaplacian");
  const Incidence inc = vertex_tet_incidence(n, tets);
  // Pattern: each row holds itself and every vertex sharing a tet with it, sorted. Rows are
  // built in a fixed number of contiguous blocks on the host threads and joined in order.
  pattern_.rows = pattern_.cols = n;
  pattern_.row_ptr.assign(n + 1, 0);
  constexpr int kBlocks = 16;
  const int per = (n + kBlocks - 1) / kBlocks;
  std::vector<std::vector<int>> block_cols(kBlocks);
  detail::parallel_for(kBlocks, 2, [&](int b0, int b1) {
    std::vector<int> nb;
    for (int b = b0; b < b1; ++b)
      for (int i = b * per; i < std::min(n, (b + 1) * per); ++i) {
        nb.clear();
        nb.push_back(i);
        for (int k = inc.offset[i]; k < inc.offset[i + 1]; ++k)
          for (int c = 0; c < 4; ++c) nb.push_back(tets(inc.tet_of[k], c));
        std::sort(nb.begin(), nb.end());
        nb.erase(std::unique(nb.begin(), nb.end()), nb.end());
        block_cols[static_cast<size_t>(b)].insert(block_cols[static_cast<size_t>(b)].end(), nb.begin(), nb.end());
        pattern_.row_ptr[i + 1] = static_cast<int>(nb.size());  // the row's length for now
      }
  });
  for (int i = 0; i < n; ++i) pattern_.row_ptr[i + 1] += pattern_.row_ptr[i];
  pattern_.col.reserve(static_cast<size_t>(pattern_.row_ptr[n]));
  for (const std::vector<int>& c : block_cols) pattern_.col.insert(pattern_.col.end(), c.begin(), c.end());
  pattern_.val.assign(pattern_.col.size(), 0.0);
  mass_ = Eigen::VectorXd::Zero(n);
  diag_.resize(n);
  for (int i = 0; i < n; ++i) diag_[i] = pattern_.find(i, i);
  slot_.resize(static_cast<size_t>(tets.rows()) * 12);
  detail::parallel_for(static_cast<int>(tets.rows()), 8192, [&](int t0, int t1) {
    for (int t = t0; t < t1; ++t)
      for (int a = 0; a < 4; ++a)
        for (int q = 0; q < 3; ++q) {
          const int b = q < a ? q : q + 1;
          slot_[12 * static_cast<size_t>(t) + 3 * a + q] = pattern_.find(tets(t, a), tets(t, b));
        }
  });
}

void CotanLaplacian::assemble(Device& device, const Points& x) {
  const int n = num_vertices();
  if (x.rows() != n)
    throw InputError("CotanLaplacian::assemble: " + std::to_string(x.rows()) +
                     " positions for " + std::to_string(n) + " vertices");
  const Eigen::Index m = tets_.rows();
  if (device.is_host() || n == 0) {
    // the kernels' two passes on the host threads: the tets' weights, then each row's gather
    std::vector<double> w(static_cast<size_t>(m) * 6), vol(m);
    detail::parallel_for(static_cast<int>(m), 8192, [&](int t0, int t1) {
      for (int t = t0; t < t1; ++t) vol[t] = tet_weights(x, tets_, t, &w[6 * static_cast<size_t>(t)]);
    });
    const Incidence inc = vertex_tet_incidence(n, tets_);
    detail::parallel_for(n, 8192, [&](int i0, int i1) {
      for (int i = i0; i < i1; ++i)
        detail::cl_assemble_row(i, pattern_.row_ptr.data(), inc.offset.data(), inc.tet_of.data(), tets_.data(),
                                slot_.data(), diag_.data(), w.data(), vol.data(), pattern_.val.data(), mass_.data());
    });
    host_stale_ = false;
    device_ = &device;
    return;
  }
  auto& q = device.cl().queue;
  if (!dev_ || dev_->device != &device) {
    auto fresh = std::make_shared<DeviceState>(device);  // kept only once every buffer exists
    auto& s = *fresh;
    s.device = &device;
    const Incidence inc = vertex_tet_incidence(n, tets_);
    // per tet: 4 ints (tets), 4 (incidence), 12 (slots), 6 doubles (weights), 1 (volume); per
    // vertex 2 ints and 4 doubles; per matrix entry an int and a double
    const unsigned long long mt = static_cast<unsigned long long>(m), nv = static_cast<unsigned long long>(n);
    const unsigned long long bytes = mt * 136 + nv * 40 + pattern_.col.size() * 12;
    detail::allocate_on_device(device, "Laplacian of " + std::to_string(m) + " tets", mt * 48, bytes, [&] {
      s.tets = bc::vector<int>(tets_.data(), tets_.data() + tets_.size(), q);
      s.row_ptr = bc::vector<int>(pattern_.row_ptr.begin(), pattern_.row_ptr.end(), q);
      s.col = bc::vector<int>(pattern_.col.begin(), pattern_.col.end(), q);
      s.inc_offset = bc::vector<int>(inc.offset.begin(), inc.offset.end(), q);
      s.inc_tet = bc::vector<int>(std::max<size_t>(inc.tet_of.size(), 1), device.cl().context);
      if (!inc.tet_of.empty()) bc::copy(inc.tet_of.begin(), inc.tet_of.end(), s.inc_tet.begin(), q);
      s.slot = bc::vector<int>(std::max<size_t>(slot_.size(), 1), device.cl().context);
      if (!slot_.empty()) bc::copy(slot_.begin(), slot_.end(), s.slot.begin(), q);
      s.diag = bc::vector<int>(diag_.begin(), diag_.end(), q);
      s.x = bc::vector<double>(static_cast<size_t>(n) * 3, device.cl().context);
      s.w = bc::vector<double>(std::max<size_t>(static_cast<size_t>(m) * 6, 1), device.cl().context);
      s.vol = bc::vector<double>(std::max<size_t>(static_cast<size_t>(m), 1), device.cl().context);
      s.val = bc::vector<double>(std::max<size_t>(pattern_.col.size(), 1), device.cl().context);
      s.mass = bc::vector<double>(static_cast<size_t>(n), device.cl().context);
    });
    s.k_weights = device.cl().kernel("laplacian", "tet_weights");
    s.k_rows = device.cl().kernel("laplacian", "assemble_rows");
    s.k_weights.set_args(static_cast<int>(m), s.x, s.tets, s.w, s.vol);
    s.k_rows.set_args(n, s.row_ptr, s.inc_offset, s.inc_tet, s.tets, s.slot, s.diag, s.w, s.vol,
                      s.val, s.mass);
    dev_ = fresh;
  }
  auto& s = *dev_;
  bc::copy(x.data(), x.data() + x.size(), s.x.begin(), q);
  if (m > 0) device.cl().launch(s.k_weights, static_cast<size_t>(m));
  device.cl().launch(s.k_rows, static_cast<size_t>(n));
  device_ = &device;
  host_stale_ = true;
}

void CotanLaplacian::download() const {
  if (!host_stale_) return;
  auto& q = dev_->device->cl().queue;
  if (!pattern_.val.empty())
    bc::copy(dev_->val.begin(), dev_->val.begin() + pattern_.val.size(), pattern_.val.begin(), q);
  if (mass_.size() > 0) bc::copy(dev_->mass.begin(), dev_->mass.end(), mass_.data(), q);
  host_stale_ = false;
}

const CsrMatrix& CotanLaplacian::matrix() const {
  download();
  return pattern_;
}

const Eigen::VectorXd& CotanLaplacian::mass() const {
  download();
  return mass_;
}

namespace {
[[noreturn]] void no_device_values() {
  throw std::logic_error("CotanLaplacian: device buffers requested but no OpenCL assemble ran");
}
}  // namespace

CotanLaplacian::DeviceState& CotanLaplacian::device_state() {
  if (!dev_) no_device_values();
  return *dev_;
}

}  // namespace vpm
