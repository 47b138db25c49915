#include "demo_deformation.hpp"

#include <array>
#include <cmath>
#include <random>
#include <vector>

#include <Eigen/Geometry>

namespace vpm::cli {

namespace {

struct Params {
  Eigen::Vector3d scale;                 // output -> input scale factors about c
  std::vector<std::array<double, 6>> bumps;  // centre offset (mm), displacement (mm)
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  double angle_deg = 0;
};

Params draw(unsigned seed, double max_rotation_deg) {
  Params p;
  std::mt19937 rng(seed == 0 ? 2014u : seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  if (seed == 0) {  // the demo's fixed subject (bench/results/register_dense/ and register_image_force/ measure it)
    p.scale = Eigen::Vector3d(1 / 1.06, 1 / 0.94, 1 / 1.03);
    p.bumps = {{25, 20, 10, 5, -4, 3}, {-25, -15, 20, -4, 5, -3}, {10, -30, -15, 3, 4, 5}, {-15, 25, -20, -5, -3, -4}};
  } else {
    for (int k = 0; k < 3; ++k) p.scale(k) = 1 / (1 + 0.06 * u(rng));
    for (int b = 0; b < 4; ++b) {
      std::array<double, 6> bump{};
      for (int k = 0; k < 3; ++k) bump[k] = 30 * u(rng);
      for (int k = 3; k < 6; ++k) bump[k] = 5 * u(rng);
      p.bumps.push_back(bump);
    }
  }
  if (max_rotation_deg > 0) {
    std::mt19937 rrng(seed + 7919u);  // its own stream: the rotation does not change the bumps
    std::normal_distribution<double> g;
    Eigen::Vector3d axis(g(rrng), g(rrng), g(rrng));
    p.angle_deg = max_rotation_deg * std::uniform_real_distribution<double>(0, 1)(rrng);
    p.rotation = Eigen::AngleAxisd(p.angle_deg * M_PI / 180, axis.normalized()).toRotationMatrix();
  }
  return p;
}

}  // namespace

std::function<Eigen::Vector3d(const Eigen::Vector3d&)> demo_deformation(const Eigen::Vector3d& c, unsigned seed,
                                                                        double max_rotation_deg, bool incompressible) {
  Params p = draw(seed, max_rotation_deg);
  const double sigma = 22.0, s2 = 2 * sigma * sigma;
  if (incompressible) {
    p.scale /= std::cbrt(p.scale.prod());  // the same shape change, volume kept
    // curl(a g) = grad g x a, g = exp(-r^2 / s2): divergence-free, largest |.| = |a| e^-1/2 / sigma
    for (auto& b : p.bumps)
      for (int k = 3; k < 6; ++k) b[static_cast<size_t>(k)] *= sigma * std::exp(0.5);
  }
  if (incompressible)  // the time-1 flow of the curl bumps (4 RK4 steps): volume kept exactly, not to first order
    return [c, p, s2](const Eigen::Vector3d& x0) {
      auto velocity = [&](const Eigen::Vector3d& x) {
        Eigen::Vector3d v = Eigen::Vector3d::Zero();
        for (const auto& b : p.bumps) {
          const Eigen::Vector3d r = x - (c + Eigen::Vector3d(b[0], b[1], b[2]));
          v += (-2 * std::exp(-r.squaredNorm() / s2) / s2) * r.cross(Eigen::Vector3d(b[3], b[4], b[5]));
        }
        return v;
      };
      Eigen::Vector3d y = c + p.scale.cwiseProduct(p.rotation * (x0 - c));
      const double h = 0.25;
      for (int k = 0; k < 4; ++k) {
        const Eigen::Vector3d k1 = velocity(y), k2 = velocity(y + 0.5 * h * k1), k3 = velocity(y + 0.5 * h * k2),
                              k4 = velocity(y + h * k3);
        y += h / 6 * (k1 + 2 * k2 + 2 * k3 + k4);
      }
      return y;
    };
  return [c, p, s2](const Eigen::Vector3d& x0) {
    const Eigen::Vector3d x = c + p.rotation * (x0 - c);
    Eigen::Vector3d y = c + p.scale.cwiseProduct(x - c);
    for (const auto& b : p.bumps)
      y += std::exp(-(x - (c + Eigen::Vector3d(b[0], b[1], b[2]))).squaredNorm() / s2) * Eigen::Vector3d(b[3], b[4], b[5]);
    return y;
  };
}

double demo_rotation_deg(unsigned seed, double max_rotation_deg) { return draw(seed, max_rotation_deg).angle_deg; }

DeformedSubject deformed_subject(const Image& t1, const Image& atlas,
                                 const std::function<Eigen::Vector3d(const Eigen::Vector3d&)>& pull) {
  DeformedSubject d{resample_image(t1, pull, Interpolation::linear), resample_image(atlas, pull, Interpolation::nearest)};
  Image mask = t1;
  for (float& v : mask.data) v = v > 0 ? 1.0f : 0.0f;
  const Image carried = resample_image(mask, pull, Interpolation::nearest);
  for (size_t i = 0; i < d.t1.data.size(); ++i)
    if (!(carried.data[i] > 0)) d.t1.data[i] = 0;
  return d;
}

}  // namespace vpm::cli
