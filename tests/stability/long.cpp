// Long runs (issue #5): 10^7 steps of SESI 2 and 10^6 of SESI 4 on the seed's scene
// (include/sesi/scenes/paper.hpp, dt = 0.1) and on the same scene turned 45 degrees about the
// x axis, so that the bodies' orbits sweep across the chart's pole and are re-charted again and
// again (sesi::Recharting). A symplectic method's energy error is bounded: the largest |E - E0|
// in the last tenth of the run may not exceed twice that of the first tenth. Energy sampled
// every 10 steps (a step costs less than an energy evaluation).
#include <doctest/doctest.h>

#include <numbers>

#include <sesi/scenes/paper.hpp>

#include "common.hpp"

namespace {

namespace paper = sesi::scenes::paper;
using S = double;
using Chart = paper::Chart<S>;

template <class C>
using StrangKdk = sesi::Composition<sesi::coefficients::Strang, C, sesi::Splitting::kick_drift_kick>;
template <class C>
using Yoshida4Kdk = sesi::Composition<sesi::coefficients::Yoshida4, C, sesi::Splitting::kick_drift_kick>;

template <template <class> class Method>
stab::Tenths run(const char* name, long steps, bool turned) {
  const auto sys = paper::make_system<S>();
  auto x = paper::initial_state<S>();
  const double dt = paper::Constants<S>::tau;
  stab::Tenths t;
  if (turned) {
    const stab::Mat<S> turn = stab::givens<S>(3, 1, 2, std::numbers::pi / 4);
    x = stab::from_world(sys, stab::Mat<S>(turn * sesi::embedding_points(sys, x)),
                         stab::Mat<S>(turn * sesi::embedding_velocities(sys, x)));
    stab::Rech<Method, Chart> st;
    sesi::rechart(sys, x, st.policy());
    t = stab::energy_tenths(st, sys, x, dt, steps, 10);
  } else {
    Method<Chart> st;
    t = stab::energy_tenths(st, sys, x, dt, steps, 10);
  }
  const std::string label = std::string("long ") + name + (turned ? " pole-crossing scene" : " seed scene") +
                            " " + std::to_string(steps) + " steps";
  stab::report(label + ": max |dE| first tenth", t.first);
  stab::report(label + ": max |dE| last tenth", t.last);
  stab::report(label + ": last/first", t.growth());
  stab::report(label + ": max |dE| / E0", t.overall / double(sys.energy(paper::initial_state<S>())));
  stab::report(label + ": re-chartings", double(t.recharts));
  stab::report(label + ": of which homings", double(t.homes));
  return t;
}

}  // namespace

TEST_CASE("long runs: the seed's scene, energy error bounded over 10^7 (SESI 2) and 10^6 (SESI 4) steps") {
  const auto a = run<sesi::Strang>("sesi2", 10'000'000, false);
  CHECK(a.last <= 2 * a.first);
  const auto b = run<sesi::Yoshida4>("sesi4", 1'000'000, false);
  CHECK(b.last <= 2 * b.first);
}

// Each re-charting changes the chart, hence the modified energy the method conserves; the turns
// of recharting.hpp keep its chart-dependent kinetic part and the kick-drift-kick form has no
// other at second order, so the jumps are of higher order and of either sign (docs/charts.md).
// Before the turns (homing every time) SESI 4's |dE| grew 11x here, SESI 2's 2.0x.
TEST_CASE("long runs: a pole-crossing scene with re-charting, energy error bounded") {
  const auto a = run<sesi::Strang>("sesi2", 10'000'000, true);
  CHECK(a.recharts > 1000);
  CHECK(a.last <= 2 * a.first);
  const auto b = run<sesi::Yoshida4>("sesi4", 1'000'000, true);
  CHECK(b.recharts > 100);
  CHECK(b.last <= 2 * b.first);
  // And at the level of the untilted scene's, not above it (measured: 0.9x and 0.4x).
  const auto a0 = run<sesi::Strang>("sesi2", 1'000'000, false);
  const auto b0 = run<sesi::Yoshida4>("sesi4", 100'000, false);
  CHECK(a.overall <= 2 * a0.overall);
  CHECK(b.overall <= 2 * b0.overall);
  // The untilted scene in kick-drift-kick form too, for docs/scheme.md (reported, not asserted).
  run<StrangKdk>("sesi2 kick-drift-kick", 1'000'000, false);
  run<Yoshida4Kdk>("sesi4 kick-drift-kick", 100'000, false);
}
