#pragma once
/// @file bench_kepler.hpp
/// The curved Kepler problem of `sesi bench` (issue #4): one unit mass about a fixed centre,
/// V = -k m ctn(d) (potentials.hpp, CentralCotangent; Kozlov & Harin, Celest. Mech. 54 (1992)
/// 393), whose bounded orbits close (Bertrand's theorem on S^2 and H^2). The centre is the
/// chart's pole (the chart a user picks for a central problem); the body starts at polar
/// radius 0.8 with angular momentum 0.7 (S^2; circular orbit: 1.015) or 0.6 (H^2; circular:
/// 0.815), so the orbits are eccentric and bounded away from the pole and its antipode.
/// No exact solution is coded: the reference is a run of sesi8-kahan-li at a small step.

#include <cstdio>
#include <string>

#include <sesi/potentials.hpp>
#include <sesi/system.hpp>

#include "bench_harness.hpp"

namespace sesi::program::bench {

template <class Chart>
Result bench_kepler(const Settings& settings, const char* scene_name, double angular_momentum) {
  sesi::CentralCotangent<Chart> term;
  term.k = 1.0;
  term.center = Chart::Ambient::Zero(3);
  term.center[2] = 1.0;  // the chart's pole: (0, 0, 1) on S^2 and on the hyperboloid
  const auto sys = sesi::System(Chart(1.0), std::vector<double>{1.0}, term);
  sesi::State<Chart> x0(2, 1);
  x0.q(0, 0) = 0.8;
  x0.q(1, 0) = 0.0;
  x0.p(0, 0) = 0.0;
  x0.p(1, 0) = angular_momentum;
  // Rotations about the centre's axis conserve M12 = L_z (the first momentum-map component).
  Eigen::MatrixXd conserved = Eigen::MatrixXd::Zero(1, 3);
  conserved(0, 0) = 1.0;
  // By default the seed's drift-kick-drift form: with the centre at the chart's origin it is much
  // the better form here (docs/scheme.md); these scenes never come near a chart singularity.
  const SesiForm form = settings.form.value_or(SesiForm::seed);
  Result r;
  r.notes.push_back(std::string("scene: ") + scene_name +
                    " (curved Kepler problem, V = -ctn(d), centre at the chart pole, q0 = (0.8, 0),"
                    " p0 = (0, " + std::to_string(angular_momentum) + "))");
  if (!settings.horizons.empty()) {  // energy errors only: no reference run needed
    r.notes.push_back(describe(form));
    r.notes.push_back("momentum: M12 = L_z, the component conserved by rotations about the centre");
    r.rows = horizon_sweep(sys, x0, settings, conserved, form);
    return r;
  }
  Harness<std::remove_const_t<decltype(sys)>> h(sys, x0, settings, conserved, form);
  const long n = long(settings.samples) * 64;
  double estimate = 0;
  const Eigen::MatrixXd reference = h.reference_run(n, &estimate);
  char line[256];
  std::snprintf(line, sizeof line,
                "reference: sesi8-kahan-li with dt = %.6g (%ld steps); distance from the run at "
                "2 dt: %.2e",
                settings.t_end / double(n), n, estimate);
  r.notes.push_back(line);
  r.notes.push_back(describe(form));
  r.notes.push_back("momentum: M12 = L_z, the component conserved by rotations about the centre");
  r.rows = h.sweep_all(reference);
  return r;
}

}  // namespace sesi::program::bench
