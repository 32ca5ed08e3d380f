// The thermostat as a stage of the composition engine (include/sesi/thermostat.hpp, stepper.hpp)
// and its counter-based normals (include/sesi/random.hpp); issue #25, docs/thermostats.md.
//
//  - gamma = 0 is the engine's kick-drift-kick Strang step bit for bit (S^2, H^2);
//  - the normals are a pure function of their key; a run is a pure function of (seed, state,
//    step counter): the same seed gives the same trajectory, a resumed run (save()/load()) the
//    same bits, one thread and two the same bits and the same heat;
//  - the heat is the kinetic energy the stages put in (free bodies: H - H0 = heat to round-off);
//  - the runtime table and the re-charting wrapper (the program's engine) step as the fixed one;
//  - bad parameters and a thermostat with a table of several stages are refused.
// The sampling tests: thermostat_langevin.cpp, thermostat_brownian.cpp, thermostat_bias.cpp.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include <doctest/doctest.h>

#include "common.hpp"

#include <sesi/random.hpp>
#include <sesi/recharting.hpp>
#include <sesi/thermostat.hpp>

namespace {

using namespace coretest;
using S2 = sesi::Sphere<2, double>;
using H2 = sesi::Hyperbolic<2, double>;

// ---- gamma = 0 ------------------------------------------------------------------------------

// BAOAB with no friction is B A A B with the two top-level half flows fused (as the engine fuses
// them), i.e. the kick-drift-kick Strang step: the same operations in the same order, so the
// states must agree to the bit. (The drift-kick-drift Sesi2 is a different step.)
template <class Chart>
void check_zero_friction() {
  const auto sys = make_scene<Chart>();
  auto a = initial_state(sys);
  auto b = a;
  sesi::Composition<sesi::coefficients::Strang, Chart, sesi::Splitting::kick_drift_kick> nve;
  sesi::LangevinBAOAB<Chart> langevin(1.0, 0.0, 12345);
  const double dt = 0.01;
  for (int k = 0; k < 500; ++k) {
    nve.do_step(sys, a, k * dt, dt);
    langevin.do_step(sys, b, k * dt, dt);
  }
  CHECK(langevin.step() == 500);
  CHECK(a.q == b.q);
  CHECK(a.p == b.p);
  CHECK(a.q.array().isFinite().all());
}

TEST_CASE("langevin: gamma = 0 is the kick-drift-kick Strang step bit for bit (S^2, H^2)") {
  check_zero_friction<S2>();
  check_zero_friction<H2>();
}

// ---- determinism ----------------------------------------------------------------------------

TEST_CASE("random: the normals are a pure function of the key") {
  using sesi::random::normal;
  using sesi::random::normal_pair;
  const std::uint64_t s = sesi::random::stream::langevin;
  // Forwards, then backwards in another order of the key's words: the same numbers.
  std::vector<double> forward, backward;
  for (std::uint64_t step = 0; step < 4; ++step)
    for (std::uint64_t body = 0; body < 3; ++body)
      for (std::uint64_t c = 0; c < 5; ++c) forward.push_back(normal(99, s, step, body, c));
  backward.resize(forward.size());
  for (std::uint64_t c = 5; c-- > 0;)
    for (std::uint64_t body = 3; body-- > 0;)
      for (std::uint64_t step = 4; step-- > 0;) backward[(step * 3 + body) * 5 + c] = normal(99, s, step, body, c);
  CHECK(forward == backward);
  const auto z = normal_pair(99, s, 2, 1, 1);
  CHECK(z[0] == normal(99, s, 2, 1, 2));
  CHECK(z[1] == normal(99, s, 2, 1, 3));
  // Every word of the key matters.
  const double x = normal(99, s, 2, 1, 2);
  CHECK(x != normal(98, s, 2, 1, 2));
  CHECK(x != normal(99, sesi::random::stream::perturbation, 2, 1, 2));
  CHECK(x != normal(99, s, 3, 1, 2));
  CHECK(x != normal(99, s, 2, 0, 2));
  CHECK(x != normal(99, s, 2, 1, 0));
  CHECK(z[0] != z[1]);
}

TEST_CASE("langevin: same seed, same trajectory; a resumed run gives the same bits") {
  const auto sys = make_scene<S2>();
  const auto x0 = initial_state(sys);
  const double dt = 0.01;
  const auto run_from = [&](sesi::State<S2> x, std::uint64_t seed, std::uint64_t first, int steps) {
    sesi::LangevinBAOAB<S2> stepper(0.5, 2.0, seed, first);
    for (int k = 0; k < steps; ++k) stepper.do_step(sys, x, (double(first) + k) * dt, dt);
    return x;
  };
  const auto a = run_from(x0, 7, 0, 300);
  const auto b = run_from(x0, 7, 0, 300);
  CHECK(a.q == b.q);
  CHECK(a.p == b.p);
  // Resume: a fresh stepper at step 150 from the state after 150 steps.
  const auto c = run_from(run_from(x0, 7, 0, 150), 7, 150, 150);
  CHECK(a.q == c.q);
  CHECK(a.p == c.p);
  // Another seed, another trajectory.
  const auto d = run_from(x0, 8, 0, 300);
  CHECK(coretest::distance(a, d) > 1e-3);
}

TEST_CASE("langevin: the same bits on one thread and on two (600 bodies: the threaded loops)") {
  // 600 bodies >= 2 parallel::min_parallel_bodies, so two threads split the bodies into chunks.
  const S2 chart(1.0);
  S2::Ambient centre(3);
  centre << 0.6, 0.0, 0.8;
  const sesi::System sys(chart, std::vector<double>(600, 1.0), Trap<S2>{2.0, centre});
  sesi::State<S2> x0(2, 600);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int b = 0; b < 600; ++b) x0.set_body(b, {1.0 + 1.1 * u(rng), 6.28 * u(rng)}, {u(rng) - 0.5, u(rng) - 0.5});
  const auto run_on = [&](int threads) {
    sesi::parallel::set_threads(threads);
#if defined(_OPENMP)
    CHECK(sesi::parallel::chunks_for(600) == (threads == 1 ? 1 : 8));  // the loops do split
#endif
    auto x = x0;
    sesi::LangevinBAOAB<S2> stepper(1.0, 3.0, 5);
    for (int k = 0; k < 20; ++k) stepper.do_step(sys, x, k * 0.01, 0.01);
    sesi::parallel::set_threads(0);
    return std::make_pair(x, stepper.stage().heat());
  };
  const auto [one, heat_one] = run_on(1);
  const auto [two, heat_two] = run_on(2);
  CHECK(one.q == two.q);
  CHECK(one.p == two.p);
  CHECK(heat_one == heat_two);  // summed in body order, whatever the threads
  CHECK(heat_one != 0.0);
}

// ---- the stage's bookkeeping ------------------------------------------------------------------

sesi::ThermostatParams<double> params(sesi::ThermostatKind kind) {
  sesi::ThermostatParams<double> p;
  p.kind = kind;
  p.kT = 0.7;
  p.gamma = 2.0;
  p.tau = 0.1;
  p.chain = 3;
  p.seed = 42;
  return p;
}
constexpr sesi::ThermostatKind all_kinds[] = {sesi::ThermostatKind::langevin, sesi::ThermostatKind::nose_hoover,
                                              sesi::ThermostatKind::csvr, sesi::ThermostatKind::brownian};

TEST_CASE("thermostat: free bodies gain exactly the heat (every kind, S^1)") {
  // Free bodies on S^1: no potential, one level whose flow is exact and keeps K = p^2/2m, so
  // H(t) - H(0) = K(t) - K(0) is the sum of the stages' kinetic-energy changes, heat(). (On S^n,
  // n >= 2, the split kinetic sweep itself changes K by the step's O(h^2) error.) Each step rounds
  // a few times at the size of eps K per body (O, the rescale, the sums): over 400 steps of 40
  // bodies the difference stays below 400 * 40 * 8 eps * max K (a generous count of roundings).
  using S1 = sesi::Sphere<1, double>;
  const S1 chart(1.0);
  const sesi::System sys(chart, std::vector<double>(40, 1.0));
  sesi::State<S1> x0(1, 40);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int b = 0; b < 40; ++b) x0.set_body(b, {6.28 * u(rng)}, {u(rng) - 0.5});
  for (const auto kind : all_kinds) {
    sesi::Thermostatted<S1> st{sesi::Thermostat<S1>(params(kind))};
    auto x = x0;
    const double k0 = sys.kinetic_energy(x);
    double kmax = k0;
    for (int k = 0; k < 400; ++k) {
      st.do_step(sys, x, k * 0.01, 0.01);
      kmax = std::max(kmax, sys.kinetic_energy(x));
    }
    const double gained = sys.kinetic_energy(x) - k0;
    CAPTURE(static_cast<int>(kind));
    CHECK(st.stage().step() == 400);
    CHECK(std::abs(st.stage().heat()) > 1e-3);  // it did act: kT/2 = 0.35 per body against K0/N ~ 1/24
    CHECK(std::abs(gained - st.stage().heat()) < 400.0 * 40 * 8 * coretest::eps<double>() * kmax);
    if (kind == sesi::ThermostatKind::brownian) {
      CHECK(std::isnan(st.stage().conserved_offset()));
    } else if (kind != sesi::ThermostatKind::nose_hoover) {
      CHECK(st.stage().conserved_offset() == -st.stage().heat());
    }
  }
}

TEST_CASE("thermostat: save() and load() resume every kind bit for bit (S^2, trap and pair term)") {
  const auto sys = make_scene<S2>();
  const auto x0 = initial_state(sys);
  const double dt = 0.01;
  for (const auto kind : all_kinds) {
    CAPTURE(static_cast<int>(kind));
    sesi::Thermostatted<S2> whole{sesi::Thermostat<S2>(params(kind))};
    sesi::Thermostatted<S2> first{sesi::Thermostat<S2>(params(kind))};
    auto a = x0, b = x0;
    for (int k = 0; k < 200; ++k) whole.do_step(sys, a, k * dt, dt);
    for (int k = 0; k < 100; ++k) first.do_step(sys, b, k * dt, dt);
    // A fresh engine (no trig cache, no kept gradient) with the saved stage.
    sesi::Thermostatted<S2> second{sesi::Thermostat<S2>(params(kind))};
    second.stage().load(first.stage().save());
    CHECK(second.stage().step() == 100);
    for (int k = 100; k < 200; ++k) second.do_step(sys, b, k * dt, dt);
    CHECK(a.q == b.q);
    CHECK(a.p == b.p);
    CHECK(whole.stage().heat() == second.stage().heat());
    if (kind != sesi::ThermostatKind::brownian)
      CHECK(whole.stage().conserved_offset() == second.stage().conserved_offset());
  }
}

TEST_CASE("thermostat: the program's engine (runtime table, re-charting) steps as the fixed table") {
  // Composition<Runtime, ...>::of<Strang>(stage) runs the same operations as the fixed table, and
  // Recharting<...> re-charts after each step: on S^2 and H^2 (trap and pair term), 300 steps.
  const auto check = [](const auto& sys) {
    using Chart = typename std::remove_cvref_t<decltype(sys)>::Chart;
    using Runtime = sesi::Composition<sesi::coefficients::Runtime, Chart, sesi::Splitting::kick_drift_kick,
                                      sesi::Thermostat<Chart>>;
    for (const auto kind : all_kinds) {
      CAPTURE(static_cast<int>(kind));
      sesi::Recharting<sesi::Thermostatted<Chart>> fixed(sesi::RechartPolicy<double>{},
                                                          sesi::Thermostat<Chart>(params(kind)));
      sesi::Recharting<Runtime> runtime(sesi::RechartPolicy<double>{},
                                        Runtime::template of<sesi::coefficients::Strang>(sesi::Thermostat<Chart>(params(kind))));
      auto a = initial_state(sys), b = a;
      for (int k = 0; k < 300; ++k) {
        fixed.do_step(sys, a, k * 0.01, 0.01);
        runtime.do_step(sys, b, k * 0.01, 0.01);
      }
      CHECK(a.q == b.q);
      CHECK(a.p == b.p);
      CHECK(a.q.array().isFinite().all());
      CHECK(fixed.stage().heat() == runtime.stage().heat());
    }
  };
  check(make_scene<S2>());
  check(make_scene<H2>());
}

TEST_CASE("thermostat: bad parameters and a table of several stages are refused") {
  using Kind = sesi::ThermostatKind;
  auto p = params(Kind::langevin);
  p.kT = -1;
  CHECK_THROWS_AS(sesi::Thermostat<S2>{p}, coretest::CheckFailure);
  p = params(Kind::langevin);
  p.gamma = -1;
  CHECK_THROWS_AS(sesi::Thermostat<S2>{p}, coretest::CheckFailure);
  p = params(Kind::brownian);
  p.gamma = 0;
  CHECK_THROWS_AS(sesi::Thermostat<S2>{p}, coretest::CheckFailure);
  p = params(Kind::nose_hoover);
  p.tau = 0;
  CHECK_THROWS_AS(sesi::Thermostat<S2>{p}, coretest::CheckFailure);
  p = params(Kind::nose_hoover);
  p.chain = 0;
  CHECK_THROWS_AS(sesi::Thermostat<S2>{p}, coretest::CheckFailure);
  p = params(Kind::csvr);
  p.tau = -1;
  CHECK_THROWS_AS(sesi::Thermostat<S2>{p}, coretest::CheckFailure);
  sesi::Thermostat<S2> t(params(Kind::langevin));
  CHECK_THROWS_AS(t.set_temperature(-0.5), coretest::CheckFailure);
  t.set_temperature(2.5);
  CHECK(t.params().kT == 2.5);
  using Engine = sesi::Composition<sesi::coefficients::Runtime, S2, sesi::Splitting::kick_drift_kick, sesi::Thermostat<S2>>;
  CHECK_THROWS_AS(Engine::of<sesi::coefficients::Yoshida4>(sesi::Thermostat<S2>(params(Kind::langevin))),
                  coretest::CheckFailure);
}

}  // namespace

