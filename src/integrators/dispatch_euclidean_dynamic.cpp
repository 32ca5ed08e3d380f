// Euclidean charts of every other dimension, with Eigen::Dynamic types (dispatch.hpp).
#include "chart_integrator.hpp"
#include "dispatch.hpp"

namespace sesi::program {

std::unique_ptr<Integrator> euclidean_integrator_dynamic(const Scene& scene) {
  return std::make_unique<ChartIntegrator<sesi::Euclidean<Eigen::Dynamic, double>>>(scene);
}

}  // namespace sesi::program
