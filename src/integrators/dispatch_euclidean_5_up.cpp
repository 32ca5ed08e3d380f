// Euclidean charts of dimensions 5 to 8 (fixed size) and above (Eigen::Dynamic) (dispatch.hpp).
#include "chart_integrator.hpp"
#include "dispatch.hpp"

namespace sesi::program {

std::unique_ptr<Integrator> euclidean_integrator_5_up(const Scene& scene) {
  static_assert(max_fixed_dim == 8, "the fixed dimensions here are 5..8");
  if (auto fixed = integrator_for<sesi::Euclidean, 5, 6, 7, 8>(scene)) return fixed;
  return std::make_unique<ChartIntegrator<sesi::Euclidean<Eigen::Dynamic, double>>>(scene);
}

}  // namespace sesi::program
