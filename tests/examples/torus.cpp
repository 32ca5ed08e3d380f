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
