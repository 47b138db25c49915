// ---- dense registration: the image refinement of every vertex (vpm/dense_registration.hpp) ----
#include "register/dense_refine.hpp"

#include <algorithm>
#include <cmath>
#include <deque>
#include <limits>

#include "core/parallel.hpp"
#include "vpm/error.hpp"
#include "vpm/geometry.hpp"
#include "vpm/image.hpp"
#include "vpm/locate.hpp"
#include "vpm/timing.hpp"

namespace vpm {

namespace {

constexpr int kChunks = 16;  ///< fixed work split: the sums do not depend on the thread count

/// `image` smoothed by a separable Gaussian of `sigma` voxels (per axis, in that axis's voxels).
std::vector<float> smoothed(const Image& image, double sigma_mm) {
  std::vector<float> out = image.data;
  for (int axis = 0; axis < 3; ++axis) {
    const double s = sigma_mm / image.spacing[static_cast<size_t>(axis)];
    if (s < 0.2) continue;
    const int r = static_cast<int>(std::ceil(3 * s));
    std::vector<double> k(static_cast<size_t>(2 * r + 1));
    for (int i = -r; i <= r; ++i) k[static_cast<size_t>(i + r)] = std::exp(-0.5 * i * i / (s * s));
    const int n = image.dims[static_cast<size_t>(axis)];
    const long stride = axis == 0 ? 1 : axis == 1 ? image.dims[0] : long(image.dims[0]) * image.dims[1];
    const int o1 = axis == 0 ? 1 : 0, o2 = axis == 2 ? 1 : 2;
    const int n1 = image.dims[static_cast<size_t>(o1)], n2 = image.dims[static_cast<size_t>(o2)];
    const long s1 = o1 == 0 ? 1 : image.dims[0], s2 = o2 == 1 ? image.dims[0] : long(image.dims[0]) * image.dims[1];
    std::vector<float> in = out;
    detail::parallel_for(n1 * n2, 64, [&](int b, int e) {
      for (int q = b; q < e; ++q) {
        const long base = (q % n1) * s1 + (q / n1) * s2;
        for (int i = 0; i < n; ++i) {
          double acc = 0, w = 0;
          for (int d = std::max(-r, -i); d <= std::min(r, n - 1 - i); ++d) {
            acc += k[static_cast<size_t>(d + r)] * in[static_cast<size_t>(base + (i + d) * stride)];
            w += k[static_cast<size_t>(d + r)];
          }
          out[static_cast<size_t>(base + i * stride)] = static_cast<float>(acc / w);
        }
      }
    });
  }
  return out;
}

/// The template's image resampled on a regular grid of the ball (nodes -1 + i h), with its
/// gradient by central differences: value and gradient at any ball point by trilinear weights.
class BallImage {
 public:
  BallImage(const Image& image, const std::vector<float>& data, const Points& ball, const Tets& tets,
            const Points& native, int cells)
      : n_(cells + 1), h_(2.0 / cells) {
    const long nodes = long(n_) * n_ * n_;
    std::vector<long> at;
    std::vector<Eigen::Vector3d> pts;
    const double reach = 1 + 2 * h_;
    for (int k = 0; k < n_; ++k)
      for (int j = 0; j < n_; ++j)
        for (int i = 0; i < n_; ++i) {
          const Eigen::Vector3d p(-1 + i * h_, -1 + j * h_, -1 + k * h_);
          if (p.norm() > reach) continue;
          at.push_back(i + long(n_) * (j + long(n_) * k));
          pts.push_back(p);
        }
    Points P(static_cast<Eigen::Index>(pts.size()), 3);
    for (size_t i = 0; i < pts.size(); ++i) P.row(static_cast<Eigen::Index>(i)) = pts[i].transpose();
    const Points world = pull_back_points(P, ball, tets, native);
    Image im = image;
    im.data = data;
    value_.assign(static_cast<size_t>(nodes), 0.0f);
    detail::parallel_for(static_cast<int>(at.size()), 4096, [&](int b, int e) {
      for (int i = b; i < e; ++i)
        value_[static_cast<size_t>(at[static_cast<size_t>(i)])] =
            sample_image(im, world.row(i).transpose(), Interpolation::linear);
    });
    grad_.assign(static_cast<size_t>(nodes) * 3, 0.0f);
    const long st[3] = {1, n_, long(n_) * n_};
    detail::parallel_for(n_, 4, [&](int b, int e) {
      for (int k = b; k < e; ++k)
        for (int j = 0; j < n_; ++j)
          for (int i = 0; i < n_; ++i) {
            const int ijk[3] = {i, j, k};
            const long c = i + long(n_) * (j + long(n_) * k);
            for (int a = 0; a < 3; ++a) {
              const long lo = ijk[a] > 0 ? c - st[a] : c, hi = ijk[a] + 1 < n_ ? c + st[a] : c;
              const double d = (hi - lo) / st[a] * h_;
              grad_[static_cast<size_t>(3 * c + a)] =
                  static_cast<float>((value_[static_cast<size_t>(hi)] - value_[static_cast<size_t>(lo)]) / d);
            }
          }
    });
  }

  /// Value at `p`, its gradient into `g`.
  double sample(const Eigen::Vector3d& p, Eigen::Vector3d& g) const {
    double f[3];
    int c[3];
    for (int a = 0; a < 3; ++a) {
      const double u = std::clamp((p(a) + 1) / h_, 0.0, n_ - 1.000001);
      c[a] = static_cast<int>(u);
      f[a] = u - c[a];
    }
    double v = 0;
    g.setZero();
    for (int dz = 0; dz < 2; ++dz)
      for (int dy = 0; dy < 2; ++dy)
        for (int dx = 0; dx < 2; ++dx) {
          const double w = (dx ? f[0] : 1 - f[0]) * (dy ? f[1] : 1 - f[1]) * (dz ? f[2] : 1 - f[2]);
          const size_t node = static_cast<size_t>(c[0] + dx + long(n_) * (c[1] + dy + long(n_) * (c[2] + dz)));
          v += w * value_[node];
          g(0) += w * grad_[3 * node];
          g(1) += w * grad_[3 * node + 1];
          g(2) += w * grad_[3 * node + 2];
        }
    return v;
  }

 private:
  int n_;
  double h_;
  std::vector<float> value_, grad_;
};

/// The subject's samples: its image's voxels inside its native mesh, each a fixed barycentric
/// point of one tet.
struct Samples {
  std::vector<int> tet;
  std::vector<std::array<double, 4>> bary;
  std::vector<double> value;
};

Samples subject_samples(const Image& image, const std::vector<float>& data, const Points& native, const Tets& tets,
                        int stride) {
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300), hi = -lo;
  for (int cx = 0; cx < 2; ++cx)
    for (int cy = 0; cy < 2; ++cy)
      for (int cz = 0; cz < 2; ++cz) {
        const Eigen::Vector3d w(cx ? native.col(0).maxCoeff() : native.col(0).minCoeff(),
                                cy ? native.col(1).maxCoeff() : native.col(1).minCoeff(),
                                cz ? native.col(2).maxCoeff() : native.col(2).minCoeff());
        const Eigen::Vector3d v = image.to_voxel(w);
        lo = lo.cwiseMin(v);
        hi = hi.cwiseMax(v);
      }
  int b[3], e[3];
  for (int a = 0; a < 3; ++a) {
    b[a] = std::max(0, static_cast<int>(std::floor(lo(a))));
    e[a] = std::min(image.dims[static_cast<size_t>(a)] - 1, static_cast<int>(std::ceil(hi(a))));
  }
  std::vector<Eigen::Vector3d> pts;
  std::vector<size_t> index;
  for (int k = b[2]; k <= e[2]; k += stride)
    for (int j = b[1]; j <= e[1]; j += stride)
      for (int i = b[0]; i <= e[0]; i += stride) {
        pts.push_back(image.to_world(Eigen::Vector3d(i, j, k)));
        index.push_back(image.index(i, j, k));
      }
  Points P(static_cast<Eigen::Index>(pts.size()), 3);
  for (size_t i = 0; i < pts.size(); ++i) P.row(static_cast<Eigen::Index>(i)) = pts[i].transpose();
  const std::vector<Location> loc = TetLocator(native, tets).locate_all(P);
  Samples s;
  for (size_t i = 0; i < loc.size(); ++i) {
    if (!loc[i].inside()) continue;
    s.tet.push_back(loc[i].tet);
    s.bary.push_back({loc[i].bary[0], loc[i].bary[1], loc[i].bary[2], loc[i].bary[3]});
    s.value.push_back(data[index[i]]);
  }
  return s;
}

/// f(x) and its gradient for the free coordinates.
struct Objective {
  const Samples& s;
  const BallImage& templ;
  const Tets& tets;
  const Eigen::VectorXd& v0;
  const std::vector<char>& fixed;
  double scale = 1, offset = 0, inv_var = 1, volume_weight = 1;
  mutable double last_image = 0, last_volume = 0;

  double operator()(const Points& x, Points& grad) const {
    const long np = static_cast<long>(s.tet.size());
    std::vector<Points> part(kChunks, Points::Zero(x.rows(), 3));
    std::vector<double> fi(kChunks, 0.0), fv(kChunks, 0.0);
    std::vector<char> bad(kChunks, 0);
    const long nt = tets.rows();
    const double wi = inv_var / static_cast<double>(np), wv = volume_weight / static_cast<double>(nt);
    detail::parallel_for(kChunks, 1, [&](int cb, int ce) {
      for (int c = cb; c < ce; ++c) {
        Points& g = part[static_cast<size_t>(c)];
        const long pb = np * c / kChunks, pe = np * (c + 1) / kChunks;
        Eigen::Vector3d tg;
        for (long p = pb; p < pe; ++p) {
          const int t = s.tet[static_cast<size_t>(p)];
          const auto& b = s.bary[static_cast<size_t>(p)];
          Eigen::Vector3d q = Eigen::Vector3d::Zero();
          for (int k = 0; k < 4; ++k) q += b[static_cast<size_t>(k)] * x.row(tets(t, k)).transpose();
          const double r = scale * s.value[static_cast<size_t>(p)] + offset - templ.sample(q, tg);
          fi[static_cast<size_t>(c)] += r * r;
          for (int k = 0; k < 4; ++k) g.row(tets(t, k)) -= (2 * wi * r * b[static_cast<size_t>(k)]) * tg.transpose();
        }
        const long tb = nt * c / kChunks, te = nt * (c + 1) / kChunks;
        for (long t = tb; t < te; ++t) {
          const Eigen::Vector3d a = x.row(tets(t, 0)), e1 = x.row(tets(t, 1)).transpose() - a,
                                e2 = x.row(tets(t, 2)).transpose() - a, e3 = x.row(tets(t, 3)).transpose() - a;
          const double v = e1.dot(e2.cross(e3)) / 6;
          if (!(v > 0)) {
            bad[static_cast<size_t>(c)] = 1;
            continue;
          }
          const double l = std::log(v / v0(t));
          fv[static_cast<size_t>(c)] += l * l;
          const double d = wv * 2 * l / v;  // d(wv l^2)/dv
          const Eigen::Vector3d g1 = e2.cross(e3) / 6, g2 = e3.cross(e1) / 6, g3 = e1.cross(e2) / 6;
          g.row(tets(t, 1)) += d * g1.transpose();
          g.row(tets(t, 2)) += d * g2.transpose();
          g.row(tets(t, 3)) += d * g3.transpose();
          g.row(tets(t, 0)) -= d * (g1 + g2 + g3).transpose();
        }
      }
    });
    for (char b : bad)
      if (b) return std::numeric_limits<double>::infinity();
    double si = 0, sv = 0;
    for (int c = 0; c < kChunks; ++c) {
      si += fi[static_cast<size_t>(c)];
      sv += fv[static_cast<size_t>(c)];
    }
    grad = Points::Zero(x.rows(), 3);
    for (int c = 0; c < kChunks; ++c) grad += part[static_cast<size_t>(c)];
    last_image = si * wi;
    last_volume = sv / static_cast<double>(nt);
    for (Eigen::Index v = 0; v < x.rows(); ++v)
      if (fixed[static_cast<size_t>(v)]) grad.row(v).setZero();
    return last_image + volume_weight * last_volume;
  }
};

/// Cells across the ball for the template's resampled image: one per voxel of the template's
/// image across its native mesh, within [32, 256].
int template_cells(const Image& image, const Points& native) {
  const double extent = (native.colwise().maxCoeff() - native.colwise().minCoeff()).maxCoeff();
  const double voxel = std::min({image.spacing[0], image.spacing[1], image.spacing[2]});
  return static_cast<int>(std::clamp(std::lround(extent / voxel), 32L, 256L));
}

/// Every stride-th voxel along each axis, so that about one falls in each tet: the voxels inside
/// a brain are about half of its bounding box's `box`. At 45,000 vertices (214k tets) and 1 mm
/// that is every second voxel (217k samples): the same held-out Dice as every voxel (1.7
/// million) on the development pairs at a fifth of the time.
int sample_stride(double box, long tets) {
  const double per_tet = 0.5 * box / static_cast<double>(std::max(tets, 1L));
  return static_cast<int>(std::clamp(std::lround(std::cbrt(per_tet)), 1L, 64L));
}

/// L-BFGS (two-loop recursion) on `f` from `x` with Armijo backtracking; returns the iterations.
template <class F>
int minimise(const F& f, Points& x, const DenseRefineOptions& o, double first_step) {
  const Eigen::Index m = x.rows() * 3;
  auto flat = [m](Points& p) { return Eigen::Map<Eigen::VectorXd>(p.data(), m); };
  Points gx;
  double fx = f(x, gx);
  std::deque<std::pair<Eigen::VectorXd, Eigen::VectorXd>> mem;
  int it = 0;
  for (; it < o.iterations; ++it) {
    Eigen::VectorXd q = flat(gx);
    std::vector<double> alpha(mem.size());
    for (size_t i = mem.size(); i-- > 0;) {
      alpha[i] = mem[i].first.dot(q) / mem[i].second.dot(mem[i].first);
      q -= alpha[i] * mem[i].second;
    }
    if (!mem.empty()) q *= mem.back().first.dot(mem.back().second) / mem.back().second.squaredNorm();
    else q *= first_step / std::max(1e-300, q.lpNorm<Eigen::Infinity>());
    for (size_t i = 0; i < mem.size(); ++i) q += (alpha[i] - mem[i].second.dot(q) / mem[i].second.dot(mem[i].first)) * mem[i].first;
    const double slope = -flat(gx).dot(q);
    if (!(slope < 0)) break;
    Points xn, gn;
    double fn = fx, step = 1;
    bool ok = false;
    for (int ls = 0; ls < 30 && !ok; ++ls, step *= 0.5) {
      xn = x;
      flat(xn) -= step * q;
      fn = f(xn, gn);
      ok = fn <= fx + 1e-4 * step * slope;
    }
    if (!ok) break;
    mem.emplace_back(flat(xn) - flat(x), flat(gn) - flat(gx));
    if (!(mem.back().first.dot(mem.back().second) > 0)) mem.pop_back();
    if (static_cast<int>(mem.size()) > o.memory) mem.pop_front();
    const double gain = (fx - fn) / std::max(std::abs(fx), 1e-300);
    x = std::move(xn);
    gx = std::move(gn);
    fx = fn;
    if (gain < o.min_gain) return it + 1;
  }
  return it;
}

}  // namespace

DenseRefineReport refine_against_image(const DenseImages& images, const DenseTemplate& templ, const Points& reference,
                                       const Tets& tets, const std::vector<char>& fixed, Points& x,
                                       const DenseRefineOptions& o) {
  const auto t0 = Clock::now();
  DenseRefineReport rep;
  const Image& simage = *images.subject;
  const double box = (images.subject_native.colwise().maxCoeff() - images.subject_native.colwise().minCoeff()).prod() /
                     (simage.spacing[0] * simage.spacing[1] * simage.spacing[2]);
  const int stride = sample_stride(box, tets.rows());
  const Samples s = subject_samples(simage, smoothed(simage, o.smoothing_mm), images.subject_native, tets, stride);
  if (s.tet.size() < 100)
    throw InputError(simage.path + ": the image refinement found " + std::to_string(s.tet.size()) +
                     " voxels inside the subject's native mesh (does the image cover it?)");
  rep.template_cells = template_cells(*images.templ, images.template_native);
  const BallImage timage(*images.templ, smoothed(*images.templ, o.smoothing_mm), templ.ball, templ.tets,
                         images.template_native, rep.template_cells);
  rep.samples = static_cast<long>(s.tet.size());
  for (char f : fixed) rep.pinned_vertices += f != 0;
  // the subject's intensities scaled to the template's mean and spread where they meet now
  double ms = 0, ms2 = 0, mt = 0, mt2 = 0;
  Eigen::Vector3d g;
  for (size_t p = 0; p < s.tet.size(); ++p) {
    Eigen::Vector3d q = Eigen::Vector3d::Zero();
    for (int k = 0; k < 4; ++k) q += s.bary[p][static_cast<size_t>(k)] * x.row(tets(s.tet[p], k)).transpose();
    const double t = timage.sample(q, g);
    ms += s.value[p];
    ms2 += s.value[p] * s.value[p];
    mt += t;
    mt2 += t * t;
  }
  const double n = static_cast<double>(s.tet.size());
  ms /= n;
  mt /= n;
  const double vs = ms2 / n - ms * ms, vt = mt2 / n - mt * mt;
  if (!(vs > 0) || !(vt > 0))
    throw InputError((vs > 0 ? images.templ->path : simage.path) +
                     ": constant where the image refinement compares the two images");
  const Eigen::VectorXd target = tet_volumes(reference, tets);
  Objective f{s, timage, tets, target, fixed};
  f.scale = std::sqrt(vt / vs);
  f.offset = mt - f.scale * ms;
  f.inv_var = 1 / vt;
  f.volume_weight = o.volume_weight;
  Points unused;
  f(x, unused);
  rep.mismatch_before = f.last_image;
  rep.volume_before = f.last_volume;
  if (rep.mismatch_before < DenseRefineOptions::kAligned) {
    rep.mismatch_after = rep.mismatch_before;
    rep.volume_after = rep.volume_before;
    rep.seconds = seconds_since(t0);
    return rep;
  }
  // the first step moves no vertex further than a tenth of a template cell
  rep.iterations = minimise(f, x, o, 0.1 * 2.0 / rep.template_cells);
  f(x, unused);
  rep.mismatch_after = f.last_image;
  rep.volume_after = f.last_volume;
  rep.seconds = seconds_since(t0);
  return rep;
}

}  // namespace vpm
