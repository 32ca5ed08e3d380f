// The special functions (special_functions.hpp) at 0, at 1e-8, on both sides of their series
// switch, and near the chart poles, against long double references computed directly, in float,
// double and long double (issue #2; shared/style.md, "Test each at 0, 1e-8 and near chart poles").
//
// The bound: every helper is at most two libm calls (sin, cos, sinh, cosh, tanh, sqrt: at most
// 3 ulp each in glibc's x86-64 tables, 1 ulp = eps relative) and at most two rounded operations
// (eps/2 each): a relative error below 7 eps; we allow 8 eps. The inputs are chosen so that no
// intermediate argument is rounded (powers of two: kappa = +-1/4 gives R = 2 exactly), so the
// conditioning of sin near pi does not enter. Below the switch the series' first omitted term
// is below eps (threshold eps^(1/4)): one more eps. The references are long double
// (eps_ld = 1.1e-19), exact enough for float and double; for long double itself the reference
// has the same 8 eps_ld budget, so the long double bound is doubled.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <numbers>
#include <random>
#include <tuple>
#include <type_traits>
#include <utility>
#include <vector>

#include <doctest/doctest.h>

#include "common.hpp"

namespace {

using namespace coretest;
namespace sp = sesi::special;
using Real = long double;

template <class Scalar>
Real tolerance() {
  const Real base = 9 * Real(eps<Scalar>());
  return std::is_same_v<Scalar, Real> ? 2 * base : base;
}

/// The largest relative error seen, in eps of its scalar (reported by -s).
Real worst_in_eps = 0;

template <class Scalar>
void check_close(Scalar value, Real reference, const char* what, Scalar x) {
  const Real rel = std::abs(Real(value) - reference) / std::abs(reference);
  worst_in_eps = std::max(worst_in_eps, rel / Real(eps<Scalar>()));
  INFO(what, " at x = ", double(x), ": value ", double(value), ", reference ", double(reference),
       ", relative error ", double(rel / Real(eps<Scalar>())), " eps");
  CHECK(rel <= tolerance<Scalar>());
}

/// (1 - cos x) / x^2 in long double, independently of the library's formula: its Taylor series
/// sum_k (-1)^k x^(2k) / (2k+2)! for |x| <= 1 (12 terms: the first omitted is below 1/26! < 1e-26),
/// the direct formula above (cancellation loses at most a factor 2/x^2 <= 2 there).
Real one_minus_cos_reference(Real x) {
  if (std::abs(x) <= Real(1)) {
    Real sum = 0, term = Real(1) / 2;  // (-1)^k x^(2k) / (2k+2)!
    for (int k = 0; k < 12; ++k) {
      sum += term;
      term *= -x * x / Real((2 * k + 3) * (2 * k + 4));
    }
    return sum;
  }
  return (Real(1) - std::cos(x)) / (x * x);
}

/// The inputs: 1e-8, both sides of the threshold (and of twice it, where one_minus_cos switches),
/// 1/4, 1.
template <class Scalar>
std::vector<Scalar> small_arguments() {
  const Scalar t = sp::series_threshold<Scalar>();
  const Scalar below = Scalar(1) - std::ldexp(Scalar(1), -10), above = Scalar(1) + std::ldexp(Scalar(1), -10);
  return {Scalar(1e-8), t * below, t * above, Scalar(2) * t * below, Scalar(2) * t * above,
          Scalar(0.25), Scalar(1)};
}

/// Near the poles of the sphere's angles (0 and pi) and of the hyperbolic radius (0).
template <class Scalar>
std::vector<Scalar> pole_arguments() {
  const Scalar pi = std::numbers::pi_v<Scalar>;
  return {Scalar(1e-8), std::ldexp(Scalar(1), -20), pi - std::ldexp(Scalar(1), -20),
          pi - Scalar(1e-3), pi / Scalar(2), Scalar(-1e-3)};
}

}  // namespace

TEST_CASE_TEMPLATE("special: series threshold is eps^(1/4)", Scalar, float, double, long double) {
  const Scalar t = sp::series_threshold<Scalar>();
  // t^4 = eps to round-off of the two square roots.
  CHECK(std::abs(Real(t) * t * t * t / Real(eps<Scalar>()) - 1) <= 4 * Real(eps<Scalar>()));
}

TEST_CASE_TEMPLATE("special: sinc, sinhc and (1 - cos x)/x^2 at 0, 1e-8 and around the switch",
                   Scalar, float, double, long double) {
  CHECK(sp::sinc(Scalar(0)) == Scalar(1));
  CHECK(sp::sinhc(Scalar(0)) == Scalar(1));
  CHECK(sp::one_minus_cos_over_x2(Scalar(0)) == Scalar(0.5));
  for (const Scalar x : small_arguments<Scalar>()) {
    for (const Scalar s : {x, -x}) {
      check_close(sp::sinc(s), std::sin(Real(s)) / Real(s), "sinc", s);
      check_close(sp::sinhc(s), std::sinh(Real(s)) / Real(s), "sinhc", s);
      check_close(sp::one_minus_cos_over_x2(s), one_minus_cos_reference(Real(s)),
                  "one_minus_cos_over_x2", s);
    }
  }
}

TEST_CASE_TEMPLATE("special: 1/sin^2, 1/sinh^2, cot, coth, 1/s near the chart poles", Scalar,
                   float, double, long double) {
  for (const Scalar x : pole_arguments<Scalar>()) {
    const Real s = std::sin(Real(x)), sh = std::sinh(Real(x));
    check_close(sp::inv_sin2(x), 1 / (s * s), "inv_sin2", x);
    check_close(sp::cot(x), std::cos(Real(x)) / s, "cot", x);
    check_close(sp::inv_sinh2(x), 1 / (sh * sh), "inv_sinh2", x);
    check_close(sp::coth(x), std::cosh(Real(x)) / sh, "coth", x);
    check_close(sp::reciprocal_sine(x), 1 / Real(x), "reciprocal_sine", x);
  }
  // At the poles themselves the guards fire (the tests' handler throws).
  CHECK_THROWS_AS(sp::inv_sin2(Scalar(0)), CheckFailure);
  CHECK_THROWS_AS(sp::cot(Scalar(0)), CheckFailure);
  CHECK_THROWS_AS(sp::inv_sinh2(Scalar(0)), CheckFailure);
  CHECK_THROWS_AS(sp::coth(Scalar(0)), CheckFailure);
  CHECK_THROWS_AS(sp::reciprocal_sine(Scalar(0)), CheckFailure);
}

TEST_CASE_TEMPLATE("special: sn, cs, ctn, ctn' on S (R = 2), H (R = 2) and E", Scalar, float, double,
                   long double) {
  const Scalar pi = std::numbers::pi_v<Scalar>;
  // kappa = 1/4, -1/4: R = 2 exactly, so d / R and d sqrt|kappa| are exact.
  for (const Scalar kappa : {Scalar(0.25), Scalar(-0.25), Scalar(0)}) {
    std::vector<Scalar> ds = {Scalar(1e-8), std::ldexp(Scalar(1), -20), Scalar(0.5), Scalar(3)};
    if (kappa > 0) {
      ds.push_back(Scalar(2) * pi - std::ldexp(Scalar(1), -18));  // near the antipode, d = pi R
    }
    for (const Scalar d : ds) {
      const Real a = Real(d) / 2;
      const Real sn = kappa > 0 ? 2 * std::sin(a) : kappa < 0 ? 2 * std::sinh(a) : Real(d);
      const Real cs = kappa > 0 ? std::cos(a) : kappa < 0 ? std::cosh(a) : Real(1);
      INFO("kappa = ", double(kappa));
      check_close(sp::sn(kappa, d), sn, "sn", d);
      check_close(sp::cs(kappa, d), cs, "cs", d);
      check_close(sp::ctn(kappa, d), cs / sn, "ctn", d);
      check_close(sp::ctn_derivative(kappa, d), -1 / (sn * sn), "ctn_derivative", d);
    }
    CHECK_THROWS_AS(sp::ctn(kappa, Scalar(0)), CheckFailure);
    CHECK_THROWS_AS(sp::ctn_derivative(kappa, Scalar(0)), CheckFailure);
  }
  MESSAGE("largest relative error so far: ", double(worst_in_eps), " eps");
}

// atan2_fast (issue #27), against long double atan2l, in ulp of the reference's magnitude in Scalar.
// The bound, 2 ulp: the reduced argument u = mn / mx (or an exact Sterbenz numerator over a
// rounded denominator) is rounded by at most 0.5 ulp(u) in the unreduced branch, which is at most
// 1 ulp of the result (atan u = u (1 - u^2/3 + ...) can sit one binade below u, as for u just
// above 1/4); the last addition rounds by 0.5 ulp; the polynomial's own error (evaluated in long
// double over its range: 0.18 eps relative for Cephes atanf, 0.02 eps for fdlibm's, i.e. at most
// 0.36 and 0.04 ulp) and the roundings inside the tail u q(u^2) (|u q| < 0.07 |u|: < 0.07 ulp)
// add the rest: 1.93 ulp float, 1.61 ulp double. The reduced branches (|u| <= 0.19, result
// >= 0.43) carry far less of u's error. Measured here: 1.77 ulp float, 1.45 ulp double (-s).
namespace {

/// The distance of v from the reference in units of the reference's last place in Scalar.
template <class Scalar>
Real ulps(Scalar v, Real reference) {
  const Real r = std::abs(reference);
  int e = 0;
  std::frexp(r, &e);
  const Real ulp = std::max(std::ldexp(Real(1), e - std::numeric_limits<Scalar>::digits),
                            Real(std::numeric_limits<Scalar>::denorm_min()));
  return std::abs(Real(v) - reference) / ulp;
}

/// A fixed-seed uniform in [0, 1) from the raw bits of mt19937_64 (whose sequence the standard
/// fixes, unlike uniform_real_distribution's), so the arguments are the same on every platform.
double unit(std::mt19937_64& g) { return double(g() >> 11) * 0x1p-53; }

template <class Scalar>
Real worst_atan2_ulps(Scalar y, Scalar x, Real worst) {
  for (const Scalar sy : {y, -y}) {
    for (const Scalar sx : {x, -x}) {
      for (const auto& ab : {std::pair{sy, sx}, std::pair{sx, sy}}) {
        const Scalar a = ab.first, b = ab.second;  // (not a structured binding: INFO's lambda captures them)
        const Real e = ulps(sp::atan2_fast(a, b), std::atan2(Real(a), Real(b)));
        if (!(e <= 2)) {  // 2 ulp: the derivation above
          INFO("atan2_fast(", double(a), ", ", double(b), ") = ", double(sp::atan2_fast(a, b)), ", ",
               double(e), " ulp from atan2l");
          CHECK(e <= 2);
        }
        worst = std::max(worst, e);
      }
    }
  }
  return worst;
}

}  // namespace

TEST_CASE_TEMPLATE("special: atan2_fast within 2 ulp of long double atan2l", Scalar, float, double) {
  using L = std::numeric_limits<Scalar>;
  Real worst = 0;
  // Ratios y/x at the special points: tiny, near tan(pi/8) and the reduction switches 13/32,
  // 7/16 and 11/16, near 1 (y = x, the octant switch), and their neighbours one and two ulp off.
  const Scalar tan_pi8 = Scalar(std::numbers::sqrt2_v<long double> - 1);
  std::vector<Scalar> ratios = {Scalar(0),       L::denorm_min(),  L::min(),         Scalar(1e-30),
                                Scalar(1e-8),    Scalar(0.01),     tan_pi8,          Scalar(0.40625),
                                Scalar(0.4375),  Scalar(0.5),      Scalar(0.6875),   Scalar(1),
                                Scalar(1) / tan_pi8};
  for (std::size_t i = 0, n = ratios.size(); i < n; ++i) {
    Scalar up = ratios[i], down = ratios[i];
    for (int k = 0; k < 2; ++k) {
      up = std::nextafter(up, L::infinity());
      down = std::nextafter(down, Scalar(0));
      ratios.push_back(up);
      ratios.push_back(down);
    }
  }
  // x over the whole exponent range, subnormal to near the largest (where 2 x + y would overflow).
  for (const Scalar x : {L::denorm_min() * Scalar(1024), L::min(), Scalar(1e-10), Scalar(1), Scalar(2),
                         Scalar(3e10), L::max() / Scalar(2), L::max()}) {
    for (const Scalar r : ratios) worst = worst_atan2_ulps(Scalar(x * r), x, worst);
  }
  // Random pairs: x log-uniform over the exponent range, the ratio log-uniform over 2^-60..2^60
  // (a third of them within a factor 2^4 of 1, where the reduction switches sit), or just above
  // 1/4, where u = y/x rounds in a binade above its arctangent (the worst case of the bound).
  std::mt19937_64 g(27);
  const int e_lo = L::min_exponent - L::digits, e_hi = L::max_exponent - 64;
  for (int i = 0; i < 150000; ++i) {
    const Scalar x = std::ldexp(Scalar(1 + unit(g)), e_lo + int((e_hi - e_lo) * unit(g)));
    const int spread = i % 3 == 0 ? 60 : 2;
    const Scalar r = i % 3 == 2 ? Scalar(0.25 + unit(g) / 128)
                                : std::ldexp(Scalar(1 + unit(g)), -spread + int(2 * spread * unit(g)) - 1);
    worst = worst_atan2_ulps(Scalar(x * r), x, worst);
  }
  MESSAGE("atan2_fast: largest error ", double(worst), " ulp");
}

TEST_CASE_TEMPLATE("special: atan2_fast signed zeros, axes and NaN", Scalar, float, double) {
  const Scalar pi = std::numbers::pi_v<Scalar>, nan = std::numeric_limits<Scalar>::quiet_NaN();
  // IEEE 754 atan2 at the zeros: the sign of y is kept, x = -0 or x < 0 gives +-pi.
  CHECK(sp::atan2_fast(Scalar(0), Scalar(0)) == Scalar(0));
  CHECK(!std::signbit(sp::atan2_fast(Scalar(0), Scalar(0))));
  CHECK(std::signbit(sp::atan2_fast(-Scalar(0), Scalar(0))));
  CHECK(sp::atan2_fast(Scalar(0), -Scalar(0)) == pi);
  CHECK(sp::atan2_fast(-Scalar(0), -Scalar(0)) == -pi);
  CHECK(sp::atan2_fast(Scalar(0), Scalar(-3)) == pi);
  CHECK(sp::atan2_fast(-Scalar(0), Scalar(-3)) == -pi);
  CHECK(sp::atan2_fast(Scalar(0), Scalar(3)) == Scalar(0));
  // On the axes the result is a correctly rounded constant (the reduction's u is 0).
  CHECK(sp::atan2_fast(Scalar(5), Scalar(0)) == pi / Scalar(2));
  CHECK(sp::atan2_fast(Scalar(-5), -Scalar(0)) == -pi / Scalar(2));
  CHECK(sp::atan2_fast(Scalar(5), Scalar(5)) == pi / Scalar(4));
  // NaN in, NaN out, in either argument.
  CHECK(std::isnan(sp::atan2_fast(nan, Scalar(1))));
  CHECK(std::isnan(sp::atan2_fast(Scalar(1), nan)));
  CHECK(std::isnan(sp::atan2_fast(nan, -Scalar(0))));
  CHECK(std::isnan(sp::atan2_fast(Scalar(0), nan)));
}

// sincos_fast (issue #27: the charts' trig caches), against long double sinl and cosl. The bound,
// 1 ulp: fdlibm's for its sin and cos, whose reduction (to 118 bits of pi/2, 151 where 49 bits
// cancel) and kernels (|polynomial error| < 2^-58 relative, the tail y1 carried) these are; the
// last addition rounds by 0.5 ulp and the rest stays well below another 0.5. Measured: 0.78 ulp.
// Arguments: log-uniform magnitudes 2^-30..2^19 of both signs (fixed seed), and the doubles
// nearest k pi/2 and their neighbours for |k| <= 2^18 (where the reduction cancels most).
TEST_CASE("special: sincos_fast within 1 ulp of long double sinl, cosl") {
  Real worst = 0;
  const auto check = [&](double x) {
    double s = 0, c = 0;
    sp::sincos_fast(x, s, c);
    const Real es = ulps(s, std::sin(Real(x))), ec = ulps(c, std::cos(Real(x)));
    if (!(es <= 1 && ec <= 1)) {
      INFO("sincos_fast(", x, ") = ", s, ", ", c, ": ", double(es), " and ", double(ec), " ulp from sinl, cosl");
      CHECK((es <= 1 && ec <= 1));
    }
    worst = std::max({worst, es, ec});
  };
  std::mt19937_64 g(27);
  for (int i = 0; i < 400000; ++i) {
    const double x = std::ldexp(1 + unit(g), -30 + int(49 * unit(g)));
    check(i % 2 == 0 ? x : -x);
  }
  for (long k = -(1L << 18); k <= (1L << 18); ++k) {
    const double x = double(k) * std::numbers::pi / 2;
    check(x);
    check(std::nextafter(x, 1e300));
    check(std::nextafter(x, -1e300));
  }
  MESSAGE("sincos_fast: largest error ", double(worst), " ulp");
}

TEST_CASE("special: sincos_fast at zeros, tiny, huge and non-finite arguments") {
  const double nan = std::numeric_limits<double>::quiet_NaN(), inf = std::numeric_limits<double>::infinity();
  double s = 1, c = 0;
  sp::sincos_fast(0.0, s, c);
  CHECK((s == 0 && !std::signbit(s) && c == 1));
  sp::sincos_fast(-0.0, s, c);
  CHECK((s == 0 && std::signbit(s) && c == 1));
  const double tiny = std::numeric_limits<double>::denorm_min();
  sp::sincos_fast(tiny, s, c);
  CHECK((s == tiny && c == 1));
  // Beyond sincos_limit: the C library's values, bit for bit.
  for (const double x : {std::nextafter(sp::sincos_limit, inf), 1e6, -3e9, 1e300}) {
    sp::sincos_fast(x, s, c);
    CHECK((s == std::sin(x) && c == std::cos(x)));
  }
  for (const double x : {nan, inf, -inf}) {
    sp::sincos_fast(x, s, c);
    CHECK((std::isnan(s) && std::isnan(c)));
  }
}

TEST_CASE("special: sincos_many gives sincos_fast's bits at every vector width") {
  std::mt19937_64 g(5);
  std::vector<double> x(1003);  // not a multiple of any width
  for (std::size_t i = 0; i < x.size(); ++i) x[i] = std::ldexp(unit(g) - 0.5, int(i % 40) - 20);
  x[7] = 1e7;  // beyond sincos_limit: the library
  x[8] = std::numeric_limits<double>::quiet_NaN();
  x[9] = -std::numeric_limits<double>::infinity();
  x[10] = -0.0;
  const int n = int(x.size());
  std::vector<double> s(x.size()), c(x.size());
  const auto same_bits = [](double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; };
  using sesi::simd::Level;
  for (const Level level : {Level::base, Level::avx2, Level::avx512}) {
    if (static_cast<int>(level) > static_cast<int>(sesi::simd::supported())) continue;
    sesi::simd::set_level(level);
    sp::sincos_many(x.data(), s.data(), c.data(), n);
    int differ = 0;
    for (int i = 0; i < n; ++i) {
      double s1 = 0, c1 = 0;
      sp::sincos_fast(x[std::size_t(i)], s1, c1);
      if (!same_bits(s1, s[std::size_t(i)]) || !same_bits(c1, c[std::size_t(i)])) ++differ;
    }
    INFO("level ", static_cast<int>(level));
    CHECK(differ == 0);
  }
  sesi::simd::set_level(sesi::simd::supported());
}

// atan2_sqrt_fast(y2, x2) = atan2(sqrt y2, sqrt x2): bound 3.5 ulp, derived in its doc comment
// (special_functions.hpp: 1.25 eps in the reduced argument, up to 2.5 ulp a binade below it,
// plus atan2_fast's last rounding and polynomial). Double: squared lengths 2^-40..2^40 (so that
// y2 x2 stays in the domain), ratios as for atan2_fast (1/16 = (1/4)^2 is the worst case);
// float: squared lengths 2^-20..2^20 and ratios down to 2^-41, so that y2 x2 >= 2^-81 is normal.
TEST_CASE_TEMPLATE("special: atan2_sqrt_fast within 3.5 ulp of long double atan2l", Scalar, float, double) {
  std::mt19937_64 g(2727);
  Real worst = 0;
  for (int i = 0; i < 150000; ++i) {
    constexpr bool is_float = std::is_same_v<Scalar, float>;
    const Scalar x2 = is_float ? std::ldexp(Scalar(1 + unit(g)), -20 + int(40 * unit(g)))
                               : std::ldexp(Scalar(1 + unit(g)), -40 + int(80 * unit(g)));
    const int spread = i % 3 == 0 ? (is_float ? 40 : 120) : 4;
    const Scalar r = i % 3 == 2 ? Scalar(0.0625 * (1 + unit(g) / 64))
                                : std::ldexp(Scalar(1 + unit(g)), -spread + int(2 * spread * unit(g)) - 1);
    for (const auto& ab : {std::pair{Scalar(x2 * r), x2}, std::pair{x2, Scalar(x2 * r)}}) {
      const Scalar a = ab.first, b = ab.second;  // (not a structured binding: INFO's lambda captures them)
      const Scalar v = sp::atan2_sqrt_fast(a, b);
      const Real e = ulps(v, std::atan2(std::sqrt(Real(a)), std::sqrt(Real(b))));
      if (!(e <= Real(3.5))) {  // 3.5 ulp: the derivation above
        INFO("atan2_sqrt_fast(", double(a), ", ", double(b), ") = ", double(v), ", ", double(e), " ulp");
        CHECK(e <= Real(3.5));
      }
      worst = std::max(worst, e);
    }
  }
  CHECK(sp::atan2_sqrt_fast(Scalar(0), Scalar(0)) == Scalar(0));
  CHECK(sp::atan2_sqrt_fast(Scalar(0), Scalar(2)) == Scalar(0));
  CHECK(sp::atan2_sqrt_fast(Scalar(2), Scalar(0)) == std::numbers::pi_v<Scalar> / Scalar(2));
  CHECK(sp::atan2_sqrt_fast(Scalar(2), Scalar(2)) == std::numbers::pi_v<Scalar> / Scalar(4));
  CHECK(std::isnan(sp::atan2_sqrt_fast(std::numeric_limits<Scalar>::quiet_NaN(), Scalar(1))));
  CHECK(std::isnan(sp::atan2_sqrt_fast(Scalar(1), std::numeric_limits<Scalar>::quiet_NaN())));
  MESSAGE("atan2_sqrt_fast: largest error ", double(worst), " ulp");
}

TEST_CASE_TEMPLATE("special: Sphere<2> distance with atan2_fast near 0 and at the antipode", Scalar,
                   float, double) {
  // d = 2R atan2(|x - y|, |x + y|) against the same formula in long double on long double copies
  // of the same points (so the points' own rounding is not counted). Bound: atan2_fast's 2 ulp,
  // plus each norm's rounding (sum of 3 rounded squares and a sqrt: 2.5 eps relative) carried
  // into atan2 with a factor d(atan2)/d(log a) = ab/(a^2 + b^2) <= 1/2 per norm (2.5 eps), and the
  // product 2R * angle (0.5 eps): 2 ulp (<= 4 eps relative) + 3 eps = 7 eps relative.
  const Scalar radius = Scalar(3);
  const sesi::Sphere<2, Scalar> sphere(radius);
  using V = Eigen::Matrix<Scalar, 3, 1>;
  using VL = Eigen::Matrix<Real, 3, 1>;
  const Real pi = std::numbers::pi_v<Real>;
  Real worst = 0;
  for (const Real angle : {Real(0), Real(1e-30), Real(1e-8), Real(1e-3), Real(0.5), Real(1), pi / 2, pi - Real(0.5),
                           pi - Real(1e-3), pi - Real(1e-6), pi - Real(3e-8), pi}) {
    // x on a generic direction, y turned from it by `angle` in a generic plane.
    const VL e1 = VL(Real(0.6), Real(0.64), Real(0.48)), e2 = VL(Real(0.8), Real(-0.48), Real(-0.36));
    const V x = (Real(radius) * e1).template cast<Scalar>();
    const V y = (Real(radius) * (std::cos(angle) * e1 + std::sin(angle) * e2)).template cast<Scalar>();
    const VL xl = x.template cast<Real>(), yl = y.template cast<Real>();
    const Real reference = 2 * Real(radius) * std::atan2((xl - yl).norm(), (xl + yl).norm());
    const Scalar d = sphere.distance(x, y);
    sesi::PairGeometry<Scalar> pair = sphere.pair_geometry(x, y);
    const Scalar d_of = sphere.distance_of(pair);
    if (reference == 0) {
      CHECK(d == Scalar(0));
      CHECK(d_of == Scalar(0));
      continue;
    }
    const Real eps_s = Real(std::numeric_limits<Scalar>::epsilon());
    const Real rel = std::abs(Real(d) - reference) / reference, rel_of = std::abs(Real(d_of) - reference) / reference;
    worst = std::max({worst, rel / eps_s, rel_of / eps_s});
    INFO("angle ", double(angle), ": distance ", double(d), ", distance_of ", double(d_of), ", reference ",
         double(reference));
    CHECK(rel <= 7 * eps_s);  // the derivation above
    // distance_of: atan2_sqrt_fast's 3.5 ulp (<= 7 eps relative), the squared norms' 2.5 eps each
    // carried with a factor <= 1/4 (1.25 eps) and the product 2R * angle (0.5 eps): 9 eps.
    CHECK(rel_of <= 9 * eps_s);
  }
  MESSAGE("Sphere distance: largest relative error ", double(worst), " eps");
}
