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

/// d^2/dd^2 ctn(d) = 2 cs(d) / sn(d)^3 (from ctn' = -1/sn^2 and sn' = cs). Singular where sn = 0.
template <class Scalar>
Scalar ctn_second_derivative(Scalar kappa, Scalar d) {
  const Scalar s = sn(kappa, d);
  SESI_CHECK(s != Scalar(0), "ctn'' evaluated at a singular distance");
  return Scalar(2) * cs(kappa, d) / (s * s * s);
}

/// The Laplace-Beltrami operator of a radial function f of the geodesic distance d to a point,
/// on an n-dimensional space of constant curvature, in geodesic polar coordinates, where the volume
/// element is sn(d)^(n-1) dd dOmega (Chavel, Eigenvalues in Riemannian Geometry, 1984, ch. II):
///   Delta f = sn^(1-n) (sn^(n-1) f')' = f''(d) + (n - 1) ctn(d) f'(d),  ctn = cs / sn,
/// from sn = sn(d), cs = cs(d) (a PairGeometry gives both without a transcendental function),
/// f1 = f'(d) and f2 = f''(d). Singular where sn = 0 (d = 0, and d = pi R on S^n): a function
/// smooth there has f' -> 0 like f'' (d - d_0), so ctn f' -> f'' and Delta f -> n f''; at sn = 0
/// the helper returns that limit when f1 = 0, NaN otherwise (a cone has no Laplacian there).
template <class Scalar>
Scalar radial_laplacian(int n, Scalar sn, Scalar cs, Scalar f1, Scalar f2) {
  if (sn == Scalar(0)) return f1 == Scalar(0) ? Scalar(n) * f2 : std::numeric_limits<Scalar>::quiet_NaN();
  return f2 + Scalar(n - 1) * cs * f1 / sn;
}

/// The Laplace-Beltrami operator of a function f of the chord c to a point (c = 2R sin(d/2R) on
/// S^n, the Minkowski chord 2R sinh(d/2R) on H^n, d on E^n; kappa = 1/R^2, -1/R^2, 0):
///   Delta f = f''(c) |grad c|^2 + f'(c) Delta c,  |grad c|^2 = 1 - kappa c^2 / 4,
///   Delta c = (n - 1) / c - (2n - 1) kappa c / 4,
/// radial_laplacian's formula for c(d) = 2 sn(d/2): c' = cs(d/2), c'' = -kappa c / 4 and
/// ctn(d) c' = (1 - kappa c^2 / 2) / c. Regular at the antipode of S^n (c = 2R); singular at
/// c = 0, where as radial_laplacian it returns n f'' when f1 = 0, NaN otherwise.
template <class Scalar>
Scalar chord_laplacian(Scalar kappa, int n, Scalar c, Scalar f1, Scalar f2) {
  if (c == Scalar(0)) return f1 == Scalar(0) ? Scalar(n) * f2 : std::numeric_limits<Scalar>::quiet_NaN();
  const Scalar q = kappa * c / Scalar(4);
  return f2 * (Scalar(1) - q * c) + f1 * (Scalar(n - 1) / c - Scalar(2 * n - 1) * q);
}

}  // namespace sesi::special
