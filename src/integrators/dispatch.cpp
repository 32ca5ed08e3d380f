#include "dispatch.hpp"

namespace sesi::program {

std::unique_ptr<Integrator> make_integrator(const Scene& scene) {
  const bool low = scene.dim() <= 4;
  switch (scene.space.kind) {
    case SpaceKind::sphere:
      return low ? sphere_integrator_1_4(scene) : sphere_integrator_5_up(scene);
    case SpaceKind::hyperbolic:
      return low ? hyperbolic_integrator_1_4(scene) : hyperbolic_integrator_5_up(scene);
    case SpaceKind::euclidean:
      break;
  }
  return low ? euclidean_integrator_1_4(scene) : euclidean_integrator_5_up(scene);
}

}  // namespace sesi::program
