// Spaces with a topology (dispatch.hpp; issue #26): E^n in a periodic box for n = 1..3 (fixed
// size) and above (Eigen::Dynamic), and the compact hyperbolic surfaces H^2/Gamma of every genus
// (one type: the genus is a run-time parameter of sesi::HyperbolicSurface).
#include <sesi/topologies/hyperbolic_surface.hpp>
#include <sesi/topologies/periodic_box.hpp>

#include "chart_integrator.hpp"
#include "dispatch.hpp"

namespace sesi::program {

namespace {
template <int N>
using BoxChart = sesi::Quotient<sesi::Euclidean<N, double>, sesi::PeriodicBox<double, N>>;
using SurfaceChart = sesi::Quotient<sesi::Hyperbolic<2, double>, sesi::HyperbolicSurface<double>>;
}  // namespace

std::unique_ptr<Integrator> topology_integrator(const Scene& scene) {
  if (scene.space.genus != 0) return std::make_unique<ChartIntegrator<SurfaceChart>>(scene);
  switch (scene.dim()) {
#ifndef SESI_FEW_FIXED_DIMS  // dispatch.hpp
    case 1: return std::make_unique<ChartIntegrator<BoxChart<1>>>(scene);
#endif
    case 2: return std::make_unique<ChartIntegrator<BoxChart<2>>>(scene);
    case 3: return std::make_unique<ChartIntegrator<BoxChart<3>>>(scene);
    default: break;
  }
  return std::make_unique<ChartIntegrator<BoxChart<Eigen::Dynamic>>>(scene);
}

}  // namespace sesi::program
