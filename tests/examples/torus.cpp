// The user-defined torus chart (examples/torus.hpp): it models the concepts, the generic level
// flow integrates it at the methods' orders, and energy stays bounded.
#include <cmath>
#include <vector>

#include <doctest/doctest.h>
#include <sesi/sesi.hpp>

#include "torus.hpp"

namespace {

static_assert(sesi::HierarchicalChart<Torus>);
static_assert(sesi::EmbeddedChart<Torus>);
static_assert(!sesi::HasLevelFlow<Torus>);  // exercises the generic flow of chart.hpp

using TorusSystem = sesi::System<Torus, Gravity>;

TorusSystem make_system() { return TorusSystem(Torus{}, std::vector<double>{1.0}, Gravity{}); }

sesi::State<Torus> initial() {
  sesi::State<Torus> x(2, 1);
  x.q << 0.3, 0.0;
  x.p << 0.4, 2.0;
  return x;
}

template <class Stepper>
sesi::State<Torus> run(double t_end, int steps) {
  auto sys = make_system();
  auto x = initial();
  Stepper stepper;
  const double dt = t_end / steps;
  for (int k = 0; k < steps; ++k) stepper.do_step(sys, x, k * dt, dt);
  return x;
}

template <class Stepper>
double measured_order(double t_end, int steps) {
  // Differences between runs at steps N, 2N, 4N fall by 2^order.
  const auto a = run<Stepper>(t_end, steps), b = run<Stepper>(t_end, 2 * steps),
             c = run<Stepper>(t_end, 4 * steps);
  const double d1 = (a.q - b.q).norm() + (a.p - b.p).norm();
  const double d2 = (b.q - c.q).norm() + (b.p - c.p).norm();
  return std::log2(d1 / d2);
}

}  // namespace

TEST_CASE("torus: the generic level flow integrates a user chart at the nominal order") {
  CHECK(measured_order<sesi::Strang<Torus>>(2.0, 100) == doctest::Approx(2.0).epsilon(0.15));
  CHECK(measured_order<sesi::Yoshida4<Torus>>(2.0, 50) == doctest::Approx(4.0).epsilon(0.075));
  CHECK(measured_order<sesi::KahanLi6<Torus>>(2.0, 20) == doctest::Approx(6.0).epsilon(0.05));
}

namespace {
struct EnergyHalves {
  double first = 0, second = 0;
};
// Maximum energy error of Strang over the first and second halves of [0, t_end].
EnergyHalves strang_energy_error(double dt, double t_end) {
  auto sys = make_system();
  auto x = initial();
  sesi::Strang<Torus> stepper;
  const double e0 = sys.energy(x);
  const long steps = std::lround(t_end / dt);
  EnergyHalves h;
  for (long k = 0; k < steps; ++k) {
    stepper.do_step(sys, x, k * dt, dt);
    double& slot = k < steps / 2 ? h.first : h.second;
    slot = std::max(slot, std::abs(sys.energy(x) - e0));
  }
  return h;
}
}  // namespace

TEST_CASE("torus: energy error is O(dt^2) and bounded over a long run") {
  const auto coarse = strang_energy_error(0.01, 1000.0);  // 10^5 steps
  const auto fine = strang_energy_error(0.005, 1000.0);
  // Second order: halving dt divides the bounded energy error by 4 (order within 0.3).
  CHECK(std::log2(std::max(coarse.first, coarse.second) / std::max(fine.first, fine.second)) ==
        doctest::Approx(2.0).epsilon(0.15));
  // No drift: the second half's maximum is not above the first half's by more than 1.5x.
  CHECK(coarse.second <= 1.5 * coarse.first);
  CHECK(fine.second <= 1.5 * fine.first);
}

TEST_CASE("torus: the chart passes sesi::check_chart") {
  const std::vector<Torus::Point> samples = {{0.3, 0.0}, {2.0, 1.0}, {-1.2, 4.0}, {3.0, -2.5}};
  const sesi::ChartCheck check = sesi::check_chart(Torus{}, std::span(samples), 0.7);
  INFO(check.report());
  CHECK(static_cast<bool>(check));
}

// Issue #14: a chart with no embedding, a potential on its coordinates (sesi::make_chart_potential)
// and the program's method names. The same gravity written on embedding points and pulled back
// through J^T (Torus + Gravity) is the same force, computed otherwise: the runs agree to
// round-off, a few eps of |z| ~ 2 per stage, grown at most linearly over 1000 steps of a smooth
// orbit (bound 1e-10); any error in the chart-coordinate path (a sign, a missing term) is O(1).
TEST_CASE("torus: a chart without embedding and a potential on its coordinates") {
  static_assert(sesi::HierarchicalChart<BareTorus> && !sesi::EmbeddedChart<BareTorus>);
  const BareTorus bare;
  sesi::System chart_sys(bare, std::vector<double>{1.0}, chart_gravity(bare));
  static_assert(decltype(chart_sys)::has_chart_terms && !decltype(chart_sys)::has_embedded_terms);
  sesi::State<BareTorus> y(2, 1);
  y.q = initial().q;
  y.p = initial().p;
  auto sys = make_system();
  auto x = initial();
  CHECK(chart_sys.energy(y) == doctest::Approx(sys.energy(x)).epsilon(1e-15));

  sesi::Sesi4<BareTorus> bare_stepper;
  sesi::Sesi4<Torus> stepper;
  const double dt = 0.01, e0 = chart_sys.energy(y);
  double max_error = 0;
  for (int k = 0; k < 1000; ++k) {
    bare_stepper.do_step(chart_sys, y, k * dt, dt);
    stepper.do_step(sys, x, k * dt, dt);
    max_error = std::max(max_error, std::abs(chart_sys.energy(y) - e0));
  }
  CHECK((y.q - x.q).cwiseAbs().maxCoeff() < 1e-10);
  CHECK((y.p - x.p).cwiseAbs().maxCoeff() < 1e-10);
  CHECK(max_error < 1e-6);  // SESI 4 at dt = 0.01: dt^4 = 1e-8 times the orbit's scale
}
