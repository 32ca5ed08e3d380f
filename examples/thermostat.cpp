// A thermostat as a stage of the composition engine (docs/thermostats.md): 200 Lennard-Jones bodies
// on the sphere S^2 of radius 8, Langevin dynamics at kT = 1, then a quench to kT = 0.2.
// Needs Random123's headers (Debian: librandom123-dev); sesi/sesi.hpp leaves the thermostats out.
#include <cmath>
#include <cstdio>
#include <vector>

#include <sesi/sesi.hpp>
#include <sesi/thermostat.hpp>

int main() {
  using Chart = sesi::Sphere<2>;
  const int n = 200;
  sesi::System sys(Chart(8.0), std::vector<double>(n, 1.0), sesi::LennardJones<double>{1.0, 1.0, 2.5});
  sesi::State<Chart> x(2, n);  // a Fibonacci lattice (spacing about 2 sigma), at rest
  for (int b = 0; b < n; ++b) {
    x.set_body(b, {std::acos(1.0 - 2.0 * (b + 0.5) / n), std::fmod(M_PI * (1.0 + std::sqrt(5.0)) * (b + 0.5), 2.0 * M_PI)},
               {0.0, 0.0});
  }
  double t = 0.0, kT = 1.0;
  const double dt = 0.005;

  sesi::ThermostatParams<double> p;
  p.kind = sesi::ThermostatKind::langevin;   // langevin | nose_hoover | csvr | brownian
  p.kT = 1.0;      // k_B T in energy units
  p.gamma = 1.0;   // langevin, brownian: friction (1/time)
  p.tau = 0.5;     // nose_hoover, csvr: relaxation time
  p.chain = 3;     // nose_hoover: chain length
  p.seed = 7;      // the noise's key
  // Re-charted after each step (docs/charts.md), as the program runs it on S^n and H^n.
  sesi::Recharting<sesi::Thermostatted<Chart>> stepper{sesi::RechartPolicy<double>{}, sesi::Thermostat<Chart>(p)};
  stepper.do_step(sys, x, t, dt);
  stepper.stage().heat();              // energy the thermostat put in so far
  stepper.stage().conserved_offset();  // H + this is conserved up to the step's error
  stepper.stage().set_temperature(kT); // from the next step on (a schedule)
  std::vector<double> saved = stepper.stage().save();  // for a checkpoint; load(saved) resumes bit for bit

  const double e0 = sys.energy(x) + stepper.stage().conserved_offset();
  for (int k = 1; k < 8000; ++k) {
    t = k * dt;
    if (k == 4000) stepper.stage().set_temperature(0.2);  // the quench
    stepper.do_step(sys, x, t, dt);
  }
  // 2K / N_f with N_f = 2 per body: near 0.2 after the quench (relative spread sqrt(2 / 400) = 7 %).
  std::printf("kinetic temperature %.3f, configurational %.3f\n", 2.0 * sys.kinetic_energy(x) / (2.0 * n),
              sesi::configurational_temperature(sys, x));
  std::printf("heat %.4g; H - heat moved by %.3g\n", stepper.stage().heat(),
              sys.energy(x) + stepper.stage().conserved_offset() - e0);
  static_cast<void>(saved);
}
