#pragma once
/// @file auto_method.hpp
/// `method = "auto"` (issue #15): the method and step of a run chosen for a target max relative
/// energy error (`tolerance`), from short pilot runs of the scene and the bench's cost model.
/// docs/scheme.md ("Choosing a method: auto") says how; docs/benchmarks.md has the data.

#include "scene.hpp"

namespace sesi::program {

/// Relative cost of one force evaluation (stage) of a geodesic method against a chart
/// method's (= 1; the processed kernels are chart compositions): the middle of 0.61-0.85 measured
/// on the bench's scenes (docs/benchmarks.md, "The cost model of method = auto").
inline constexpr double geodesic_stage_cost = 0.7;

/// With scene.integrator.method == "auto": picks the method and step, sets them (and
/// output_every: the given output interval is kept when the step divides it) and records the
/// choice in scene.integrator.auto_choice. Deterministic: the pilot runs are runs of the scene,
/// so the same scene gets the same choice on any machine and any thread count. Throws InputError
/// when no candidate meets the tolerance or the scene's energy is 0 (a relative error is then
/// undefined). Any other method: nothing.
void resolve_auto(Scene& scene);

}  // namespace sesi::program
