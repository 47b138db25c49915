#pragma once
// Private: the two distribution functions the single-case tests of vpm/statistics.hpp need,
// written here because Boost.Math's incomplete beta returns NaN when built with
// -frounding-math (which CGAL's targets add to every translation unit of the library).

namespace vpm::detail {

/// Regularized incomplete beta I_x(a, b) for a, b > 0 and x in [0, 1] (continued fraction,
/// Lentz's method; about 1e-14 relative).
double incomplete_beta(double a, double b, double x);

/// P(T <= -|t|) for Student's t with `dof` degrees of freedom (the lower tail, never rounded to
/// 0 before double underflow).
double student_t_tail(double t, double dof);

/// The z with Phi(z) = p for p in (0, 0.5] (z <= 0): Acklam's rational approximation refined
/// by one Halley step against std::erfc; p below the smallest normal double is clamped.
double normal_lower_quantile(double p);

}  // namespace vpm::detail
