// The geodesic methods' integrators on Sphere charts: the fixed-size dimensions (dispatch.hpp),
// the others with Eigen::Dynamic (embedded_integrator.hpp).
#include "dispatch.hpp"
#include "embedded_integrator.hpp"

namespace sesi::program {

std::unique_ptr<Integrator> sphere_geodesic_integrator(const Scene& scene) {
  if (auto fixed = embedded_integrator_for<sesi::Sphere>(scene, FixedDims{})) return fixed;
  return std::make_unique<EmbeddedIntegrator<sesi::Sphere<Eigen::Dynamic, double>>>(scene);
}

}  // namespace sesi::program
