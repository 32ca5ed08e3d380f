// Integrates free motion on S^2 with SESI 4 through the installed package and checks that the
// body stays on its great circle: exits non-zero on failure.
#include <cmath>
#include <cstdio>
#include <vector>

#include <sesi/sesi.hpp>

int main() {
  using Chart = sesi::Sphere2d;
  sesi::System sys(Chart(1.0), std::vector<double>{1.0});
  sesi::State<Chart> x(2, 1);
  x.q << 1.0, 0.5;
  x.p << 0.3, 0.2;
  const double e0 = sys.energy(x);
  sesi::Yoshida4<Chart> stepper;
  for (int k = 0; k < 1000; ++k) stepper.do_step(sys, x, 0.01 * k, 0.01);
  const double drift = std::abs(sys.energy(x) - e0);
  std::printf("consumer: energy error %.3g after 1000 steps\n", drift);
  return drift < 1e-9 ? 0 : 1;
}
