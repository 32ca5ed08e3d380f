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
#include <cmath>
#include <limits>
#include <numbers>
#include <tuple>

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
