// Two bodies attracting each other on the unit sphere S^2 (the curved Kepler/N-body problem),
// integrated with SESI 4, the seed paper's fourth-order scheme.
#include <cstdio>
#include <vector>

#include <sesi/sesi.hpp>

int main() {
  using Chart = sesi::Sphere<2>;  // hyperspherical angles (theta, phi), radius 1
  sesi::System sys(Chart(1.0), std::vector<double>{1.0, 1.0}, sesi::CotangentGravity<double>{1.0});

  sesi::State<Chart> x(2, 2);              // dimension 2, two bodies; column b is body b
  x.set_body(0, {1.2, 0.0}, {0.0, 0.4});   // (theta, phi), (p_theta, p_phi)
  x.set_body(1, {1.9, 0.0}, {0.0, -0.4});

  sesi::Sesi4<Chart> stepper;  // the seed's SESI 4 (Yoshida's triple jump)
  const double dt = 1e-3, e0 = sys.energy(x);
  for (int k = 0; k < 10000; ++k) stepper.do_step(sys, x, k * dt, dt);

  std::printf("energy error after 10000 steps: %.3g\n", sys.energy(x) - e0);
  std::printf("momentum map (L_z, -L_y, L_x): %s\n", "see sesi::momentum_map");
  const auto m = sesi::momentum_map(sys, x);
  std::printf("  %.12f %.12f %.12f\n", m[0], m[1], m[2]);

  // The method chosen at run time: one engine, the table's weights as data (docs/scheme.md).
  {
    auto stepper = sesi::Composition<sesi::coefficients::Runtime, sesi::Sphere<2>>::of<
        sesi::coefficients::KahanLi6>();  // or (weights, order) from anywhere
    for (int k = 0; k < 100; ++k) stepper.do_step(sys, x, k * 0.01, 0.01);
    std::printf("order %d, %zu stages; energy error %.3g\n", stepper.order(), stepper.stages(),
                sys.energy(x) - e0);
  }
}
