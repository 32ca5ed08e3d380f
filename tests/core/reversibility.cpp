// Time reversibility: a step of tau then a step of -tau returns the state to round-off
// (issue #2). Every method is a palindromic composition of exact flows and kicks, so
// S(-tau) S(tau) = id exactly in real arithmetic (HLW V.1); what is left is round-off.
//
// The bound: a step applies, per stage and body, 2n level flows and one kick (2n + 1
// sub-steps); each adds an increment computed with a relative error of a few eps (a product
// of at most n sines and 3 factors) and rounds the sum once, so the error it leaves is at most
// about (n + 4) eps times the size of the state (the increments are smaller than the state at
// these steps). The Jacobians of the sub-steps are 1 + O(tau) and do not amplify at tau = 0.1.
// Two steps of s stages: bound = 2 s (2n + 1) (n + 4) eps max(1, |z|_max).
// A reversibility bug (an unfused or doubled half flow, a stale trig cache) leaves O(tau)
// errors, 1e-2 or more: orders of magnitude above the bound.
#include <cmath>
#include <random>
#include <tuple>

#include <doctest/doctest.h>

#include "common.hpp"

namespace {

using namespace coretest;
namespace co = sesi::coefficients;

template <class Method, class Chart>
void check_reversible(typename Chart::Scalar tau, int states) {
  using Scalar = typename Chart::Scalar;
  const auto sys = make_scene<Chart>();
  std::mt19937 rng(5);
  Method stepper;
  for (int s = 0; s < states; ++s) {
    const auto x0 = random_state(sys, rng);
    auto x = x0;
    stepper.do_step(sys, x, Scalar(0), tau);
    stepper.do_step(sys, x, tau, -tau);
    const Scalar n = Scalar(sys.dim());
    const Scalar bound = Scalar(2 * Method::table::stages) * (Scalar(2) * n + Scalar(1)) *
                         (n + Scalar(4)) * eps<Scalar>() * size_of(x0);
    const Scalar err = distance(x, x0);
    MESSAGE(Method::table::name, " error/bound ", double(err / bound));
    CHECK(err <= bound);
  }
}

}  // namespace

TEST_CASE_TEMPLATE_DEFINE("reversibility: Yoshida4 on every space and dimension", Chart,
                          reversible_spaces) {
  check_reversible<sesi::Yoshida4<Chart>, Chart>(typename Chart::Scalar(0.1), 4);
}
TEST_CASE_TEMPLATE_APPLY(reversible_spaces, AllCharts<double>);

using Tables = std::tuple<co::Strang, co::Yoshida4, co::Suzuki4, co::McLachlan4, co::Yoshida6,
                          co::KahanLi6, co::McLachlan8, co::KahanLi8>;
// Through the runtime table's engine, bit for bit the compile-time one (common.hpp).
TEST_CASE_TEMPLATE_DEFINE("reversibility: every method, both forms, on S^3", Table,
                          reversible_methods) {
  using Chart = sesi::Sphere<3, double>;
  check_reversible<RuntimeComposition<Table, Chart>, Chart>(0.1, 3);
  check_reversible<RuntimeComposition<Table, Chart, sesi::Splitting::kick_drift_kick>, Chart>(0.1, 3);
}
TEST_CASE_TEMPLATE_APPLY(reversible_methods, Tables);

TEST_CASE_TEMPLATE("reversibility: Strang, both forms, in float, double and long double on H^2",
                   Scalar, float, double, long double) {
  using Chart = sesi::Hyperbolic<2, Scalar>;
  check_reversible<sesi::Strang<Chart>, Chart>(Scalar(0.1), 4);
  check_reversible<sesi::Composition<co::Strang, Chart, sesi::Splitting::kick_drift_kick>, Chart>(
      Scalar(0.1), 4);
}
