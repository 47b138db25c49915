// ---- dense registration: the image force on a ball grid (local least-squares translations) ----
#include "register/dense_image_force.hpp"

#include <cmath>
#include <tuple>
#include <utility>

#include "core/parallel.hpp"
#include "vpm/error.hpp"
#include "vpm/image.hpp"
#include "vpm/locate.hpp"

namespace vpm {

namespace {

/// `image` at `points` (world mm; trilinear, 0 outside the grid).
std::vector<double> read_at(const Image& image, const Points& points) {
  std::vector<double> out(static_cast<size_t>(points.rows()));
  detail::parallel_for(static_cast<int>(points.rows()), 4096, [&](int begin, int end) {
    for (int i = begin; i < end; ++i)
      out[static_cast<size_t>(i)] = sample_image(image, points.row(i).transpose(), Interpolation::linear);
  });
  return out;
}

/// Mean and (population) variance of `v`.
std::pair<double, double> mean_variance(const std::vector<double>& v) {
  double s = 0, s2 = 0;
  for (double x : v) {
    s += x;
    s2 += x * x;
  }
  const double n = static_cast<double>(v.size()), mean = s / n;
  return {mean, s2 / n - mean * mean};
}

}  // namespace

ImageForce::ImageForce(const DenseImages& images, const Points& tball, const Tets& ttets, const Points& ball,
                       const Tets& tets, int cells)
    : images_(images), tets_(tets), cells_(cells), h_(2.0 / cells) {
  if (!images.subject || !images.templ) throw InputError("dense registration: the image force needs both images");
  if (cells < 4) throw InputError("dense registration: the image grid needs at least 4 cells");
  if (images.template_native.rows() != tball.rows())
    throw InputError("dense registration: the template has " + std::to_string(tball.rows()) +
                     " vertices but " + std::to_string(images.template_native.rows()) + " native positions");
  index_.assign(static_cast<size_t>(cells) * cells * cells, -1);
  std::vector<Eigen::Vector3d> pts;
  for (int k = 0; k < cells; ++k)
    for (int j = 0; j < cells; ++j)
      for (int i = 0; i < cells; ++i) {
        const Eigen::Vector3d p(-1 + (i + 0.5) * h_, -1 + (j + 0.5) * h_, -1 + (k + 0.5) * h_);
        if (p.norm() >= 1) continue;
        const int c = i + cells * (j + cells * k);
        index_[static_cast<size_t>(c)] = static_cast<long>(pts.size());
        cell_of_.push_back(c);
        pts.push_back(p);
      }
  grid_.resize(static_cast<Eigen::Index>(pts.size()), 3);
  for (size_t i = 0; i < pts.size(); ++i) grid_.row(static_cast<Eigen::Index>(i)) = pts[i].transpose();
  templ_ = read_at(*images.templ, pull_back_points(grid_, tball, ttets, images.template_native));
  std::tie(templ_mean_, templ_var_) = mean_variance(templ_);
  auto where = [](const Image& im, const char* who) {
    return std::string(im.path.empty() ? who : im.path.c_str());
  };
  if (!(templ_var_ > 0))
    throw InputError(where(*images.templ, "the template's image") +
                     ": constant where the template's map reaches it (wrong image, or it does not overlap the mesh?)");
  scale_ = 1;
  offset_ = 0;
  const auto [m, var] = mean_variance(subject_values(ball));  // at scale 1, offset 0
  if (!(var > 0))
    throw InputError(where(*images.subject, "the subject's image") +
                     ": constant where the subject's map reaches it (wrong image, or it does not overlap the mesh?)");
  scale_ = std::sqrt(templ_var_ / var);
  offset_ = templ_mean_ - scale_ * m;
}

std::vector<double> ImageForce::subject_values(const Points& ball) const {
  if (images_.subject_native.rows() != ball.rows())
    throw InputError("dense registration: the subject has " + std::to_string(ball.rows()) + " vertices but " +
                     std::to_string(images_.subject_native.rows()) + " native positions");
  return subject_values(TetLocator(ball, tets_));
}

std::vector<double> ImageForce::subject_values(const TetLocator& ball) const {
  std::vector<double> v = read_at(*images_.subject, pull_back_points(grid_, ball, images_.subject_native));
  for (double& x : v) x = scale_ * x + offset_;
  return v;
}

double ImageForce::mismatch(const std::vector<double>& subject) const {
  double s = 0;
  for (size_t i = 0; i < subject.size(); ++i) s += (subject[i] - templ_[i]) * (subject[i] - templ_[i]);
  return s / static_cast<double>(subject.size()) / templ_var_;
}

Eigen::Vector3d ImageForce::gradient(const std::vector<double>& f, long p) const {
  const int c = cell_of_[static_cast<size_t>(p)];
  const int ijk[3] = {c % cells_, (c / cells_) % cells_, c / (cells_ * cells_)};
  const int stride[3] = {1, cells_, cells_ * cells_};
  Eigen::Vector3d g = Eigen::Vector3d::Zero();
  for (int a = 0; a < 3; ++a) {
    const long lo = ijk[a] > 0 ? index_[static_cast<size_t>(c - stride[a])] : -1;
    const long hi = ijk[a] + 1 < cells_ ? index_[static_cast<size_t>(c + stride[a])] : -1;
    const double f0 = f[static_cast<size_t>(p)];
    if (lo >= 0 && hi >= 0) g(a) = (f[static_cast<size_t>(hi)] - f[static_cast<size_t>(lo)]) / (2 * h_);
    else if (hi >= 0) g(a) = (f[static_cast<size_t>(hi)] - f0) / h_;
    else if (lo >= 0) g(a) = (f0 - f[static_cast<size_t>(lo)]) / h_;
  }
  return g;
}

Points ImageForce::gradients(const std::vector<double>& values) const {
  Points g(grid_.rows(), 3);
  const double inv = 1 / std::sqrt(templ_var_);
  for (Eigen::Index p = 0; p < grid_.rows(); ++p) g.row(p) = inv * gradient(values, p).transpose();
  return g;
}

std::vector<double> ImageForce::smoothed(const std::vector<double>& f, double sigma) const {
  const double s = sigma / h_;  // in cells
  if (s < 0.25) return f;
  const int r = static_cast<int>(std::ceil(3 * s));
  std::vector<double> kernel(static_cast<size_t>(2 * r + 1));
  for (int i = -r; i <= r; ++i) kernel[static_cast<size_t>(i + r)] = std::exp(-0.5 * i * i / (s * s));
  const size_t cells3 = index_.size();
  std::vector<double> value(cells3, 0.0), mass(cells3, 0.0);
  for (size_t p = 0; p < cell_of_.size(); ++p) {
    value[static_cast<size_t>(cell_of_[p])] = f[p];
    mass[static_cast<size_t>(cell_of_[p])] = 1;
  }
  const int n = cells_;
  for (int axis = 0; axis < 3; ++axis) {  // separable: one axis at a time, values and mass alike
    const int stride = axis == 0 ? 1 : axis == 1 ? n : n * n;
    for (std::vector<double>* a : {&value, &mass}) {
      std::vector<double> out(cells3, 0.0);
      detail::parallel_for(n * n, 16, [&](int begin, int end) {
        std::vector<double> line(static_cast<size_t>(n));
        for (int q = begin; q < end; ++q) {
          // the line's first cell: q enumerates the two other axes
          const int u = q % n, v = q / n;
          const int base = axis == 0 ? n * (u + n * v) : axis == 1 ? u + n * n * v : u + n * v;
          for (int i = 0; i < n; ++i) line[static_cast<size_t>(i)] = (*a)[static_cast<size_t>(base + i * stride)];
          for (int i = 0; i < n; ++i) {
            double acc = 0;
            for (int k = std::max(-r, -i); k <= std::min(r, n - 1 - i); ++k)
              acc += kernel[static_cast<size_t>(k + r)] * line[static_cast<size_t>(i + k)];
            out[static_cast<size_t>(base + i * stride)] = acc;
          }
        }
      });
      *a = std::move(out);
    }
  }
  std::vector<double> g(f.size());
  for (size_t p = 0; p < cell_of_.size(); ++p) {
    const size_t c = static_cast<size_t>(cell_of_[p]);
    g[p] = mass[c] > 0 ? value[c] / mass[c] : f[p];
  }
  return g;
}

LocalSystems ImageForce::local_systems(const std::vector<double>& subject_raw, const Points& centres, double sigma,
                                      double image_sigma) const {
  const std::vector<double> subject = smoothed(subject_raw, image_sigma);
  const std::vector<double> templ = image_sigma > 0 ? smoothed(templ_, image_sigma) : templ_;
  const Eigen::Index n = grid_.rows(), nc = centres.rows();
  Points g(n, 3);
  Eigen::VectorXd diff(n);
  detail::parallel_for(static_cast<int>(n), 4096, [&](int begin, int end) {
    for (int p = begin; p < end; ++p) {
      g.row(p) = (0.5 * (gradient(subject, p) + gradient(templ, p))).transpose();
      diff(p) = subject[static_cast<size_t>(p)] - templ[static_cast<size_t>(p)];
    }
  });
  LocalSystems sys;
  sys.a.resize(static_cast<size_t>(nc));
  sys.b.resize(nc, 3);
  const double cut2 = 9 * sigma * sigma, inv = 1 / (2 * sigma * sigma);
  detail::parallel_for(static_cast<int>(nc), 8, [&](int begin, int end) {
    for (int c = begin; c < end; ++c) {
      const Eigen::Vector3d x = centres.row(c).transpose();
      Eigen::Matrix3d m = Eigen::Matrix3d::Zero();
      Eigen::Vector3d r = Eigen::Vector3d::Zero();
      // the grid cells within 3 sigma, in the grid points' own order (k, j, i)
      int lo[3], hi[3];
      for (int a = 0; a < 3; ++a) {
        lo[a] = std::max(0, static_cast<int>(std::floor((x(a) - 3 * sigma + 1) / h_ - 0.5)));
        hi[a] = std::min(cells_ - 1, static_cast<int>(std::ceil((x(a) + 3 * sigma + 1) / h_ - 0.5)));
      }
      for (int k = lo[2]; k <= hi[2]; ++k)
        for (int j = lo[1]; j <= hi[1]; ++j)
          for (int i = lo[0]; i <= hi[0]; ++i) {
            const long p = index_[static_cast<size_t>(i + cells_ * (j + cells_ * k))];
            if (p < 0) continue;
            const double d2 = (grid_.row(p).transpose() - x).squaredNorm();
            if (d2 > cut2) continue;
            const double w = std::exp(-d2 * inv);
            const Eigen::Vector3d gp = g.row(p).transpose();
            m += w * gp * gp.transpose();
            r += w * diff(p) * gp;
          }
      sys.a[static_cast<size_t>(c)] = m;
      sys.b.row(c) = r.transpose();
    }
  });
  return sys;
}

}  // namespace vpm
