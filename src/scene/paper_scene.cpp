#include "paper_scene.hpp"

#include <cmath>

#include <sesi/scenes/paper.hpp>

namespace sesi::program {

namespace paper = sesi::scenes::paper;

Scene paper_scene() {
  Scene scene;
  scene.name = "paper";
  scene.source = "<default scene>";
  scene.space = {SpaceKind::sphere, 2, 1.0};
  const auto x = paper::initial_state<double>();
  for (int b = 0; b < x.bodies(); ++b) scene.bodies.push_back({1.0, x.q.col(b), x.p.col(b)});
  scene.potentials.emplace_back(ChordWellSpec{paper::Constants<double>::theta0(), 2.0});
  scene.integrator.method = "sesi4";
  scene.integrator.dt = paper::Constants<double>::tau;
  scene.integrator.t_end = paper::Constants<double>::t_end;
  scene.integrator.output_every = 1;
  scene.exact = ExactSolution::paper;
  return scene;
}

std::string paper_scene_mismatch(const Scene& scene) {
  const Scene seed = paper_scene();
  // Initial conditions agree to this (absolute) tolerance; files carry 16-17 digits.
  constexpr double tolerance = 1e-12;
  if (scene.space.kind != SpaceKind::sphere || scene.space.dim != 2 || scene.space.radius != 1.0) {
    return "the space is not the unit sphere S^2";
  }
  if (scene.body_count() != seed.body_count()) return "it does not have 3 bodies";
  for (int b = 0; b < seed.body_count(); ++b) {
    const Body& mine = scene.bodies[static_cast<std::size_t>(b)];
    const Body& theirs = seed.bodies[static_cast<std::size_t>(b)];
    if (mine.mass != 1.0) return "the masses are not 1";
    if ((mine.q - theirs.q).cwiseAbs().maxCoeff() > tolerance ||
        (mine.p - theirs.p).cwiseAbs().maxCoeff() > tolerance) {
      return "the initial conditions of bodies[" + std::to_string(b + 1) + "] differ";
    }
  }
  const auto* well = scene.potentials.size() == 1 ? std::get_if<ChordWellSpec>(&scene.potentials[0]) : nullptr;
  const auto& seed_well = std::get<ChordWellSpec>(seed.potentials[0]);
  if (!well || std::abs(well->theta0 - seed_well.theta0) > tolerance || well->strength != seed_well.strength) {
    return "the potential is not one chord-well with theta0 = pi/4 and strength 2";
  }
  return "";
}

}  // namespace sesi::program
