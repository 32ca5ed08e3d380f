#pragma once
/// @file special_functions.hpp
/// Every singular or cancelling expression of the library goes through one helper here.
/// Each helper has a series branch below a per-Scalar threshold (as Sophus's common.hpp does),
/// chosen so that the first omitted term is below half an ulp.

#include <cmath>
#include <cstdint>
#include <limits>
#include <type_traits>

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

namespace detail {

/// The odd part q(z), z = u^2, of a minimax approximation atan(u) = u - u q(z), per Scalar.
/// double: fdlibm s_atan.c (Sun Microsystems, 1993), coefficients aT[0..10], |u| <= 7/16,
/// polynomial error below 2^-58 relative; evaluated in its two interleaved Horner chains.
/// float: Cephes atanf.c (S. L. Moshier, 1989), |u| <= tan(pi/8), relative error 1.9e-7 with roundings.
template <class Scalar>
struct AtanPoly;

template <>
struct AtanPoly<double> {
  static constexpr double small_below = 0.4375;  // 7/16: the end of fdlibm's polynomial range
  SESI_INLINE static double q(double z) {
    const double w = z * z;
    const double s1 = z * (3.33333333333329318027e-01 +
                           w * (1.42857142725034663711e-01 +
                                w * (9.09088713343650656196e-02 +
                                     w * (6.66107313738753120669e-02 +
                                          w * (4.97687799461593236017e-02 + w * 1.62858201153657823623e-02)))));
    const double s2 = w * (-1.99999999998764832476e-01 +
                           w * (-1.11111104054623557880e-01 +
                                w * (-7.69187620504482999495e-02 +
                                     w * (-5.83357013379057348645e-02 + w * -3.65315727442169155270e-02))));
    return s1 + s2;
  }
};

template <>
struct AtanPoly<float> {
  static constexpr float small_below = 0.40625f;  // 13/32, inside Cephes' range |u| <= tan(pi/8) = 0.41421
  SESI_INLINE static float q(float z) {
    return z * (3.33329491539e-1f + z * (-1.99777106478e-1f + z * (1.38776856032e-1f + z * -8.05374449538e-2f)));
  }
};

}  // namespace detail

/// atan2(y, x) in [-pi, pi] without a libm call, for the pair kernels' geodesic distance (issue #27):
/// inline and branch-free (selects only: no jump at -O2 on x86-64). GCC 12 vectorises a loop of
/// it only under -fno-trapping-math (otherwise it may not evaluate both arms of a select).
/// Error against long double atan2l (tests/core/special.cpp: 1.2e6 arguments per type, tiny,
/// huge and subnormal, both signs, the reduction switches): measured at most 1.45 ulp in double,
/// 1.77 ulp in float; bound 2 ulp (derived in the test: 1 ulp from rounding y/x, 0.5 from the
/// last addition, the polynomial's 0.04 (double) or 0.36 (float) ulp). IEEE zeros: atan2(+-0, +0) =
/// +-0, atan2(+-0, -0) = +-pi, atan2(+-0, x < 0) = +-pi; a NaN argument gives NaN. Two infinite
/// arguments give NaN (not +-pi/4 or +-3pi/4); one infinite argument is handled. Other Scalars
/// (long double) call std::atan2.
template <class Scalar>
SESI_INLINE Scalar atan2_fast(Scalar y, Scalar x) {
  if constexpr (!std::is_same_v<Scalar, double> && !std::is_same_v<Scalar, float>) {
    using std::atan2;
    return atan2(y, x);
  } else {
    using Poly = detail::AtanPoly<Scalar>;
    // pi/2, atan(1/2), pi/4 and pi as hi + lo pairs (hi the nearest Scalar; lo the rest, from
    // the 40-digit values of atan(1/2) = 0.4636476090008061162142562314612144020285 and pi).
    constexpr long double pi_l = 3.141592653589793238462643383279502884L;
    constexpr long double atan_half_l = 0.4636476090008061162142562314612144020285L;
    constexpr Scalar pi_hi = Scalar(pi_l), pi_lo = Scalar(pi_l - (long double)pi_hi);
    constexpr Scalar pio2_hi = Scalar(pi_l / 2), pio2_lo = Scalar(pi_l / 2 - (long double)pio2_hi);
    constexpr Scalar pio4_hi = Scalar(pi_l / 4), pio4_lo = Scalar(pi_l / 4 - (long double)pio4_hi);
    constexpr Scalar ah_hi = Scalar(atan_half_l), ah_lo = Scalar(atan_half_l - (long double)ah_hi);
    const Scalar a = y < Scalar(0) ? -y : y, b = x < Scalar(0) ? -x : x;
    // The sign of x through copysign (x = -0 counts as negative), not signbit: GCC vectorises it.
    const bool swap = a > b, neg = std::copysign(Scalar(1), x) < Scalar(0);
    // mn <= mx; a NaN lands in one of them (the comparison is false) and flows to the result.
    Scalar mn = a < b ? a : b, mx = a < b ? b : a;
    // Scale huge pairs by 1/4 so that 2 mx + mn cannot overflow, and tiny ones by 2^digits so
    // that the switch tests T mx below are not subnormal (both exact: powers of two).
    using Limits = std::numeric_limits<Scalar>;
    constexpr Scalar up = Scalar(std::uint64_t(1) << Limits::digits);
    constexpr Scalar big = Limits::max() / Scalar(8), tiny = Limits::min() * up;
    const Scalar s = mx > big ? Scalar(0.25) : (mx < tiny ? up : Scalar(1));
    mn *= s;
    mx *= s;
    // Reduction (fdlibm s_atan.c): t = mn/mx in [0, 1] is taken to u with atan t = H + atan u:
    //   t < T1:          u = t,                        H = 0
    //   T1 <= t < 11/16: u = (2t - 1)/(2 + t),         H = atan(1/2),  u in [-0.11, 0.14)
    //   t >= 11/16:      u = (t - 1)/(t + 1),          H = pi/4,       u in [-0.19, 0]
    // The numerators 2 mn - mx and mn - mx are exact (Sterbenz: the operands are within a
    // factor 2), so u carries only the rounding of its denominator and of the division.
    const bool mid = mn > Poly::small_below * mx, hi = mn > Scalar(0.6875) * mx;
    const Scalar num = hi ? mn - mx : (mid ? Scalar(2) * mn - mx : mn);
    Scalar den = hi ? mn + mx : (mid ? Scalar(2) * mx + mn : mx);
    den = den == Scalar(0) ? Scalar(1) : den;  // x = y = 0: u = 0, angle 0 (or pi for x = -0)
    const Scalar u = num / den;
    const Scalar hh = hi ? pio4_hi : (mid ? ah_hi : Scalar(0));
    const Scalar hl = hi ? pio4_lo : (mid ? ah_lo : Scalar(0));
    // The angle K + sigma (H + atan u) in [0, pi] from the octant: K = 0, pi/2 or pi.
    const Scalar sigma = swap == neg ? Scalar(1) : Scalar(-1);
    const Scalar kh = swap ? pio2_hi : (neg ? pi_hi : Scalar(0));
    const Scalar kl = swap ? pio2_lo : (neg ? pi_lo : Scalar(0));
    // A = kh + sigma hh with its rounding error e (Fast2Sum, |kh| >= |hh| or kh = 0: Dekker 1971).
    const Scalar sh = sigma * hh;
    const Scalar A = kh + sh;
    const Scalar e = sh - (A - kh);
    const Scalar su = sigma * u;
    const Scalar tail = (e + (kl + sigma * hl)) - su * Poly::q(u * u);
    const Scalar angle = A + (su + tail);
    return std::copysign(angle, y);
  }
}

/// atan2(sqrt(y2), sqrt(x2)) for squared lengths y2, x2 >= 0 with one square root instead of two
/// (Sphere::distance_of: y2 = chord^2, x2 = cochord^2): atan2_fast's reduction multiplied through
/// by mx, with p = sqrt(mn mx) = mn' mx' (mn' = sqrt(mn), mx' = sqrt(mx)) in place of mn':
///   u = p / mx,  (2 p - mx) / (2 mx + p),  (p - mx) / (p + mx).
/// u carries 1.25 eps relative (the product 0.5 halved by the root, the root 0.5, the division
/// 0.5), up to 2.5 ulp of the result a binade below u, plus atan2_fast's 0.5 + 0.36 (float) or
/// 0.11 (double): bound 3.5 ulp; measured 2.6 ulp double, 2.9 float (tests/core/special.cpp). Domain: y2 x2 neither overflows nor underflows (as the pair's
/// sn = sqrt(chord2 cochord2)); zeros give 0 or pi/2, a NaN gives NaN. Long double: std::atan2.
template <class Scalar>
SESI_INLINE Scalar atan2_sqrt_fast(Scalar y2, Scalar x2) {
  if constexpr (!std::is_same_v<Scalar, double> && !std::is_same_v<Scalar, float>) {
    using std::atan2;
    using std::sqrt;
    return atan2(sqrt(y2), sqrt(x2));
  } else {
    using Poly = detail::AtanPoly<Scalar>;
    constexpr long double pi_l = 3.141592653589793238462643383279502884L;
    constexpr long double atan_half_l = 0.4636476090008061162142562314612144020285L;
    constexpr Scalar pio2_hi = Scalar(pi_l / 2), pio2_lo = Scalar(pi_l / 2 - (long double)pio2_hi);
    constexpr Scalar pio4_hi = Scalar(pi_l / 4), pio4_lo = Scalar(pi_l / 4 - (long double)pio4_hi);
    constexpr Scalar ah_hi = Scalar(atan_half_l), ah_lo = Scalar(atan_half_l - (long double)ah_hi);
    const bool swap = y2 > x2;
    const Scalar mn = y2 < x2 ? y2 : x2, mx = y2 < x2 ? x2 : y2;  // a NaN flows as in atan2_fast
    // The switches of atan2_fast on t = sqrt(mn / mx), squared: t > T  <=>  mn > T^2 mx.
    constexpr Scalar t1 = Poly::small_below * Poly::small_below, t2 = Scalar(0.6875 * 0.6875);
    const bool mid = mn > t1 * mx, hi = mn > t2 * mx;
    const Scalar p = std::sqrt(mn * mx);
    const Scalar num = hi ? p - mx : (mid ? Scalar(2) * p - mx : p);  // exact: Sterbenz, as there
    Scalar den = hi ? p + mx : (mid ? Scalar(2) * mx + p : mx);
    den = den == Scalar(0) ? Scalar(1) : den;  // y2 = x2 = 0: angle 0
    const Scalar u = num / den;
    const Scalar hh = hi ? pio4_hi : (mid ? ah_hi : Scalar(0));
    const Scalar hl = hi ? pio4_lo : (mid ? ah_lo : Scalar(0));
    // The angle K + sigma (H + atan u) in [0, pi/2]: K = 0, sigma = 1, or K = pi/2, sigma = -1.
    const Scalar sigma = swap ? Scalar(-1) : Scalar(1);
    const Scalar kh = swap ? pio2_hi : Scalar(0), kl = swap ? pio2_lo : Scalar(0);
    const Scalar sh = sigma * hh;
    const Scalar A = kh + sh;
    const Scalar e = sh - (A - kh);  // Fast2Sum (Dekker 1971), as in atan2_fast
    const Scalar su = sigma * u;
    const Scalar tail = (e + (kl + sigma * hl)) - su * Poly::q(u * u);
    return A + (su + tail);
  }
}

namespace detail {

/// sin and cos of x in double, |x| <= sincos_limit, branch-free (selects only), so that a loop
/// of it vectorises: the argument reduction of fdlibm's e_rem_pio2.c (Sun Microsystems, 1993;
/// its "medium" case: pi/2 in 33-bit pieces pio2_1, pio2_2, pio2_3 and the tails pio2_2t,
/// pio2_3t, each product with fn exact for |fn| < 2^20), to y0 + y1, then the kernels of
/// FreeBSD's k_sin.c and k_cos.c (S. Kargl and B. Evans, 2008: minimax on [-pi/4, pi/4],
/// |poly error| < 2^-58), and the quadrant fn mod 4 as an exact double (the vector loop has no
/// integer lanes to spare). fdlibm takes the second and third reduction steps only on
/// cancellation; here the second is always taken and the third selected where fdlibm takes it
/// (the third step drops the second's tail, so it must not replace it elsewhere). lanes: the
/// quadrant by std::floor (a vector instruction from SSE4.1 on), else by integers (floor is a
/// libm call on SSE2); the same value either way.
template <bool lanes>
SESI_INLINE void sincos_reduced(double x, double& s, double& c) {
  constexpr double invpio2 = 0x1.45f306dc9c883p-1;   // 2/pi
  constexpr double pio2_1 = 0x1.921fb54400000p+0;    // first 33 bits of pi/2
  constexpr double pio2_2 = 0x1.0b4611a600000p-34;   // second 33 bits
  constexpr double pio2_2t = 0x1.3198a2e037073p-69;  // pi/2 - (pio2_1 + pio2_2)
  constexpr double pio2_3 = 0x1.3198a2e000000p-69;   // third 33 bits
  constexpr double pio2_3t = 0x1.b839a252049c1p-104; // pi/2 - (pio2_1 + pio2_2 + pio2_3)
  constexpr double S1 = -0x1.5555555555549p-3, S2 = 0x1.111111110f8a6p-7, S3 = -0x1.a01a019c161d5p-13,
                   S4 = 0x1.71de357b1fe7dp-19, S5 = -0x1.ae5e68a2b9cebp-26, S6 = 0x1.5d93a5acfd57cp-33;
  constexpr double C1 = 0x1.555555555554cp-5, C2 = -0x1.6c16c16c15177p-10, C3 = 0x1.a01a019cb1590p-16,
                   C4 = -0x1.27e4f809c52adp-22, C5 = 0x1.1ee9ebdb4b1c4p-29, C6 = -0x1.8fae9be8838d4p-37;
  constexpr double shifter = 0x1.8p52;  // x / (pi/2) rounded to the nearest integer (ties even)
  const double fn = (x * invpio2 + shifter) - shifter;
  const double t = x - fn * pio2_1;  // exact
  const double w2 = fn * pio2_2;     // exact
  const double r2 = t - w2;
  const double e2 = fn * pio2_2t - ((t - r2) - w2);
  const double w3 = fn * pio2_3;
  const double r3 = r2 - w3;
  const double e3 = fn * pio2_3t - ((r2 - r3) - w3);
  const bool deep = std::fabs(r2 - e2) < std::fabs(x) * 0x1p-49;  // fdlibm: 49 bits cancelled
  const double r = deep ? r3 : r2, w = deep ? e3 : e2;
  const double y0 = r - w;
  const double y1 = (r - y0) - w;
  const double z = y0 * y0, zz = z * z;
  const double rs = S2 + z * (S3 + z * S4) + z * zz * (S5 + z * S6);
  const double v = z * y0;
  const double sn = y0 - ((z * (0.5 * y1 - v * rs) - y1) - v * S1);
  const double rc = z * (C1 + z * (C2 + z * C3)) + zz * zz * (C4 + z * (C5 + z * C6));
  const double hz = 0.5 * z;
  const double wc = 1.0 - hz;
  const double cs = wc + (((1.0 - wc) - hz) + (z * rc - y0 * y1));
  // Quadrant fn mod 4 = m: sin x = sin y, cos y, -sin y, -cos y for m = 0..3; cos x likewise
  // shifted by one. Exact in doubles (fn is an integer below 2^20).
  double m, odd, mc;
  if constexpr (lanes) {
    m = fn - 4.0 * std::floor(fn * 0.25);
    odd = m - 2.0 * std::floor(m * 0.5);
    mc = (m + 1.0) - 4.0 * std::floor((m + 1.0) * 0.25);
  } else {
    const auto n = static_cast<std::int64_t>(fn);
    m = static_cast<double>(n & 3);
    odd = static_cast<double>(n & 1);
    mc = static_cast<double>((n + 1) & 3);
  }
  const double s0 = odd != 0.0 ? cs : sn;
  const double c0 = odd != 0.0 ? sn : cs;
  s = m >= 2.0 ? -s0 : s0;
  c = mc >= 2.0 ? -c0 : c0;
}

}  // namespace detail

/// Arguments up to this magnitude take sincos_fast's own path; beyond it, and for NaN or an
/// infinity, the C library's sincos (fdlibm's medium reduction holds below 2^20 pi/2).
inline constexpr double sincos_limit = 0x1p19;

/// s = sin x, c = cos x, the same bits as every lane of sincos_many (the charts' trig caches:
/// hyperspherical.hpp). Error against long double sinl, cosl (tests/core/special.cpp: 3e6
/// arguments from 1e-8 to 5e5 in magnitude, and the doubles next to k pi/2 for |k| <= 2^19):
/// measured at most 0.78 ulp; glibc's sincos is within 1 ulp and correctly rounded in most cases,
/// so the two differ in the last bit for some arguments. Other Scalars: the C library.
template <class Scalar>
SESI_INLINE void sincos_fast(Scalar x, Scalar& s, Scalar& c) {
  using std::cos;
  using std::sin;
  if constexpr (std::is_same_v<Scalar, double>) {
    if (std::fabs(x) <= sincos_limit) {
      detail::sincos_reduced<false>(x, s, c);
      return;
    }
  }
  s = sin(x);
  c = cos(x);
}

namespace detail {
/// sincos_many's loop for one vector width: every lane reduced (an argument beyond the limit
/// as 0), then those arguments again through sincos_fast (the C library).
SESI_INLINE void sincos_lanes(const double* x, double* s, double* c, int n) {
  SESI_PRAGMA_SIMD
  for (int k = 0; k < n; ++k) sincos_reduced<true>(std::fabs(x[k]) <= sincos_limit ? x[k] : 0.0, s[k], c[k]);
  for (int k = 0; k < n; ++k) {
    if (!(std::fabs(x[k]) <= sincos_limit)) sincos_fast(x[k], s[k], c[k]);
  }
}
#if SESI_SIMD_DISPATCH
SESI_TARGET_AVX512 inline void sincos_lanes_avx512(const double* x, double* s, double* c, int n) {
  sincos_lanes(x, s, c, n);
}
SESI_TARGET_AVX2 inline void sincos_lanes_avx2(const double* x, double* s, double* c, int n) {
  sincos_lanes(x, s, c, n);
}
#endif
}  // namespace detail

/// sincos_fast of x[0..n) into s, c: in vector lanes (AVX2, AVX-512 as simd::level() picks;
/// the base width is a scalar loop, its vector floor being a libm call on SSE2), the same bits
/// at every width and as sincos_fast one by one (no FMA at any width).
template <class Scalar>
void sincos_many(const Scalar* x, Scalar* s, Scalar* c, int n) {
  if constexpr (std::is_same_v<Scalar, double>) {
#if SESI_SIMD_DISPATCH
    const simd::Level level = simd::level();
    if (level == simd::Level::avx512) return detail::sincos_lanes_avx512(x, s, c, n);
    if (level == simd::Level::avx2) return detail::sincos_lanes_avx2(x, s, c, n);
#endif
  }
  for (int k = 0; k < n; ++k) sincos_fast(x[k], s[k], c[k]);
}

}  // namespace sesi::special
