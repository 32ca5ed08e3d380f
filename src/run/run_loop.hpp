#pragma once
/// @file run_loop.hpp
/// The step loop: step the integrator to t_end, check the state (finiteness after every step;
/// energy, momentum map, energy guard and close encounters every check_every steps and at every
/// output row), stop at a failed check or a signal, and hand the conserved quantities (at the
/// checks) and snapshots (every output_every steps, and the last state known good) to the
/// recorder. With a thermostat (Scene::thermostat) it sets each step's temperature from the
/// schedule and the noise's step key, hands the thermostat's observables on with every snapshot,
/// and the energy guard judges the conserved quantity E + conserved_offset() (off for brownian).

#include "integrator.hpp"
#include "run_sink.hpp"
#include "run_types.hpp"
#include "scene.hpp"

namespace sesi::program {

/// Scenes from this many bodies on check every 20 steps by default (default_check_every).
inline constexpr int many_bodies = 1000;

/// Steps between the run's checks when the scene does not say: 1 below many_bodies bodies, where
/// the checks cost little; 20 from there on, which keeps them below 10 % of stepping at 10^4
/// bodies (docs/benchmarks.md, "Checks").
long default_check_every(int bodies);

/// Run scene, from its initial state or, with `from`, from a checkpoint (whose state the
/// integrator already holds and whose outputs the recorder goes on with): the run then goes on
/// exactly as if it had not stopped. Throws InputError (before any step) when the initial
/// energy is not finite.
RunOutcome run_loop(const Scene& scene, Integrator& integrator, RunSink& recorder, const RunControl& control,
                    const Checkpoint* from = nullptr);

/// A run that goes on from any state the integrator holds (the Python package's
/// Simulation.integrate): after `step` steps at time t, with the energy guard's reference. The
/// steps go on from there on the grid t + k dt (k dt when t is step dt, so that a run cut into
/// pieces on the grid takes the steps of one run) up to the scene's t_end (whose sign is dt's),
/// the last shortened to end there. Its first state is neither tracked nor written: the sink
/// has it from the run before.
struct RunStart {
  long step = 0;
  double t = 0.0;
  double guard_energy = 0.0, guard_scale = 0.0;
};
RunOutcome run_loop(const Scene& scene, Integrator& integrator, RunSink& sink, const RunControl& control,
                    const RunStart& start);

/// The energy guard's reference (E0 and K0 + |V0|, sesi::EnergyGuard) at the integrator's
/// state, as run_loop takes it at the start of a run. Throws InputError when E0 is not finite.
RunStart guard_reference(const Scene& scene, Integrator& integrator);

}  // namespace sesi::program
