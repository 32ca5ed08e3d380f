// A user chart through the installed package (issue #14): the torus with no embedding
// (examples/torus.hpp's BareTorus), gravity on its coordinates (sesi::make_chart_potential) and
// sesi::Sesi4. It must pass sesi::check_chart, keep its energy to SESI 4's dt^4, and converge at
// order 4 (measured within 0.3). Exits non-zero otherwise.
#include <cmath>
#include <cstdio>
#include <span>
#include <vector>

#include <sesi/sesi.hpp>

#include "torus.hpp"

namespace {
struct Run {
  BareTorus::Point q, p;
  double max_energy_error;
};

Run run(double dt, double t_end) {
  const BareTorus torus;
  sesi::System sys(torus, std::vector<double>{1.0}, chart_gravity(torus));
  sesi::State<BareTorus> x(2, 1);
  x.q << 0.3, 0.0;
  x.p << 0.4, 2.0;
  sesi::Sesi4<BareTorus> stepper;
  const double e0 = sys.energy(x);
  double worst = 0;
  const long steps = std::lround(t_end / dt);
  for (long k = 0; k < steps; ++k) {
    stepper.do_step(sys, x, k * dt, dt);
    worst = std::max(worst, std::abs(sys.energy(x) - e0));
  }
  return {x.q.col(0), x.p.col(0), worst};
}
}  // namespace

int main() {
  const std::vector<BareTorus::Point> samples = {{0.3, 0.0}, {2.0, 1.0}, {-1.2, 4.0}};
  const sesi::ChartCheck check = sesi::check_chart(BareTorus{}, std::span(samples));
  if (!check) {
    std::fprintf(stderr, "%s", check.report().c_str());
    return 1;
  }
  const Run a = run(0.04, 4.0), b = run(0.02, 4.0), c = run(0.01, 4.0);
  const double order = std::log2(((a.q - b.q).norm() + (a.p - b.p).norm()) / ((b.q - c.q).norm() + (b.p - c.p).norm()));
  std::printf("consumer_torus: SESI 4 on a chart without embedding: measured order %.2f, energy error %.3g\n", order,
              c.max_energy_error);
  return std::abs(order - 4.0) <= 0.3 && c.max_energy_error < 1e-6 ? 0 : 1;
}
