// Every reference stepper in float and long double (double is the reference run): it compiles,
// and on the seed's scene it follows the double trajectory to the round-off of the coarser type.
// One translation unit for all, so that the scene's system is instantiated once per Scalar.
// Eigen's allocation guard is on in this translation unit, with Eigen's assertions recorded
// (also under NDEBUG): steps after the first two allocate nothing.
namespace reftest {
inline int& eigen_assertion_failures() {
  static int failures = 0;
  return failures;
}
}  // namespace reftest
#define EIGEN_RUNTIME_NO_MALLOC
#define eigen_assert(x)                                \
  do {                                                 \
    if (!(x)) ++::reftest::eigen_assertion_failures(); \
  } while (false)
#include <cmath>
#include <limits>

#include <doctest/doctest.h>
#include <sesi/reference/embedding.hpp>
#include <sesi/reference/implicit.hpp>
#include <sesi/reference/tao.hpp>

#include "common.hpp"

namespace {
namespace R = sesi::reference;
namespace paper = reftest::paper;

/// 100 steps of 0.1 of a stepper template M on the seed's scene in Scalar, from the chart state
/// (Embedded = false) or from its embedding; the result as double.
template <template <class> class M, bool Embedded, class Scalar>
auto hundred_steps() {
  const auto sys = paper::make_system<Scalar>();
  M<paper::Chart<Scalar>> st;
  const Scalar h(0.1);
  if constexpr (Embedded) {
    auto e = R::to_embedded(sys, paper::initial_state<Scalar>());
    for (int k = 0; k < 100; ++k) st.do_step(sys, e, Scalar(k) * h, h);
    R::EmbeddedState<paper::Chart<double>> out;
    out.x = e.x.template cast<double>();
    out.v = e.v.template cast<double>();
    return out;
  } else {
    auto x = paper::initial_state<Scalar>();
    for (int k = 0; k < 100; ++k) st.do_step(sys, x, Scalar(k) * h, h);
    sesi::State<paper::Chart<double>> out;
    out.q = x.q.template cast<double>();
    out.p = x.p.template cast<double>();
    return out;
  }
}

/// The Scalar run stays within 100 steps x 10 operations of round-off of the double run (the
/// orbit is integrable, so round-off grows linearly), in the coarser of the two precisions.
template <template <class> class M, bool Embedded, class Scalar>
void check_against_double() {
  const double unit = std::max(double(std::numeric_limits<Scalar>::epsilon()),
                               std::numeric_limits<double>::epsilon());
  const double d =
      reftest::distance(hundred_steps<M, Embedded, Scalar>(), hundred_steps<M, Embedded, double>());
  MESSAGE("distance to the double run: ", d, " (bound ", 100 * 10 * unit, ")");
  CHECK(d <= 100 * 10 * unit);
}

template <class C>
using Tao4 = R::Tao4<C>;
template <class C>
using Gauss4 = R::Gauss4<C>;
template <class C>
using Rattle = R::Rattle<C>;
template <class C>
using Geodesic4 = R::Geodesic4<C>;
}  // namespace

TEST_CASE_TEMPLATE("reference steppers in float and long double follow the double run", Scalar,
                   float, long double) {
  check_against_double<Gauss4, false, Scalar>();
  check_against_double<Tao4, false, Scalar>();
  check_against_double<Rattle, true, Scalar>();
  check_against_double<Geodesic4, true, Scalar>();

  // Gauss 4 converges in Scalar's own round-off; the embedding invariants hold in it.
  const auto sys = paper::make_system<Scalar>();
  auto x = paper::initial_state<Scalar>();
  R::Gauss4<paper::Chart<Scalar>> g;
  for (int k = 0; k < 100; ++k) g.do_step(sys, x, Scalar(k) / 10, Scalar(0.1));
  CHECK(g.statistics().unconverged == 0);
  auto e = R::to_embedded(sys, paper::initial_state<Scalar>());
  R::Geodesic4<paper::Chart<Scalar>> geo;
  for (int k = 0; k < 100; ++k) geo.do_step(sys, e, Scalar(k) / 10, Scalar(0.1));
  const double eps = double(std::numeric_limits<Scalar>::epsilon());
  for (int i = 0; i < 3; ++i) {
    CHECK(std::abs(double(e.x.col(i).squaredNorm() - 1)) <= 64 * eps);
    CHECK(std::abs(double(e.x.col(i).dot(e.v.col(i)))) <= 64 * eps);
  }
}

namespace {
/// Two steps to size the scratch space, then 20 with Eigen's allocator forbidden (an
/// allocation would fail Eigen's assertion).
template <class St, class Sys, class X>
void steps_without_allocation(const Sys& sys, X x) {
  using Scalar = typename Sys::Scalar;
  St st;
  const Scalar h(0.1);
  st.do_step(sys, x, Scalar(0), h);
  st.do_step(sys, x, h, h);
  Eigen::internal::set_is_malloc_allowed(false);
  for (int k = 2; k < 22; ++k) st.do_step(sys, x, Scalar(k) * h, h);
  Eigen::internal::set_is_malloc_allowed(true);
}
}  // namespace

TEST_CASE_TEMPLATE("reference steps allocate nothing once sized", Scalar, float, long double) {
  const auto sys = paper::make_system<Scalar>();
  const auto x = paper::initial_state<Scalar>();
  using C = paper::Chart<Scalar>;
  steps_without_allocation<R::Gauss4<C>>(sys, x);
  steps_without_allocation<R::Tao4<C>>(sys, x);
  steps_without_allocation<R::Rattle<C>>(sys, R::to_embedded(sys, x));
  steps_without_allocation<R::Geodesic4<C>>(sys, R::to_embedded(sys, x));
  CHECK(reftest::eigen_assertion_failures() == 0);
  // The guard works: an allocation while forbidden is recorded.
  Eigen::internal::set_is_malloc_allowed(false);
  Eigen::MatrixXd m(3, 3);
  Eigen::internal::set_is_malloc_allowed(true);
  CHECK(reftest::eigen_assertion_failures() == 1);
  reftest::eigen_assertion_failures() = 0;
  m.setZero();
}
