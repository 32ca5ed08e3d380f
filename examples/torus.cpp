// A body sliding on a torus of revolution under gravity, integrated with the sixth-order
// Kahan-Li composition of the hierarchical Strang step. The chart is user-defined (torus.hpp).
#include <cmath>
#include <cstdio>
#include <span>
#include <vector>

#include <sesi/sesi.hpp>

#include "torus.hpp"

static_assert(sesi::EmbeddedChart<Torus>);

int main() {
  // First, check the chart numerically: the hierarchy and the derivatives (docs/concepts.md).
  const std::vector<Torus::Point> samples = {{0.3, 0.0}, {2.0, 1.0}, {-1.2, 4.0}};
  if (const sesi::ChartCheck check = sesi::check_chart(Torus{}, std::span(samples)); !check) {
    std::fprintf(stderr, "%s", check.report().c_str());
    return 1;
  }

  sesi::System sys(Torus{}, std::vector<double>{1.0}, Gravity{});
  sesi::State<Torus> x(2, 1);
  x.q << 0.3, 0.0;  // a little above the outer equator
  x.p << 0.0, 2.0;  // moving around the axis

  sesi::Sesi6KahanLi<Torus> stepper;
  const double dt = 0.01, e0 = sys.energy(x);
  double max_error = 0.0;
  for (int k = 0; k < 10000; ++k) {
    stepper.do_step(sys, x, k * dt, dt);
    max_error = std::max(max_error, std::abs(sys.energy(x) - e0));
  }
  std::printf("torus: t = %g, q = (%.6f, %.6f), max |energy error| = %.3g\n", 10000 * dt,
              x.q(0, 0), x.q(1, 0), max_error);
}
