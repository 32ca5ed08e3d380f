// The geodesic methods' integrators on Hyperbolic charts: dimensions 1 to 4 with fixed-size types,
// above with Eigen::Dynamic (dispatch.hpp, embedded_integrator.hpp). Fixed sizes stop at 4 here,
// not at max_fixed_dim as for the chart methods: the geodesic steps are plain vector operations
// on the ambient points, and each fixed dimension costs compile time.
#include "dispatch.hpp"
#include "embedded_integrator.hpp"

namespace sesi::program {

std::unique_ptr<Integrator> hyperbolic_geodesic_integrator(const Scene& scene) {
  check_geodesic_reach(scene);
  if (auto fixed = embedded_integrator_for<sesi::Hyperbolic, 1, 2, 3, 4>(scene)) return fixed;
  return std::make_unique<EmbeddedIntegrator<sesi::Hyperbolic<Eigen::Dynamic, double>>>(scene);
}

}  // namespace sesi::program
