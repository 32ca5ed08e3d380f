#pragma once
/// @file paper_scene.hpp
/// The embedded default scene: the seed paper's three bodies on S^2 (shared/paper-scene.md),
/// built from the library's sesi::scenes::paper, run with SESI 4 at tau = 0.1 to T = 800.

#include <string>

#include "scene.hpp"

namespace sesi::program {

/// The seed's scene, named "paper", with its exact solution attached.
Scene paper_scene();

/// Why scene is not the seed's scene (so that its exact solution does not apply), or "" when it
/// is: the space, masses, potential and initial conditions must match (integrator settings may
/// differ).
std::string paper_scene_mismatch(const Scene& scene);

}  // namespace sesi::program
