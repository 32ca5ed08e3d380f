// Sphere charts of dimensions 1 to 4 (dispatch.hpp).
#include "chart_integrator.hpp"
#include "dispatch.hpp"

namespace sesi::program {

std::unique_ptr<Integrator> sphere_integrator_1_4(const Scene& scene) {
  return integrator_for<sesi::Sphere, 1, 2, 3, 4>(scene);
}

}  // namespace sesi::program
