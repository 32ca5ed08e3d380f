// Long runs (issue #5): 10^7 steps of SESI 2 and 10^6 of SESI 4 on the seed's scene
// (include/sesi/scenes/paper.hpp, dt = 0.1) and on the same scene turned 45 degrees about the
// x axis, so that the bodies' orbits sweep across the chart's pole and are re-charted again and
// again (sesi::Recharting). A symplectic method's energy error is bounded: the largest |E - E0|
// in the last tenth of the run may not exceed twice that of the first tenth, plus the round-off
// that accumulates over the run (bounded(), below). Energy sampled every 10 steps (a step costs
// less than an energy evaluation).
#include <doctest/doctest.h>

#include <cmath>
#include <numbers>
#include <string>

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

/// Energy error record of a run, with the run's length, its method's stages and its energy scale
/// |T0| + |V0| (the terms whose rounding the energy carries; E0 itself may cancel).
struct Run : stab::Tenths {
  long steps = 0;
  long stages = 0;
  double scale = 0;
};

/// The run's round-off term: steps x stages x eps x energy scale. A symplectic method conserves a
/// modified energy to O(dt^p) for exponentially long times, but each stage's rounding (about eps
/// relative to the state, hence to the energy's terms) is a perturbation it does not undo.
/// Rounding errors of either sign add like a random walk (Brouwer's law, ~sqrt(steps) eps E;
/// Hairer, McLachlan & Razakarivony, BIT 48 (2008) 231); biased ones add linearly, so the linear
/// term bounds both. The issue #12 runs, 10x longer than these, grew last/first to 1.4 (sesi2),
/// 2.3 (sesi4), 3.0 (sesi6), 48 (sesi8) in double and stayed near 1.2 in long double: rounding,
/// which a plain "last <= 2 first" would call drift at order 8, where first is tiny.
double rounding(const Run& r) { return double(r.steps) * double(r.stages) * stab::eps<double>() * r.scale; }

/// Bounded energy error: last tenth <= 2 x first tenth + the round-off term. The term stays
/// far below the truncation error of sesi2 and sesi4 here (reported: its ratio to first), so a
/// real drift (the 11x growth of homing re-chartings, docs/stability.md) still fails.
bool bounded(const Run& r, const std::string& label) {
  stab::report(label + ": round-off term steps stages eps (|T0| + |V0|)", rounding(r));
  stab::report(label + ": round-off term / max |dE| first tenth", rounding(r) / r.first);
  return r.last <= 2 * r.first + rounding(r);
}

template <template <class> class Method>
Run run(const char* name, long steps, bool turned) {
  const auto sys = paper::make_system<S>();
  auto x = paper::initial_state<S>();
  const double dt = paper::Constants<S>::tau;
  Run t;
  t.steps = steps;
  t.stages = long(Method<Chart>::table::stages);
  const auto scale = [&sys](const auto& state) {
    return std::abs(double(sys.kinetic_energy(state))) + std::abs(double(sys.potential_energy(state)));
  };
  if (turned) {
    const stab::Mat<S> turn = stab::givens<S>(3, 1, 2, std::numbers::pi / 4);
    x = stab::from_world(sys, stab::Mat<S>(turn * sesi::embedding_points(sys, x)),
                         stab::Mat<S>(turn * sesi::embedding_velocities(sys, x)));
    stab::Rech<Method, Chart> st;
    sesi::rechart(sys, x, st.policy());
    t.scale = scale(x);
    static_cast<stab::Tenths&>(t) = stab::energy_tenths(st, sys, x, dt, steps, 10);
  } else {
    Method<Chart> st;
    t.scale = scale(x);
    static_cast<stab::Tenths&>(t) = stab::energy_tenths(st, sys, x, dt, steps, 10);
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
  CHECK(bounded(a, "long sesi2 seed scene"));
  const auto b = run<sesi::Yoshida4>("sesi4", 1'000'000, false);
  CHECK(bounded(b, "long sesi4 seed scene"));
}

// Each re-charting changes the chart, hence the modified energy the method conserves; the turns
// of recharting.hpp keep its chart-dependent kinetic part and the kick-drift-kick form has no
// other at second order, so the jumps are of higher order and of either sign (docs/charts.md).
// Before the turns (homing every time) SESI 4's |dE| grew 11x here, SESI 2's 2.0x.
TEST_CASE("long runs: a pole-crossing scene with re-charting, energy error bounded") {
  const auto a = run<sesi::Strang>("sesi2", 10'000'000, true);
  CHECK(a.recharts > 1000);
  CHECK(bounded(a, "long sesi2 pole-crossing scene"));
  const auto b = run<sesi::Yoshida4>("sesi4", 1'000'000, true);
  CHECK(b.recharts > 100);
  CHECK(bounded(b, "long sesi4 pole-crossing scene"));
  // Order 8, where the truncation error is small enough that round-off shows (issue #12). Measured:
  // last/first 1.86, round-off term 3.1 x first, so a growth beyond 5.1x (homing's 11x) still fails.
  const auto c = run<sesi::McLachlan8>("sesi8", 100'000, true);
  CHECK(c.recharts > 10);
  CHECK(bounded(c, "long sesi8 pole-crossing scene"));
  // And at the level of the untilted scene's, not above it (measured: 0.9x and 0.4x).
  const auto a0 = run<sesi::Strang>("sesi2", 1'000'000, false);
  const auto b0 = run<sesi::Yoshida4>("sesi4", 100'000, false);
  CHECK(a.overall <= 2 * a0.overall);
  CHECK(b.overall <= 2 * b0.overall);
  // The untilted scene in kick-drift-kick form too, for docs/scheme.md (reported, not asserted).
  run<StrangKdk>("sesi2 kick-drift-kick", 1'000'000, false);
  run<Yoshida4Kdk>("sesi4 kick-drift-kick", 100'000, false);
}
