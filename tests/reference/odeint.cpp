// The odeint adapter (sesi/odeint.hpp's chart_ode) and drivers (sesi/reference/odeint.hpp): the
// chart ODE is Hamilton's equations, RK4 has order 4, the adaptive methods' errors fall with the
// tolerance, evaluations are counted, sampling reaches 1000 times without disturbing the steps,
// and reference steppers work under odeint's integrate functions.
#include <cmath>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include <boost/numeric/odeint/integrate/integrate_const.hpp>
#include <doctest/doctest.h>
#include <sesi/reference/odeint.hpp>
#include <sesi/reference/implicit.hpp>

#include "common.hpp"

namespace {
namespace R = sesi::reference;
namespace paper = reftest::paper;
using Chart = paper::Chart<double>;

/// Largest distance of the three bodies from the exact solution at t.
double position_error(const sesi::State<Chart>& x, double t) {
  const auto sys = paper::make_system<double>();
  const paper::Exact exact;
  double worst = 0;
  for (int b = 0; b < 3; ++b) {
    Eigen::Vector3d p;
    sys.chart().embed(Eigen::Vector2d(x.q.col(b)), p);
    worst = std::max(worst, (p - exact.position(b, t).cast<double>()).norm());
  }
  return worst;
}

std::vector<double> uniform_times(double t0, double t1, int n) {
  std::vector<double> t(static_cast<std::size_t>(n) + 1);
  for (int k = 0; k <= n; ++k) t[static_cast<std::size_t>(k)] = t0 + (t1 - t0) * k / n;
  return t;
}
}  // namespace

TEST_CASE("the chart ODE is Hamilton's equations: it matches central differences of H") {
  // Central differences of H with step d have error d^2/6 |H'''| + eps |H| / d; with d = 1e-5
  // and derivatives of order one, both are below 1e-9.
  auto check = [](const auto& sys, auto x) {
    R::HamiltonianField<std::remove_cvref_t<decltype(sys)>> f(sys);
    auto dx = x;
    f(x, dx);
    CHECK(f.evaluations() == 1);
    const double d = 1e-5;
    for (int b = 0; b < x.bodies(); ++b) {
      for (int i = 0; i < sys.dim(); ++i) {
        auto a = x, c = x;
        a.p(i, b) += d;
        c.p(i, b) -= d;
        const double dh_dp = (sys.energy(a) - sys.energy(c)) / (2 * d);
        a = x;
        c = x;
        a.q(i, b) += d;
        c.q(i, b) -= d;
        const double dh_dq = (sys.energy(a) - sys.energy(c)) / (2 * d);
        CHECK(dx.q(i, b) == doctest::Approx(dh_dp).epsilon(1e-9).scale(1));
        CHECK(dx.p(i, b) == doctest::Approx(-dh_dq).epsilon(1e-9).scale(1));
      }
    }
  };
  check(paper::make_system<double>(), paper::initial_state<double>());
  check(reftest::hyperbolic_system<double>(), reftest::hyperbolic_initial<double>());
  check(reftest::sphere3_system<double>(), reftest::sphere3_initial<double>());
}

TEST_CASE("flat vectors round-trip a state") {
  const auto sys = paper::make_system<double>();
  sesi::odeint::chart_ode<decltype(sys)> ode(sys);
  const auto x = paper::initial_state<double>();
  const auto y = ode.flat(x);
  CHECK(y.size() == R::flat_size(x));
  sesi::State<Chart> back;
  ode.unflat(y, back);
  CHECK(back.q == x.q);
  CHECK(back.p == x.p);
}

TEST_CASE("RK4 on the chart ODE has order 4 and 4 evaluations per step") {
  const auto sys = paper::make_system<double>();
  const auto x0 = paper::initial_state<double>();
  auto final_state = [&](long steps) {
    const auto r = sesi::odeint::integrate_rk4(sys, x0, 0.0, 10.0, 10.0 / double(steps));
    CHECK(r.steps == std::size_t(steps));
    CHECK(r.evaluations == 4 * std::size_t(steps));
    return r.state;
  };
  const auto a = final_state(100), b = final_state(200), c = final_state(400);
  const double order = std::log2(reftest::distance(a, b) / reftest::distance(b, c));
  MESSAGE("rk4 order ", order);
  CHECK(std::abs(order - 4) < 0.3);
}

TEST_CASE("adaptive methods: the error falls with the tolerance") {
  // Tolerance proportionality: the global error of a controlled method scales like the
  // tolerance, so a tolerance 100 times smaller must give an error at least 10 times smaller.
  const auto sys = paper::make_system<double>();
  const auto x0 = paper::initial_state<double>();
  const double t1 = 10;
  for (const std::string name : {"dopri5", "fehlberg78", "bulirsch_stoer"}) {
    double previous = std::numeric_limits<double>::infinity();
    for (double tol : {1e-6, 1e-8, 1e-10}) {
      const sesi::odeint::tolerances<double> tl{tol, tol, 1e-2};
      const auto r = name == "dopri5" ? sesi::odeint::integrate_dopri5(sys, x0, 0.0, t1, tl)
                     : name == "fehlberg78"
                         ? sesi::odeint::integrate_fehlberg78(sys, x0, 0.0, t1, tl)
                         : sesi::odeint::integrate_bulirsch_stoer(sys, x0, 0.0, t1, tl);
      const double err = position_error(r.state, t1);
      MESSAGE(name, " tol ", tol, ": error ", err, ", ", r.steps, " steps, ", r.evaluations,
              " evaluations");
      CHECK(err < previous / 10);
      CHECK(r.evaluations > r.steps);
      previous = err;
    }
  }
}

TEST_CASE("dopri5 counts 6 evaluations per attempted step (first same as last)") {
  const auto sys = paper::make_system<double>();
  const auto r = sesi::odeint::integrate_dopri5(sys, paper::initial_state<double>(), 0.0, 10.0,
                                                {1e-8, 1e-8, 1e-2});
  // One evaluation to start, then 6 per attempt (accepted or rejected).
  CHECK(r.evaluations >= 6 * r.steps + 1);
  CHECK((r.evaluations - 1) % 6 == 0);
}

TEST_CASE("sampling at 1001 times: every method observes them all, without changing the steps") {
  const auto sys = paper::make_system<double>();
  const auto x0 = paper::initial_state<double>();
  const double t1 = 100;
  const auto times = uniform_times(0, t1, 1000);
  const double e0 = sys.energy(x0);
  struct Log {
    std::vector<double> t;
    double max_error = 0;
  };
  auto observer = [&](Log& log) {
    return [&](const sesi::State<Chart>& s, double t) {
      log.t.push_back(t);
      log.max_error = std::max(log.max_error, std::abs(sys.energy(s) - e0));
    };
  };
  const sesi::odeint::tolerances<double> tol{1e-9, 1e-9, 1e-2};
  Log d, f, b, k;
  const auto rd = sesi::odeint::integrate_dopri5(sys, x0, 0.0, t1, tol, times, observer(d));
  const auto rf = sesi::odeint::integrate_fehlberg78(sys, x0, 0.0, t1, tol, times, observer(f));
  const auto rb = sesi::odeint::integrate_bulirsch_stoer(sys, x0, 0.0, t1, tol, times, observer(b));
  const auto rk = sesi::odeint::integrate_rk4(sys, x0, 0.0, t1, 0.05, times, observer(k));
  for (const Log* log : {&d, &f, &b}) {
    REQUIRE(log->t.size() == times.size());
    for (std::size_t i = 0; i < times.size(); ++i) CHECK(log->t[i] == doctest::Approx(times[i]));
  }
  // RK4 observes at its grid points (every second step of 0.05 here: all 1001 times).
  CHECK(k.t.size() == times.size());
  MESSAGE("max energy error at the samples: dopri5 ", d.max_error, ", fehlberg78 ", f.max_error,
          ", bulirsch-stoer ", b.max_error, ", rk4 ", k.max_error);
  // Dense output: the same steps as without sampling.
  const auto plain = sesi::odeint::integrate_dopri5(sys, x0, 0.0, t1, tol);
  CHECK(rd.steps <= plain.steps + 1);
  CHECK(rd.steps + 1 >= plain.steps);
  CHECK(reftest::distance(rd.state, plain.state) <= 1e-6);
  // RK4 sampling never changes a step: bit-identical to the unsampled run.
  const auto rk_plain = sesi::odeint::integrate_rk4(sys, x0, 0.0, t1, 0.05);
  CHECK(rk.state.q == rk_plain.state.q);
  CHECK(rk.state.p == rk_plain.state.p);
  (void)rf;
  (void)rb;
}

TEST_CASE("integrate_fixed observes the nearest grid point once, and ends at t1") {
  const auto sys = paper::make_system<double>();
  auto x = paper::initial_state<double>();
  sesi::Strang<Chart> st;
  std::vector<double> seen;
  const std::vector<double> times{0.0, 0.04, 0.26, 0.27, 0.5};
  const auto steps = R::integrate_fixed(st, sys, x, 0.0, 0.5, 0.1, std::span<const double>(times),
                                        [&](const auto&, double t) { seen.push_back(t); });
  CHECK(steps == 5);
  REQUIRE(seen.size() == 3);  // 0 (for 0 and 0.04), 0.3 (for 0.26 and 0.27), 0.5
  CHECK(seen[0] == 0.0);
  CHECK(seen[1] == doctest::Approx(0.3));
  CHECK(seen[2] == 0.5);
  // A span that is not a whole number of steps ends with a shorter step, exactly at t1.
  std::vector<double> last;
  const std::vector<double> end{0.45};
  auto y = paper::initial_state<double>();
  CHECK(R::integrate_fixed(st, sys, y, 0.0, 0.45, 0.1, std::span<const double>(end),
                           [&](const auto&, double t) { last.push_back(t); }) == 5);
  REQUIRE(last.size() == 1);
  CHECK(last[0] == 0.45);
}

TEST_CASE("reference steppers run under odeint's integrate_const") {
  // sesi::odeint::stepper adds odeint's stepper tag to any stepper with do_step(sys, x, t, dt).
  auto sys = paper::make_system<double>();
  auto x = paper::initial_state<double>();
  int observed = 0;
  const auto steps = boost::numeric::odeint::integrate_const(
      sesi::odeint::stepper<R::ImplicitMidpoint<Chart>>{}, std::ref(sys), x, 0.0, 1.0, 0.1,
      [&](const sesi::State<Chart>&, double) { ++observed; });
  CHECK(steps == 10);
  CHECK(observed == 11);
}
