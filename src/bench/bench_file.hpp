#pragma once
/// @file bench_file.hpp
/// `sesi bench --scene FILE`: any scene file of the program, on the program's own system type
/// (terms.hpp) and initial state, with re-charting compositions (as `sesi run`).

#include <cstdio>
#include <string>
#include <variant>

#include <sesi/scenes/paper.hpp>

#include "bench_harness.hpp"
#include "chart_integrator.hpp"
#include "terms.hpp"

namespace sesi::program::bench {

template <class Chart>
Result bench_scene_file(const Scene& scene, const Settings& settings) {
  const auto sys = make_system(scene, make_chart<Chart>(scene.space));
  bool external = false;
  for (const PotentialSpec& p : scene.potentials)
    external = external || std::holds_alternative<CentralCotangentSpec>(p);
  // As `sesi run` steps (with re-charting), unless --form seed asks for the library's default.
  const SesiForm form = settings.form == SesiForm::seed ? SesiForm::seed : SesiForm::program_recharting;
  Harness<std::remove_const_t<decltype(sys)>> h(sys, initial_state<Chart>(scene), settings,
                                                Eigen::MatrixXd(), form);
  Result r;
  r.notes.push_back("scene: " + scene.name + " (" + scene.source + ")");
  r.notes.push_back(describe(form));
  if (!settings.horizons.empty()) {  // energy errors only: no reference needed
    r.notes.push_back(external ? "momentum: all components (NOT conserved: the scene has an external potential)"
                               : "momentum: all components of the momentum map");
    r.rows = horizon_sweep(sys, initial_state<Chart>(scene), settings, Eigen::MatrixXd(), form);
    return r;
  }
  Eigen::MatrixXd reference;
  if (scene.exact == ExactSolution::paper) {
    const sesi::scenes::paper::Exact exact;
    reference.resize(3, 3);
    for (int b = 0; b < 3; ++b) reference.col(b) = exact.position(b, settings.t_end).cast<double>();
    r.notes.push_back("reference: exact solution (sesi/scenes/paper.hpp, long double)");
  } else {
    const long n = long(settings.samples) * 64;
    double estimate = 0;
    reference = h.reference_run(n, &estimate);
    char line[200];
    std::snprintf(line, sizeof line,
                  "reference: sesi8-kahan-li with dt = %.6g (%ld steps); distance from the run at "
                  "2 dt: %.2e",
                  settings.t_end / double(n), n, estimate);
    r.notes.push_back(line);
  }
  r.notes.push_back(external ? "momentum: all components (NOT conserved: the scene has an external potential)"
                             : "momentum: all components of the momentum map");
  r.rows = h.sweep_all(reference);
  return r;
}

}  // namespace sesi::program::bench
