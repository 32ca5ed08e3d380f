#pragma once
/// @file dispatch.hpp
/// From the scene's runtime space and dimension to a compile-time chart, once per run:
/// S^n, H^n and E^n with fixed-size Eigen types for n = 1..8 (max_fixed_dim), Eigen::Dynamic
/// above. Each (space, dimension) instantiates one ChartIntegrator: one System type (terms.hpp),
/// one composition engine serving every method (methods.hpp) and one thermostatted engine serving
/// every thermostat kind (thermostat_stepper.hpp); on S^n and H^n also one
/// EmbeddedIntegrator serving every geodesic method. The instantiations are spread over the
/// dispatch_*.cpp files so that they compile in parallel.

#include <memory>

#include "integrator.hpp"

namespace sesi::program {

/// The largest dimension with a fixed-size instantiation.
inline constexpr int max_fixed_dim = 8;

// One per file (dispatch_<space>_<dimensions>.cpp).
std::unique_ptr<Integrator> sphere_integrator_1_4(const Scene&);
std::unique_ptr<Integrator> sphere_integrator_5_up(const Scene&);
std::unique_ptr<Integrator> hyperbolic_integrator_1_4(const Scene&);
std::unique_ptr<Integrator> hyperbolic_integrator_5_up(const Scene&);
std::unique_ptr<Integrator> euclidean_integrator_1_4(const Scene&);
std::unique_ptr<Integrator> euclidean_integrator_5_up(const Scene&);
// A space with a topology (SpaceSpec::has_topology): a periodic box on E^n (n = 1..3 fixed size,
// Eigen::Dynamic above) or a compact surface H^2/Gamma, chart methods only (dispatch_topology.cpp).
std::unique_ptr<Integrator> topology_integrator(const Scene&);
// The geodesic methods (EmbeddedIntegrator), every dimension (dispatch_geodesic_<space>.cpp).
std::unique_ptr<Integrator> sphere_geodesic_integrator(const Scene&);
std::unique_ptr<Integrator> hyperbolic_geodesic_integrator(const Scene&);

}  // namespace sesi::program
