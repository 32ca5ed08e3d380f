#pragma once
/// @file run_loop.hpp
/// The step loop: step the integrator to t_end, check the state (finiteness after every step;
/// energy, momentum map, energy guard and close encounters every check_every steps and at every
/// output row), stop at a failed check or a signal, and hand the conserved quantities (at the
/// checks) and snapshots (every output_every steps, and the last state known good) to the
/// recorder.

#include "integrator.hpp"
#include "recorder.hpp"
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
RunOutcome run_loop(const Scene& scene, Integrator& integrator, Recorder& recorder, const RunControl& control,
                    const Checkpoint* from = nullptr);

}  // namespace sesi::program
