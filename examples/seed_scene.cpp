// The seed paper's benchmark (shared/paper-scene.md): three bodies on S^2, SESI 2 and SESI 4
// with tau = 0.1 to T = 800. Prints the maximum energy error and the final position error of
// body 1 against the exact solution.
#include <algorithm>
#include <cmath>
#include <cstdio>

#include <sesi/scenes/paper.hpp>
#include <sesi/sesi.hpp>

namespace paper = sesi::scenes::paper;

template <class Stepper>
void run(const char* name, double tau, double t_end) {
  auto sys = paper::make_system();
  auto x = paper::initial_state();
  const paper::Exact exact;
  const double e0 = sys.energy(x);
  const auto steps = static_cast<long>(std::lround(t_end / tau));
  Stepper stepper;
  double max_energy_error = 0.0;
  for (long k = 0; k < steps; ++k) {
    stepper.do_step(sys, x, k * tau, tau);
    max_energy_error = std::max(max_energy_error, std::abs(sys.energy(x) - e0));
  }
  const auto X = sesi::embedding_points(sys, x);
  const double position_error = (X.col(0) - exact.position(0, t_end).cast<double>()).norm();
  std::printf("%-6s tau = %-5g T = %g: max |energy error| = %.3e, body-1 position error = %.3e\n",
              name, tau, t_end, max_energy_error, position_error);
}

int main() {
  const paper::Exact exact;
  std::printf("seed scene: E = %.15f, radial period = %.10f\n", static_cast<double>(exact.energy()),
              static_cast<double>(2 * std::numbers::pi_v<long double> / exact.frequency()));
  run<sesi::Sesi2<paper::Chart<>>>("SESI 2", 0.1, 800.0);
  run<sesi::Sesi4<paper::Chart<>>>("SESI 4", 0.1, 800.0);
  run<sesi::Sesi4<paper::Chart<>>>("SESI 4", 0.01, 800.0);
}
