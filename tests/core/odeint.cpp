// odeint drives the steppers (issue #2; include/sesi/odeint.hpp): integrate_const and
// integrate_n_steps with an observer call it the right number of times, and the result equals a
// manual do_step loop bit for bit (same operations in the same order: no tolerance).
#include <cmath>
#include <functional>
#include <vector>

#include <boost/numeric/odeint/integrate/integrate_const.hpp>
#include <boost/numeric/odeint/integrate/integrate_n_steps.hpp>
#include <boost/ref.hpp>
#include <doctest/doctest.h>
#include <sesi/odeint.hpp>

#include "common.hpp"

namespace {

using namespace coretest;
namespace odeint = boost::numeric::odeint;

template <class Chart>
struct Observer {
  std::vector<sesi::State<Chart>>* states;
  std::vector<typename Chart::Scalar>* times;
  void operator()(const sesi::State<Chart>& x, typename Chart::Scalar t) const {
    states->push_back(x);
    times->push_back(t);
  }
};

template <class Stepper, class Chart>
void check_integrate_const() {
  using Scalar = typename Chart::Scalar;
  static_assert(std::is_same_v<typename Stepper::stepper_category, odeint::stepper_tag>);
  const auto sys = make_scene<Chart>();
  const auto x0 = initial_state(sys);
  // dt = 1/64 and t_end = 1 are exact: 64 steps, and the observer sees t = 0, 1/64, ..., 1.
  const Scalar dt = Scalar(1) / Scalar(64), t_end = Scalar(1);
  const int steps = 64;

  std::vector<sesi::State<Chart>> states;
  std::vector<Scalar> times;
  auto x = x0;
  const std::size_t n = odeint::integrate_const(Stepper(), std::cref(sys), x, Scalar(0), t_end, dt,
                                                Observer<Chart>{&states, &times});
  CHECK(n == std::size_t(steps));
  REQUIRE(states.size() == std::size_t(steps + 1));

  // The manual loop, observed the same way.
  Stepper manual;
  auto y = x0;
  for (int k = 0; k <= steps; ++k) {
    CHECK(times[std::size_t(k)] == Scalar(k) * dt);
    CHECK(states[std::size_t(k)].q == y.q);  // bit for bit
    CHECK(states[std::size_t(k)].p == y.p);
    if (k < steps) manual.do_step(sys, y, Scalar(k) * dt, dt);
  }
  CHECK(x.q == y.q);
  CHECK(x.p == y.p);

  // integrate_n_steps, with the system by boost::ref: the same result.
  auto z = x0;
  std::vector<sesi::State<Chart>> zs;
  std::vector<Scalar> zt;
  odeint::integrate_n_steps(Stepper(), boost::ref(sys), z, Scalar(0), dt, steps,
                            Observer<Chart>{&zs, &zt});
  CHECK(zs.size() == std::size_t(steps + 1));
  CHECK(z.q == y.q);
  CHECK(z.p == y.p);
}

}  // namespace

TEST_CASE("odeint: integrate_const drives Strang and Yoshida4 on S^2, bit for bit") {
  check_integrate_const<sesi::odeint::strang<sesi::Sphere<2, double>>, sesi::Sphere<2, double>>();
  check_integrate_const<sesi::odeint::yoshida4<sesi::Sphere<2, double>>, sesi::Sphere<2, double>>();
}

TEST_CASE("odeint: integrate_const drives KahanLi8 on H^3 (long double) and a KDK form on E^2") {
  check_integrate_const<sesi::odeint::kahan_li8<sesi::Hyperbolic<3, long double>>,
                        sesi::Hyperbolic<3, long double>>();
  check_integrate_const<
      sesi::odeint::stepper<sesi::Composition<sesi::coefficients::Yoshida4,
                                              sesi::Euclidean<2, double>,
                                              sesi::Splitting::kick_drift_kick>>,
      sesi::Euclidean<2, double>>();
}
