#pragma once
/// @file dispatch.hpp
/// From the scene's runtime space and dimension to a compile-time chart, once per run:
/// S^n, H^n and E^n with fixed-size Eigen types for n = 1..4 (FixedDims), Eigen::Dynamic
/// above. Each (space, dimension) instantiates one ChartIntegrator: one System type (terms.hpp),
/// one composition engine serving every method (methods.hpp) and one thermostatted engine serving
/// every thermostat kind (thermostat_stepper.hpp); on S^n and H^n also one
/// EmbeddedIntegrator serving every geodesic method. The instantiations are spread over the
/// dispatch_*.cpp files so that they compile in parallel.
///
/// Fixed sizes stop at 4: each costs 20-60 s of compile time per space (in every build, in CI's
/// `make test` twice), and the many-body users' spaces are S^2, S^3, H^2, H^3 and E^2, E^3. Above,
/// a step costs more: Eigen's loops over a run-time size are not unrolled and inlined as over a
/// fixed one.

#include <memory>
#include <utility>

#include "integrator.hpp"

namespace sesi::program {

#ifdef SESI_FEW_FIXED_DIMS
// The sanitizer job's build (SESI_SANITIZER_BUILD, src/CMakeLists.txt): fixed sizes for n = 2 and 3
// only, Eigen::Dynamic for every other n. ASan and UBSan then check each template once at a fixed
// and once at the dynamic size, which is what they can tell apart (the same code at another N
// holds memory alike); the main build's tests run every fixed size. 400 s less of clang's CPU.
using FixedDims = std::integer_sequence<int, 2, 3>;
#else
/// The dimensions with fixed-size instantiations (of the chart and of the geodesic methods).
using FixedDims = std::integer_sequence<int, 1, 2, 3, 4>;
#endif
/// Is n one of FixedDims?
constexpr bool fixed_size_dim(int n) {
  const auto among = []<int... Dims>(int m, std::integer_sequence<int, Dims...>) { return ((m == Dims) || ...); };
  return among(n, FixedDims{});
}

// One per file (dispatch_<space>_fixed.cpp: the fixed-size dimensions; _dynamic.cpp: the others).
std::unique_ptr<Integrator> sphere_integrator_fixed(const Scene&);
std::unique_ptr<Integrator> sphere_integrator_dynamic(const Scene&);
std::unique_ptr<Integrator> hyperbolic_integrator_fixed(const Scene&);
std::unique_ptr<Integrator> hyperbolic_integrator_dynamic(const Scene&);
std::unique_ptr<Integrator> euclidean_integrator_fixed(const Scene&);
std::unique_ptr<Integrator> euclidean_integrator_dynamic(const Scene&);
// A space with a topology (SpaceSpec::has_topology): a periodic box on E^n (n = 1..3 fixed size,
// Eigen::Dynamic above) or a compact surface H^2/Gamma, chart methods only (dispatch_topology.cpp).
std::unique_ptr<Integrator> topology_integrator(const Scene&);
// The geodesic methods (EmbeddedIntegrator), every dimension (dispatch_geodesic_<space>.cpp).
std::unique_ptr<Integrator> sphere_geodesic_integrator(const Scene&);
std::unique_ptr<Integrator> hyperbolic_geodesic_integrator(const Scene&);

}  // namespace sesi::program
