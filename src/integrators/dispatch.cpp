#include "dispatch.hpp"

#include <algorithm>
#include <string>
#include <variant>

#include "errors.hpp"
#include "methods.hpp"
#include "validate.hpp"

namespace sesi::program {

double short_range_cutoff(const Scene& scene) {
  double range = 0.0;
  for (const PotentialSpec& spec : scene.potentials) {
    if (const auto* lj = std::get_if<LennardJonesSpec>(&spec)) range = std::max(range, lj->cutoff);
  }
  return range;
}

double wrap_margin(const Scene& scene, double max_cutoff) {
  const double range = short_range_cutoff(scene);
  return 0.25 * (range > 0.0 ? range : max_cutoff);
}

std::unique_ptr<Integrator> make_integrator(const Scene& scene) {
  const bool fixed = fixed_size_dim(scene.dim());
  if (scene.space.has_topology()) {
    // Every front end's scene (a file, --method, Python, a sweep, a checkpoint) comes through here.
    check_topology_method(scene, Origin{scene.source, scene.integrator.line}, "integrator.method");
    return topology_integrator(scene);
  }
  if (is_embedded_method(scene.integrator.method)) {
    switch (scene.space.kind) {
      case SpaceKind::sphere:
        return sphere_geodesic_integrator(scene);
      case SpaceKind::hyperbolic:
        return hyperbolic_geodesic_integrator(scene);
      case SpaceKind::euclidean:
        break;
    }
    // On E^n the geodesic splitting is the chart methods' drift-kick splitting in Cartesian
    // coordinates: the sesi methods are already it.
    throw InputError("method '" + scene.integrator.method + "' runs on curved spaces only (sphere, hyperbolic), and " +
                     scene.source + " is on the euclidean space E^" + std::to_string(scene.dim()) +
                     "; there the sesi methods are the same splitting ('" +
                     std::string(scene.integrator.method).replace(0, 8, "sesi") + "')");
  }
  switch (scene.space.kind) {
    case SpaceKind::sphere:
      return fixed ? sphere_integrator_fixed(scene) : sphere_integrator_dynamic(scene);
    case SpaceKind::hyperbolic:
      return fixed ? hyperbolic_integrator_fixed(scene) : hyperbolic_integrator_dynamic(scene);
    case SpaceKind::euclidean:
      break;
  }
  return fixed ? euclidean_integrator_fixed(scene) : euclidean_integrator_dynamic(scene);
}

std::unique_ptr<Integrator> make_integrator(const Scene& scene, const Integrator& from) {
  // The post-processed state: a processed method's kernel's variables are not the state, and
  // another method (or the same with another step) would step them as if they were.
  FramedState state = from.shown_state();
  if (state.embedded == is_embedded_method(scene.integrator.method)) {
    std::unique_ptr<Integrator> next = make_integrator(scene);
    next->start_from(state);
    return next;
  }
  // A chart state and an embedded state: through the scene's chart, as the initial state.
  Scene at = scene;
  Eigen::MatrixXd q, p;
  from.read(q, p);
  for (int b = 0; b < at.body_count(); ++b) {
    at.bodies[static_cast<std::size_t>(b)].q = q.col(b);
    at.bodies[static_cast<std::size_t>(b)].p = p.col(b);
  }
  return make_integrator(at);
}

}  // namespace sesi::program
