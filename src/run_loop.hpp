#pragma once
/// @file run_loop.hpp
/// The step loop: step the integrator to t_end, stop at once when the state (or its energy)
/// becomes non-finite or a signal arrives, and hand the conserved quantities (every step) and
/// snapshots (every output_every steps, and the last finite state) to the recorder.

#include "integrator.hpp"
#include "observables.hpp"
#include "recorder.hpp"
#include "run_types.hpp"
#include "scene.hpp"

namespace sesi::program {

/// Run scene. Throws InputError (before any step) when the initial energy is not finite.
RunOutcome run_loop(const Scene& scene, Integrator& integrator, Observables& observe, Recorder& recorder,
                    const RunControl& control);

}  // namespace sesi::program
