// The program's integrators (src/integrators) take states of their own kind only, and a method
// switch (make_integrator(scene, from), sesi.Simulation.method) starts from the state the outputs
// show, never from a processed method's kernel's variables.
#include <doctest/doctest.h>

#include <stdexcept>
#include <string>

#include "integrator.hpp"

namespace {

using sesi::program::FramedState;
using sesi::program::Scene;
using sesi::program::SpaceKind;

/// Three bodies in a harmonic pair well on the space, at fixed chart coordinates and momenta.
Scene scene_on(SpaceKind kind, int dim, const std::string& method) {
  Scene s;
  s.name = "state-kinds";
  s.source = "<test>";
  s.space = {kind, dim, 1.3};
  for (int b = 0; b < 3; ++b) {
    sesi::program::Body body;
    body.q = Eigen::VectorXd::Constant(dim, 0.6 + 0.3 * b);
    body.p = Eigen::VectorXd::LinSpaced(dim, 0.2, -0.1 * b);
    s.bodies.push_back(body);
  }
  s.potentials.emplace_back(sesi::program::HarmonicPairSpec{1.0, 0.5});
  s.integrator.method = method;
  s.integrator.dt = 0.05;
  return s;
}

void expect_same(const FramedState& a, const FramedState& b) {
  REQUIRE(a.embedded == b.embedded);
  if (a.embedded) {
    CHECK(a.x == b.x);
    CHECK(a.v == b.v);
  } else {
    CHECK(a.q == b.q);
    CHECK(a.p == b.p);
  }
}

}  // namespace

TEST_CASE("a chart method's integrator refuses a state of another kind or size") {
  // Plain variables, not structured bindings: CAPTURE's lambda cannot capture those in C++20 (clang).
  for (const auto& space : {std::pair{SpaceKind::sphere, 2}, std::pair{SpaceKind::hyperbolic, 3},
                            std::pair{SpaceKind::euclidean, 2}, std::pair{SpaceKind::sphere, 9}}) {
    const SpaceKind kind = space.first;
    const int dim = space.second;
    for (const char* method : {"sesi4", "sesi6-processed"}) {
      CAPTURE(dim);
      CAPTURE(method);
      const auto integrator = sesi::program::make_integrator(scene_on(kind, dim, method));
      const FramedState own = integrator->framed_state();
      REQUIRE_FALSE(own.embedded);

      FramedState embedded;  // a geodesic method's: x, v of the same bodies, no q, p
      embedded.embedded = true;
      embedded.x = integrator->points();
      embedded.v = integrator->velocities();
      CHECK_THROWS_AS(integrator->restore(embedded), std::logic_error);
      CHECK_THROWS_AS(integrator->start_from(embedded), std::logic_error);

      FramedState short_of_a_body = own;
      short_of_a_body.q.conservativeResize(Eigen::NoChange, 2);
      short_of_a_body.p.conservativeResize(Eigen::NoChange, 2);
      CHECK_THROWS_AS(integrator->restore(short_of_a_body), std::logic_error);

      integrator->restore(own);  // its own kind is taken, unchanged
      expect_same(integrator->framed_state(), own);
    }
  }
}

TEST_CASE("a geodesic method's integrator refuses a chart state") {
  const auto integrator = sesi::program::make_integrator(scene_on(SpaceKind::sphere, 3, "geodesic4"));
  FramedState chart;
  chart.q = Eigen::MatrixXd::Zero(3, 3);
  chart.p = Eigen::MatrixXd::Zero(3, 3);
  CHECK_THROWS_AS(integrator->restore(chart), std::logic_error);
}

TEST_CASE("a method switch starts from the post-processed state, not the kernel's variables") {
  // After steps of a processed method its framed state (kernel's variables) and its shown state
  // differ by the processor, O(dt^2); the next method must start exactly at the shown one.
  for (const auto& change : {std::pair{"sesi6-processed", "sesi4"}, std::pair{"sesi8-processed", "sesi6-processed"},
                             std::pair{"geodesic6-processed", "geodesic4"},
                             std::pair{"geodesic8-processed", "geodesic6-processed"}}) {
    const char* const from = change.first;
    const char* const to = change.second;
    CAPTURE(from);
    CAPTURE(to);
    const Scene a = scene_on(SpaceKind::sphere, 3, from);
    const auto first = sesi::program::make_integrator(a);
    for (int k = 0; k < 10; ++k) first->step(k * 0.05, 0.05);
    const FramedState shown = first->shown_state();
    const FramedState kernel = first->framed_state();
    REQUIRE(shown.embedded == kernel.embedded);
    REQUIRE((shown.embedded ? shown.x != kernel.x : shown.q != kernel.q));  // processed indeed

    Scene b = a;
    b.integrator.method = to;
    const auto second = sesi::program::make_integrator(b, *first);
    expect_same(second->shown_state(), shown);
    expect_same(second->framed_state(), shown);  // a processed method: the state itself until it steps
  }
}
