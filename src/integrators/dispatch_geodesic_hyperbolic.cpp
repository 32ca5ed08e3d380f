// The geodesic methods' integrators on Hyperbolic charts: the fixed-size dimensions (dispatch.hpp),
// the others with Eigen::Dynamic (embedded_integrator.hpp).
#include "dispatch.hpp"
#include "embedded_integrator.hpp"

namespace sesi::program {

std::unique_ptr<Integrator> hyperbolic_geodesic_integrator(const Scene& scene) {
  check_geodesic_reach(scene);
  if (auto fixed = embedded_integrator_for<sesi::Hyperbolic>(scene, FixedDims{})) return fixed;
  return std::make_unique<EmbeddedIntegrator<sesi::Hyperbolic<Eigen::Dynamic, double>>>(scene);
}

}  // namespace sesi::program
