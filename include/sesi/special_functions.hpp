#pragma once
/// @file special_functions.hpp
/// Every singular or cancelling expression of the library goes through one helper here.
/// Each helper has a series branch below a per-Scalar threshold (as Sophus's common.hpp does),
/// chosen so that the first omitted term is below half an ulp.

#include <cmath>
#include <limits>

#include "sesi/config.hpp"

namespace sesi::special {

/// Threshold under which the two-term series of an even function f(x) = 1 + a x^2 + b x^4 + ...
/// is exact to round-off: the omitted x^4 term is below epsilon.
template <class Scalar>
Scalar series_threshold() {
  using std::sqrt;
  return sqrt(sqrt(std::numeric_limits<Scalar>::epsilon()));
}

/// sin(x) / x, equal to 1 at x = 0.
template <class Scalar>
Scalar sinc(Scalar x) {
  using std::abs;
  using std::sin;
  if (abs(x) < series_threshold<Scalar>()) return Scalar(1) - x * x / Scalar(6);
  return sin(x) / x;
}

/// sinh(x) / x, equal to 1 at x = 0.
template <class Scalar>
Scalar sinhc(Scalar x) {
  using std::abs;
  using std::sinh;
  if (abs(x) < series_threshold<Scalar>()) return Scalar(1) + x * x / Scalar(6);
  return sinh(x) / x;
}

/// (1 - cos x) / x^2, equal to 1/2 at x = 0; written as 2 sin^2(x/2)/x^2 to avoid cancellation.
template <class Scalar>
Scalar one_minus_cos_over_x2(Scalar x) {
  const Scalar s = sinc(x / Scalar(2));
  return s * s / Scalar(2);
}

/// 1 / sin^2(x), singular at multiples of pi. Guard: checked to be finite in debug builds;
/// pole-safe charts re-chart a body before it gets near (docs/charts.md).
template <class Scalar>
Scalar inv_sin2(Scalar x) {
  using std::sin;
  const Scalar s = sin(x);
  SESI_CHECK(s != Scalar(0), "1/sin^2 evaluated at a chart pole");
  return Scalar(1) / (s * s);
}

/// 1 / sinh^2(x), singular at 0 (the hyperbolic chart origin).
template <class Scalar>
Scalar inv_sinh2(Scalar x) {
  using std::sinh;
  const Scalar s = sinh(x);
  SESI_CHECK(s != Scalar(0), "1/sinh^2 evaluated at the hyperbolic chart origin");
  return Scalar(1) / (s * s);
}

/// cot(x) = cos x / sin x, singular at multiples of pi (same guard as inv_sin2).
template <class Scalar>
Scalar cot(Scalar x) {
  using std::cos;
  using std::sin;
  const Scalar s = sin(x);
  SESI_CHECK(s != Scalar(0), "cot evaluated at a chart pole");
  return cos(x) / s;
}

/// 1/s for a cached sine (or sinh) s of a chart coordinate: singular at the chart's poles.
/// Guard: checked non-zero in debug builds; pole-safe charts re-chart a body before it gets near.
template <class Scalar>
Scalar reciprocal_sine(Scalar s) {
  SESI_CHECK(s != Scalar(0), "reciprocal of a vanishing sine: body at a chart pole");
  return Scalar(1) / s;
}

/// coth(x) = cosh x / sinh x, singular at 0.
template <class Scalar>
Scalar coth(Scalar x) {
  using std::tanh;
  SESI_CHECK(x != Scalar(0), "coth evaluated at zero");
  return Scalar(1) / tanh(x);
}

/// The generalised trigonometric functions of a space of constant curvature kappa
/// (kappa = 1/R^2 on S^n, -1/R^2 on H^n, 0 on E^n), as in Diacu's curved N-body problem:
/// sn(d) = R sin(d/R) | R sinh(d/R) | d,  cs(d) = cos(d/R) | cosh(d/R) | 1,  ctn = cs/sn.
template <class Scalar>
Scalar sn(Scalar kappa, Scalar d) {
  using std::sin;
  using std::sinh;
  using std::sqrt;
  if (kappa > 0) {
    const Scalar r = Scalar(1) / sqrt(kappa);
    return r * sin(d / r);
  }
  if (kappa < 0) {
    const Scalar r = Scalar(1) / sqrt(-kappa);
    return r * sinh(d / r);
  }
  return d;
}

template <class Scalar>
Scalar cs(Scalar kappa, Scalar d) {
  using std::cos;
  using std::cosh;
  using std::sqrt;
  if (kappa > 0) return cos(d * sqrt(kappa));
  if (kappa < 0) return cosh(d * sqrt(-kappa));
  return Scalar(1);
}

/// ctn(d) = cs(d)/sn(d): cot(d/R)/R, coth(d/R)/R or 1/d. Singular at d = 0 (and d = pi R on S^n).
template <class Scalar>
Scalar ctn(Scalar kappa, Scalar d) {
  const Scalar s = sn(kappa, d);
  SESI_CHECK(s != Scalar(0), "ctn evaluated at a singular distance");
  return cs(kappa, d) / s;
}

/// d/dd ctn(d) = -1 / sn(d)^2 (since cs' = -kappa sn and sn' = cs, and cs^2 + kappa sn^2 = 1).
template <class Scalar>
Scalar ctn_derivative(Scalar kappa, Scalar d) {
  const Scalar s = sn(kappa, d);
  SESI_CHECK(s != Scalar(0), "ctn' evaluated at a singular distance");
  return -Scalar(1) / (s * s);
}

}  // namespace sesi::special
