// Euclidean charts of the fixed-size dimensions (dispatch.hpp).
#include "chart_integrator.hpp"
#include "dispatch.hpp"

namespace sesi::program {

std::unique_ptr<Integrator> euclidean_integrator_fixed(const Scene& scene) {
  return integrator_for<sesi::Euclidean>(scene, FixedDims{});
}

}  // namespace sesi::program
