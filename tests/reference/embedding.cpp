// Embedding-space references (reference/embedding.hpp): conversions, the orders of RATTLE and
// of the geodesic splittings, bounded energy, the invariants, the w -> 0 limit, and agreement
// with the chart steppers.
#include <cmath>
#include <limits>
#include <string>

#include <doctest/doctest.h>
#include <sesi/reference/embedding.hpp>

#include "common.hpp"

namespace {
namespace R = sesi::reference;
using reftest::measured_order;
namespace paper = reftest::paper;
using Strang = sesi::coefficients::Strang;
using Yoshida4 = sesi::coefficients::Yoshida4;

template <class C>
using Rattle4 = R::RattleComposition<Yoshida4, C>;
template <class C>
using Geodesic2Kdk = R::GeodesicComposition<Strang, C, sesi::Splitting::kick_drift_kick>;

/// Largest invariant residuals of an embedding state, relative to R^2 (constraint) and R |v|
/// (tangency).
template <class Sys>
double residual(const Sys& sys, const R::EmbeddedState<typename Sys::Chart>& e) {
  using Q = R::Quadric<typename Sys::Chart>;
  const double r = double(sys.chart().radius());
  double worst = 0;
  for (int b = 0; b < e.bodies(); ++b) {
    const double xx = double(Q::dot(e.x.col(b), e.x.col(b)));
    const double speed = std::sqrt(std::abs(double(Q::dot(e.v.col(b), e.v.col(b))))) + 1e-300;
    worst = std::max(worst, std::abs(xx - Q::sign * r * r) / (r * r));
    worst = std::max(worst, std::abs(double(Q::dot(e.x.col(b), e.v.col(b)))) / (r * speed));
  }
  return worst;
}

/// Orders of every embedding method on one problem (chart initial state x0, T, N steps).
template <class Sys>
void check_orders(const std::string& name, const Sys& sys,
                  const sesi::State<typename Sys::Chart>& x0, double t_end, long steps) {
  using C = typename Sys::Chart;
  const auto e0 = R::to_embedded(sys, x0);
  const double rattle = measured_order<R::Rattle<C>>(sys, e0, t_end, steps);
  const double rattle4 = measured_order<Rattle4<C>>(sys, e0, t_end, steps);
  const double geo2 = measured_order<R::Geodesic2<C>>(sys, e0, t_end, steps);
  const double geo2kdk = measured_order<Geodesic2Kdk<C>>(sys, e0, t_end, steps);
  const double geo4 = measured_order<R::Geodesic4<C>>(sys, e0, t_end, steps);
  const double geo6 = measured_order<R::Geodesic6<C>>(sys, e0, t_end, steps);
  MESSAGE(name, ": rattle ", rattle, ", rattle4 ", rattle4, ", geodesic2 ", geo2, " (kdk ", geo2kdk,
          "), geodesic4 ", geo4, ", geodesic6 ", geo6);
  CHECK(std::abs(rattle - 2) < 0.3);
  CHECK(std::abs(rattle4 - 4) < 0.3);
  CHECK(std::abs(geo2 - 2) < 0.3);
  CHECK(std::abs(geo2kdk - 2) < 0.3);
  CHECK(std::abs(geo4 - 4) < 0.3);
  CHECK(std::abs(geo6 - 6) < 0.3);
}

}  // namespace

TEST_CASE("chart and embedding states convert both ways") {
  auto check = [](const auto& sys, const auto& x) {
    const double eps = std::numeric_limits<double>::epsilon();
    const auto e = R::to_embedded(sys, x);
    CHECK(residual(sys, e) <= 16 * eps);
    const auto back = R::to_chart(sys, e);
    // Angles come back in their principal ranges: compare the embeddings and the momenta.
    const auto again = R::to_embedded(sys, back);
    CHECK((again.x - e.x).cwiseAbs().maxCoeff() <= 64 * eps);
    CHECK((again.v - e.v).cwiseAbs().maxCoeff() <= 64 * eps);
    CHECK((back.p - x.p).cwiseAbs().maxCoeff() <= 64 * eps);
    CHECK(double(R::energy(sys, e)) == doctest::Approx(double(sys.energy(x))).epsilon(1e-14));
  };
  check(paper::make_system<double>(), paper::initial_state<double>());
  check(reftest::hyperbolic_system<double>(), reftest::hyperbolic_initial<double>());
  check(reftest::sphere3_system<double>(), reftest::sphere3_initial<double>());
}

TEST_CASE("RATTLE and the geodesic splittings converge at their orders") {
  check_orders("paper, T = 10", paper::make_system<double>(), paper::initial_state<double>(), 10,
               40);
  check_orders("H2, T = 3", reftest::hyperbolic_system<double>(),
               reftest::hyperbolic_initial<double>(), 3, 40);
  check_orders("S3, T = 3", reftest::sphere3_system<double>(), reftest::sphere3_initial<double>(),
               3, 40);
}

TEST_CASE("embedding methods keep the energy bounded and the invariants to round-off") {
  auto check = [](const std::string& name, const auto& sys, const auto& x0, double h) {
    using C = typename std::remove_cvref_t<decltype(sys)>::Chart;
    const auto e0 = R::to_embedded(sys, x0);
    auto energy = [&](const auto& e) { return R::energy(sys, e); };
    const auto rattle = reftest::energy_halves<R::Rattle<C>>(sys, e0, h, 800, energy);
    const auto geo2 = reftest::energy_halves<R::Geodesic2<C>>(sys, e0, h, 800, energy);
    const auto geo4 = reftest::energy_halves<R::Geodesic4<C>>(sys, e0, h, 800, energy);
    MESSAGE(name, ": rattle ", rattle.first, " / ", rattle.second, "; geodesic2 ", geo2.first,
            " / ", geo2.second, "; geodesic4 ", geo4.first, " / ", geo4.second);
    for (const auto& r : {rattle, geo2, geo4}) CHECK(r.second <= 1.5 * r.first);
    // Invariants after 800 / h steps: RATTLE solves its constraints exactly, the geodesic
    // splitting retracts once per step; both leave round-off only.
    auto a = e0, b = e0;
    R::Rattle<C> ra;
    R::Geodesic4<C> ge;
    const long steps = std::lround(800 / h);
    for (long k = 0; k < steps; ++k) {
      ra.do_step(sys, a, k * h, h);
      ge.do_step(sys, b, k * h, h);
    }
    const double eps = std::numeric_limits<double>::epsilon();
    CHECK(residual(sys, a) <= 64 * eps);
    CHECK(residual(sys, b) <= 64 * eps);
  };
  check("paper", paper::make_system<double>(), paper::initial_state<double>(), 0.1);
  // Chaotic scenes, in the embedding (no chart poles to pass near).
  check("H2", reftest::hyperbolic_system<double>(), reftest::hyperbolic_initial<double>(), 0.05);
  check("S3", reftest::sphere3_system<double>(), reftest::sphere3_initial<double>(), 0.05);
}

TEST_CASE("the geodesic flow is exact and finite as the speed goes to zero") {
  // One free body (no potential): the drift is the whole step and follows the great circle /
  // hyperbola exactly, also at zero speed and at speeds where w h is far below the series
  // threshold of sinc.
  auto check = [](auto chart, double speed) {
    using C = decltype(chart);
    sesi::System sys(chart, std::vector<double>{1.0});
    R::EmbeddedState<C> e(chart.ambient_dim(), 1);
    e.x.setZero();
    e.x(chart.ambient_dim() - 1, 0) = chart.radius();  // the pole / the hyperboloid's vertex
    e.v.setZero();
    e.v(0, 0) = speed;
    R::Geodesic2<C> st;
    const double t = 3;
    st.do_step(sys, e, 0.0, t);
    // Exact: x = R (sin, 0, .., cos) of the angle s t / R (sinh, cosh on H^n).
    const double r = chart.radius(), angle = speed * t / r;
    const bool sphere = R::Quadric<C>::sign > 0;
    const double along = r * (sphere ? std::sin(angle) : std::sinh(angle));
    const double up = r * (sphere ? std::cos(angle) : std::cosh(angle));
    CHECK(std::isfinite(double(e.x.norm())));
    CHECK(e.x(0, 0) == doctest::Approx(along).epsilon(1e-14).scale(1e-300));
    CHECK(e.x(chart.ambient_dim() - 1, 0) == doctest::Approx(up).epsilon(1e-14));
    CHECK(e.v(0, 0) == doctest::Approx(speed * (sphere ? std::cos(angle) : std::cosh(angle)))
                           .epsilon(1e-14)
                           .scale(1e-300));
  };
  for (double speed : {0.0, 1e-12, 1e-6, 0.3}) {
    check(sesi::Sphere<2, double>(1.5), speed);
    check(sesi::Hyperbolic<2, double>(0.7), speed);
  }
}

TEST_CASE("embedding methods agree with the chart steppers") {
  // Geodesic6 at step h is within its own error of the exact flow, about |geo6(2h) - geo6(h)|
  // / (2^6 - 1); SESI 8 at the same step is far more accurate. So the two agree to much better
  // than |geo6(2h) - geo6(h)| unless they integrate different equations.
  const auto sys = reftest::sphere3_system<double>();
  const auto x0 = reftest::sphere3_initial<double>();
  using C = sesi::Sphere<3, double>;
  const double t_end = 3;
  const long steps = 80;
  const auto chart_run = reftest::run<sesi::KahanLi8<C>>(sys, x0, t_end, steps);
  const auto e_fine = reftest::run<R::Geodesic6<C>>(sys, R::to_embedded(sys, x0), t_end, steps);
  const auto e_coarse =
      reftest::run<R::Geodesic6<C>>(sys, R::to_embedded(sys, x0), t_end, steps / 2);
  const double self = reftest::distance(e_fine, e_coarse);
  const double cross = reftest::distance(e_fine, R::to_embedded(sys, chart_run));
  MESSAGE("geodesic6 vs sesi8-kahan-li: ", cross, "; geodesic6 step halving: ", self);
  CHECK(cross <= self / 8);
}

TEST_CASE("force evaluations per step") {
  const auto sys = paper::make_system<double>();
  const auto e0 = R::to_embedded(sys, paper::initial_state<double>());
  using C = paper::Chart<double>;
  auto count = [&](auto stepper) {
    auto e = e0;
    for (int k = 0; k < 10; ++k) stepper.do_step(sys, e, k * 0.1, 0.1);
    return stepper.evaluations();
  };
  // RATTLE: one per stage, plus the first force (first-same-as-last afterwards).
  CHECK(count(R::Rattle<C>{}) == 10 + 1);
  CHECK(count(Rattle4<C>{}) == 30 + 1);
  // Drift-kick-drift: one kick per stage.
  CHECK(count(R::Geodesic4<C>{}) == 30);
  // Kick-drift-kick: the step's last kick shares its force with the next step's first.
  CHECK(count(Geodesic2Kdk<C>{}) == 10 + 1);
}
