// Smoothed-aggregation multigrid hierarchy and the host backend of its V-cycle (vpm/amg.hpp,
// linalg/amg_vcycle.hpp). The coarse
// (pseudo-)inverse is in amg_coarse.cpp.
#include "vpm/amg.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "linalg/amg_coarse.hpp"
#include "linalg/amg_vcycle.hpp"
#include "linalg/csr_ops.hpp"
#include "vpm/error.hpp"

namespace vpm {

using detail::csr_transpose;
using detail::spgemm_pattern;
using detail::spgemm_values;

struct AmgHierarchy::Setup {
  std::vector<char> strong;  // per entry of A: off-diagonal, both rows active, strong
  std::vector<int> agg;      // aggregate of each row, -1: none
  CsrMatrix AP;              // pattern (and scratch values) of A P
};

namespace {

// Active rows: not fixed and with a non-zero diagonal.
std::vector<char> active_rows(const CsrMatrix& a, const std::vector<char>& fixed) {
  std::vector<char> act(a.rows, 1);
  const Eigen::VectorXd dia = a.diagonal();
  for (int i = 0; i < a.rows; ++i) act[i] = (fixed.empty() || !fixed[i]) && dia[i] != 0.0;
  return act;
}

std::vector<char> strength(const CsrMatrix& a, const std::vector<char>& act, double eps) {
  const Eigen::VectorXd dia = a.diagonal();
  std::vector<char> s(a.nnz(), 0);
  for (int i = 0; i < a.rows; ++i) {
    if (!act[i]) continue;
    for (int k = a.row_ptr[i]; k < a.row_ptr[i + 1]; ++k) {
      const int j = a.col[k];
      s[k] = j != i && act[j] && std::abs(a.val[k]) >= eps * std::sqrt(std::abs(dia[i] * dia[j]));
    }
  }
  return s;
}

// Greedy aggregation in three passes; returns the number of aggregates.
int aggregate(const CsrMatrix& a, const std::vector<char>& strong, std::vector<int>& agg) {
  const int n = a.rows;
  agg.assign(n, -1);
  auto has_strong = [&](int i) {
    for (int k = a.row_ptr[i]; k < a.row_ptr[i + 1]; ++k)
      if (strong[k]) return true;
    return false;
  };
  int count = 0;
  for (int i = 0; i < n; ++i) {  // 1: roots whose strong neighbours are all free
    if (agg[i] >= 0 || !has_strong(i)) continue;
    bool free = true;
    for (int k = a.row_ptr[i]; k < a.row_ptr[i + 1] && free; ++k)
      if (strong[k] && agg[a.col[k]] >= 0) free = false;
    if (!free) continue;
    agg[i] = count;
    for (int k = a.row_ptr[i]; k < a.row_ptr[i + 1]; ++k)
      if (strong[k]) agg[a.col[k]] = count;
    ++count;
  }
  const std::vector<int> first = agg;
  for (int i = 0; i < n; ++i) {  // 2: attach to the strongest neighbouring aggregate
    if (agg[i] >= 0) continue;
    double best = -1;
    for (int k = a.row_ptr[i]; k < a.row_ptr[i + 1]; ++k)
      if (strong[k] && first[a.col[k]] >= 0 && std::abs(a.val[k]) > best) {
        best = std::abs(a.val[k]);
        agg[i] = first[a.col[k]];
      }
  }
  for (int i = 0; i < n; ++i) {  // 3: leftovers group with their free strong neighbours
    if (agg[i] >= 0 || !has_strong(i)) continue;
    agg[i] = count;
    for (int k = a.row_ptr[i]; k < a.row_ptr[i + 1]; ++k)
      if (strong[k] && agg[a.col[k]] < 0) agg[a.col[k]] = count;
    ++count;
  }
  return count;
}

// Pattern of P = (I - omega D^-1 A_f) P_tent: row i holds the aggregates of i and of its strong
// neighbours.
CsrMatrix prolongation_pattern(const CsrMatrix& a, const std::vector<char>& strong,
                               const std::vector<int>& agg, int nc) {
  CsrMatrix p;
  p.rows = a.rows;
  p.cols = nc;
  p.row_ptr.assign(a.rows + 1, 0);
  for (int i = 0; i < a.rows; ++i) {
    const size_t start = p.col.size();
    if (agg[i] >= 0) p.col.push_back(agg[i]);
    for (int k = a.row_ptr[i]; k < a.row_ptr[i + 1]; ++k)
      if (strong[k] && agg[a.col[k]] >= 0) p.col.push_back(agg[a.col[k]]);
    std::sort(p.col.begin() + start, p.col.end());
    p.col.erase(std::unique(p.col.begin() + start, p.col.end()), p.col.end());
    p.row_ptr[i + 1] = static_cast<int>(p.col.size());
  }
  p.val.assign(p.col.size(), 0.0);
  return p;
}

// Values of the smoothed prolongation into p's pattern. A_f: strong entries kept, weak
// off-diagonal entries between active rows lumped into the diagonal, inactive columns dropped.
void prolongation_values(const CsrMatrix& a, const std::vector<char>& act,
                         const std::vector<char>& strong, const std::vector<int>& agg, CsrMatrix& p) {
  const int n = a.rows;
  std::vector<double> dia(n, 0.0);
  double rho = 0;  // Gershgorin bound of rho(D_f^-1 A_f)
  for (int i = 0; i < n; ++i) {
    if (!act[i]) continue;
    double d = 0, off = 0;
    for (int k = a.row_ptr[i]; k < a.row_ptr[i + 1]; ++k) {
      const int j = a.col[k];
      if (j == i || (!strong[k] && act[j])) d += a.val[k];
      else if (strong[k]) off += std::abs(a.val[k]);
    }
    dia[i] = d;
    if (d != 0) rho = std::max(rho, (std::abs(d) + off) / std::abs(d));
  }
  const double omega = rho > 0 ? (4.0 / 3.0) / rho : 0.0;
  for (int i = 0; i < n; ++i) {
    const int b = p.row_ptr[i], e = p.row_ptr[i + 1];
    auto slot = [&](int c) { return int(std::lower_bound(p.col.begin() + b, p.col.begin() + e, c) - p.col.begin()); };
    for (int q = b; q < e; ++q) p.val[q] = 0.0;
    if (b == e) continue;
    if (agg[i] >= 0) p.val[slot(agg[i])] += 1.0;
    if (dia[i] == 0) continue;
    const double s = -omega / dia[i];
    p.val[slot(agg[i])] += s * dia[i];
    for (int k = a.row_ptr[i]; k < a.row_ptr[i + 1]; ++k)
      if (strong[k] && agg[a.col[k]] >= 0) p.val[slot(agg[a.col[k]])] += s * a.val[k];
  }
}

std::vector<double> smoother_diagonal(const CsrMatrix& a, const std::vector<char>& act,
                                      const AmgOptions& o) {
  std::vector<double> d(a.rows, 0.0);
  for (int i = 0; i < a.rows; ++i) {
    if (!act[i]) continue;
    double dia = 0, sq = 0;
    for (int k = a.row_ptr[i]; k < a.row_ptr[i + 1]; ++k) {
      if (a.col[k] == i) dia = a.val[k];
      if (act[a.col[k]]) sq += a.val[k] * a.val[k];
    }
    d[i] = o.smoother == AmgSmoother::spai0 ? (sq > 0 ? dia / sq : 0.0) : o.jacobi_weight / dia;
  }
  return d;
}

}  // namespace

AmgHierarchy::AmgHierarchy(const CsrMatrix& a, const std::vector<char>& fixed, AmgOptions options)
    : options_(options), fixed_(fixed) {
  if (a.rows != a.cols) throw InputError("AmgHierarchy: matrix is not square");
  if (!fixed_.empty() && static_cast<int>(fixed_.size()) != a.rows)
    throw InputError("AmgHierarchy: fixed mask has length " + std::to_string(fixed_.size()) +
                     ", expected " + std::to_string(a.rows));
  levels_.push_back({a, {}, {}, {}});
  double eps = options_.strength;
  std::vector<int> pos;
  while (levels_.back().A.rows > options_.coarse_size && num_levels() < options_.max_levels) {
    const int l = num_levels() - 1;
    AmgLevel& lv = levels_.back();
    const std::vector<char> act = active_rows(lv.A, l == 0 ? fixed_ : std::vector<char>{});
    Setup s;
    s.strong = strength(lv.A, act, eps);
    const int nc = aggregate(lv.A, s.strong, s.agg);
    if (nc == 0 || nc >= lv.A.rows) break;
    lv.P = prolongation_pattern(lv.A, s.strong, s.agg, nc);
    s.AP = spgemm_pattern(lv.A, lv.P);
    AmgLevel next;
    next.A = spgemm_pattern(csr_transpose(lv.P), s.AP);
    setup_.push_back(std::move(s));
    levels_.push_back(std::move(next));
    level_values(l, pos);  // the next level's strength test needs its values
    eps *= 0.5;
  }
  finish_values();
}

AmgHierarchy::~AmgHierarchy() = default;
AmgHierarchy::AmgHierarchy(AmgHierarchy&&) noexcept = default;
AmgHierarchy& AmgHierarchy::operator=(AmgHierarchy&&) noexcept = default;

void AmgHierarchy::update_values(const CsrMatrix& a) {
  const CsrMatrix& a0 = levels_[0].A;
  if (a.rows != a0.rows || a.row_ptr != a0.row_ptr || a.col != a0.col)
    throw InputError("AmgHierarchy::update_values: the pattern differs from the construction's");
  levels_[0].A.val = a.val;
  compute_values();
}

void AmgHierarchy::level_values(int l, std::vector<int>& pos) {
  AmgLevel& lv = levels_[l];
  const std::vector<char> act = active_rows(lv.A, l == 0 ? fixed_ : std::vector<char>{});
  Setup& s = setup_[l];
  lv.d = smoother_diagonal(lv.A, act, options_);
  prolongation_values(lv.A, act, s.strong, s.agg, lv.P);
  lv.R = csr_transpose(lv.P);
  spgemm_values(lv.A, lv.P, s.AP, pos);
  spgemm_values(lv.R, s.AP, levels_[l + 1].A, pos);
}

void AmgHierarchy::finish_values() {
  const AmgLevel& last = levels_.back();
  coarse_inv_ = detail::coarse_pseudo_inverse(
      last.A, active_rows(last.A, num_levels() == 1 ? fixed_ : std::vector<char>{}));
  work_.resize(num_levels());
  for (int l = 0; l < num_levels(); ++l) work_[l].assign(5 * size_t(levels_[l].A.rows), 0.0);
}

void AmgHierarchy::compute_values() {
  std::vector<int> pos;
  for (int l = 0; l + 1 < num_levels(); ++l) level_values(l, pos);
  finish_values();
}

double AmgHierarchy::operator_complexity() const {
  double s = 0;
  for (const auto& lv : levels_) s += lv.A.nnz();
  return s / std::max(1, levels_[0].A.nnz());
}

namespace {

// amg_vcycle's backend on the host: loops over the levels' CSR matrices, vectors as pointers
// into the hierarchy's work vectors (per level: f, out, x, r, t).
struct HostAmgBackend {
  using Vec = double*;
  const std::vector<AmgLevel>& lv;
  std::vector<std::vector<double>>& vectors;  // per level: f, out, x, r, t
  const Eigen::MatrixXd& coarse_inv;
  int nsweeps;

  int levels() const { return static_cast<int>(lv.size()); }
  int sweeps() const { return nsweeps; }
  int rows(int l) const { return lv[l].A.rows; }
  void work_vectors(int l, Vec& f, Vec& out, Vec& x, Vec& r, Vec& t) const {
    const size_t n = static_cast<size_t>(rows(l));
    f = vectors[l].data();
    out = f + n;
    x = out + n;
    r = x + n;
    t = r + n;
  }
  void work(int l, Vec& x, Vec& r, Vec& t) const {
    Vec f, out;
    work_vectors(l, f, out, x, r, t);
  }
  void coarse_vectors(int l, Vec& f, Vec& out) const {
    Vec x, r, t;
    work_vectors(l, f, out, x, r, t);
  }
  // y = b - M v (Subtract: a residual) or y = b + M v (a correction; b null: 0) over M's rows
  template <bool Subtract>
  static void row_products(const CsrMatrix& m, const double* b, const double* v, double* y) {
    for (int i = 0; i < m.rows; ++i) {
      double s = b ? b[i] : 0.0;
      for (int k = m.row_ptr[i]; k < m.row_ptr[i + 1]; ++k) {
        if constexpr (Subtract)
          s -= m.val[k] * v[m.col[k]];
        else
          s += m.val[k] * v[m.col[k]];
      }
      y[i] = s;
    }
  }
  void scale(int l, const double* f, double* x) const {
    for (int i = 0; i < rows(l); ++i) x[i] = lv[l].d[i] * f[i];
  }
  void residual(int l, const double* f, const double* x, double* r) const { row_products<true>(lv[l].A, f, x, r); }
  void first(int l, const double* f, double* x, double* r) const {
    scale(l, f, x);
    residual(l, f, x, r);
  }
  void sweep(int l, const double* f, const double* in, double* o) const {
    const CsrMatrix& A = lv[l].A;
    const std::vector<double>& d = lv[l].d;
    for (int i = 0; i < A.rows; ++i) {
      double s = f[i];
      for (int k = A.row_ptr[i]; k < A.row_ptr[i + 1]; ++k) s -= A.val[k] * in[A.col[k]];
      o[i] = in[i] + d[i] * s;
    }
  }
  void restrict_to(int l, const double* r, double* fc) const { row_products<false>(lv[l].R, nullptr, r, fc); }
  void prolong(int l, const double* xc, const double* x, double* t) const { row_products<false>(lv[l].P, x, xc, t); }
  void coarse(int l, const double* f, double* out) const {
    Eigen::Map<const Eigen::VectorXd> ff(f, rows(l));
    Eigen::Map<Eigen::VectorXd>(out, rows(l)).noalias() = coarse_inv * ff;
  }
};

}  // namespace

void AmgHierarchy::apply(const double* r, double* z) const {
  HostAmgBackend bk{levels_, work_, coarse_inv_, options_.sweeps};
  detail::amg_vcycle(bk, 0, const_cast<double*>(r), z);  // level 0's f is only read
}

}  // namespace vpm
