// A composition over a runtime table (sesi::Composition<coefficients::Runtime, Chart>, the
// program's engine) must step exactly as the one over the same compile-time table: same
// operations in the same order, so bit-identical states.
#include <doctest/doctest.h>

#include <sesi/coefficients.hpp>
#include <sesi/potentials.hpp>
#include <sesi/scenes/paper.hpp>
#include <sesi/spaces/euclidean.hpp>
#include <sesi/spaces/hyperbolic.hpp>
#include <sesi/stepper.hpp>
#include <sesi/system.hpp>

namespace {

/// Step both engines n times from x with step dt; they must agree exactly after every step.
template <class Table, class Sys>
void expect_identical(const Sys& sys, typename Sys::StateType x, double dt, int n) {
  using Chart = typename Sys::Chart;
  sesi::Composition<Table, Chart> library;
  auto runtime = sesi::Composition<sesi::coefficients::Runtime, Chart>::template of<Table>();
  REQUIRE(runtime.order() == library.order());
  REQUIRE(runtime.stages() == library.stages());
  auto y = x;
  for (int k = 0; k < n; ++k) {
    library.do_step(std::cref(sys), x, k * dt, dt);
    runtime.do_step(sys, y, k * dt, dt);
    REQUIRE(x.q == y.q);
    REQUIRE(x.p == y.p);
  }
}

}  // namespace

TEST_CASE_TEMPLATE("runtime composition equals sesi::Composition on the seed's scene", Table,
                   sesi::coefficients::Strang, sesi::coefficients::Yoshida4, sesi::coefficients::Suzuki4,
                   sesi::coefficients::McLachlan4, sesi::coefficients::Yoshida6, sesi::coefficients::KahanLi6,
                   sesi::coefficients::McLachlan8, sesi::coefficients::KahanLi8) {
  const auto sys = sesi::scenes::paper::make_system();
  expect_identical<Table>(sys, sesi::scenes::paper::initial_state(), 0.1, 50);
}

TEST_CASE("runtime composition equals sesi::Composition on H^3 (trig cache) and E^2 (none)") {
  using H3 = sesi::Hyperbolic<3>;
  const sesi::System hyperbolic(H3(1.5), std::vector<double>{1.0, 2.0}, sesi::CotangentGravity<double>{0.5});
  sesi::State<H3> x(3, 2);
  x.q << 0.7, 1.3, 0.9, 1.1, 0.4, 2.0;
  x.p << 0.1, -0.2, 0.3, 0.2, 0.1, -0.4;
  expect_identical<sesi::coefficients::Yoshida4>(hyperbolic, x, 0.01, 100);

  using E2 = sesi::Euclidean<2>;
  const sesi::System flat(E2(), std::vector<double>{1.0, 1.0}, sesi::HarmonicPair<double>{2.0, 0.5});
  sesi::State<E2> y(2, 2);
  y.q << 0.0, 1.0, 0.0, 0.2;
  y.p << 0.3, -0.3, 0.1, 0.0;
  expect_identical<sesi::coefficients::KahanLi6>(flat, y, 0.01, 100);
}
