// Close encounters of singular potentials (issue #5): sesi::closest_encounter and its floor
// (default L eps^(1/3), include/sesi/potentials.hpp), and head-on collisions run under the
// floor and the energy guard (sesi::EnergyGuard): the run must stop with a named pair or a
// tripped guard while the state is still finite -- never NaN.
#include <doctest/doctest.h>

#include <cmath>
#include <numbers>

#include "common.hpp"

namespace {

using S = double;
using stab::report;

template <class Sys>
sesi::State<typename Sys::Chart> two_on_equator(const Sys& sys, S phi0, S phi1) {
  sesi::State<typename Sys::Chart> x(2, 2);
  x.q << std::numbers::pi / 2, std::numbers::pi / 2, phi0, phi1;
  x.p.setZero();
  (void)sys;
  return x;
}

/// How a guarded run ended.
struct Stop {
  long step = 0;  // 0: ran to the end
  bool encounter = false, guard = false, finite = true;
  sesi::Encounter<S> where;
  double error = 0;
};

/// Step sys from x with the floor and the energy guard checked after every step (as the
/// program's run loop does), until one trips or `steps` are done.
template <class Stepper, class Sys>
Stop guarded(Stepper& st, const Sys& sys, sesi::State<typename Sys::Chart>& x, S dt, long steps,
             S relative = S(sesi::EnergyGuard<S>::default_relative)) {
  const auto guard = sesi::EnergyGuard<S>::of(sys, x, relative);
  auto w = sys.make_workspace();
  Stop out;
  for (long k = 1; k <= steps; ++k) {
    st.do_step(sys, x, S(k - 1) * dt, dt);
    out.finite = x.q.allFinite() && x.p.allFinite();
    const auto e = sesi::closest_encounter(sys, x, w);
    const auto g = guard.check(sys, x, k, S(k) * dt);
    if (e.found() || !g.ok()) {
      out.step = k;
      out.encounter = e.found();
      out.where = e;
      out.guard = !g.ok();
      out.error = g.error;
      out.finite = out.finite && g.status != sesi::GuardStatus::non_finite;
      return out;
    }
  }
  return out;
}

}  // namespace

TEST_CASE("encounters: the floor of each singular term, pairs and centers, and none without one") {
  using Chart = sesi::Sphere<2, S>;
  const S floor = sesi::default_min_distance<S>(1.0);
  report("encounters default floor (R = 1, double)", floor);
  CHECK(floor == doctest::Approx(std::cbrt(stab::eps<S>())));
  {
    const auto sys = sesi::System(Chart(1.0), std::vector<S>{1.0, 1.0}, sesi::CotangentGravity<S>{1.0});
    auto x = two_on_equator(sys, 0.0, 0.5 * floor);
    auto e = sesi::closest_encounter(sys, x);
    CHECK(e.found());
    CHECK(e.first == 0);
    CHECK(e.second == 1);
    CHECK(e.gap == doctest::Approx(0.5 * floor).epsilon(1e-6));
    x = two_on_equator(sys, 0.0, 2 * floor);
    CHECK(!sesi::closest_encounter(sys, x).found());
    // The antipode is singular for cot(d/R) too.
    x = two_on_equator(sys, 0.0, std::numbers::pi - 0.5 * floor);
    CHECK(sesi::closest_encounter(sys, x).found());
    // min_distance = 0 turns the check off.
    const auto off = sesi::System(Chart(1.0), std::vector<S>{1.0, 1.0}, sesi::CotangentGravity<S>{1.0, 0.0});
    CHECK(!sesi::closest_encounter(off, two_on_equator(off, 0.0, 0.5 * floor)).found());
  }
  {
    // Lennard-Jones: the floor scales with sigma; the check does not look at the antipode.
    const auto sys = sesi::System(Chart(1.0), std::vector<S>{1.0, 1.0}, sesi::LennardJones<S>{1.0, 0.1, 0.25});
    CHECK(sesi::closest_encounter(sys, two_on_equator(sys, 0.0, 0.05 * floor)).found());
    CHECK(!sesi::closest_encounter(sys, two_on_equator(sys, 0.0, 0.2 * floor)).found());
    CHECK(!sesi::closest_encounter(sys, two_on_equator(sys, 0.0, std::numbers::pi - 0.05 * floor)).found());
  }
  {
    // Central cotangent: the body and the center (second = -1).
    sesi::CentralCotangent<Chart> term;
    term.k = 1;
    term.center = Chart::Ambient(1.0, 0.0, 0.0);
    const auto sys = sesi::System(Chart(1.0), std::vector<S>{1.0, 1.0}, term);
    const auto e = sesi::closest_encounter(sys, two_on_equator(sys, 1.0, 0.3 * floor));
    CHECK(e.found());
    CHECK(e.first == 1);
    CHECK(e.second == -1);
  }
  {
    // No singular term: closest_encounter is compiled out.
    const auto sys = sesi::System(Chart(1.0), std::vector<S>{1.0, 1.0}, sesi::HarmonicPair<S>{1.0, 0.0});
    static_assert(!sesi::has_singular_terms<std::remove_cvref_t<decltype(sys)>>);
    CHECK(!sesi::closest_encounter(sys, two_on_equator(sys, 0.0, 0.0)).found());
  }
}

TEST_CASE("encounters: head-on collisions stop with a named pair or a tripped guard, never NaN") {
  // Two unit masses falling onto each other from rest (G = 1, separation 0.5 on the unit S^2;
  // and on E^2): they collide at t ~ 0.28; the steps do not resolve the collision.
  using Chart = sesi::Sphere<2, S>;
  for (const S dt : {1e-2, 1e-3, 1e-4}) {
    const auto sys = sesi::System(Chart(1.0), std::vector<S>{1.0, 1.0}, sesi::CotangentGravity<S>{1.0});
    auto x = two_on_equator(sys, -0.25, 0.25);
    sesi::Yoshida4<Chart> st;
    const Stop r = guarded(st, sys, x, dt, std::lround(1.0 / dt));
    char label[96];
    std::snprintf(label, sizeof label, "encounters S^2 head-on sesi4 dt=%g default floor", dt);
    report(std::string(label) + ": stopped at step", double(r.step));
    report(std::string(label) + ": by the floor (1) or the guard (0)", r.encounter ? 1.0 : 0.0);
    report(std::string(label) + ": relative energy error at the stop", r.error);
    CHECK(r.step > 0);
    CHECK(r.finite);
    CHECK((r.encounter || r.guard));
  }
  // With a floor the step resolves (min_distance = 0.05), the floor names the pair first.
  {
    const auto sys = sesi::System(Chart(1.0), std::vector<S>{1.0, 1.0}, sesi::CotangentGravity<S>{1.0, 0.05});
    auto x = two_on_equator(sys, -0.25, 0.25);
    sesi::Yoshida4<Chart> st;
    const Stop r = guarded(st, sys, x, 1e-3, 1000);
    report("encounters S^2 head-on sesi4 dt=0.001 min_distance=0.05: stopped at step", double(r.step));
    report("encounters S^2 head-on sesi4 dt=0.001 min_distance=0.05: gap", r.where.gap);
    CHECK(r.encounter);
    CHECK(!r.guard);
    CHECK(r.where.first == 0);
    CHECK(r.where.second == 1);
    CHECK(r.where.gap < 0.05);
    CHECK(r.where.gap > 0.0);
  }
  // On E^2 the same collision, and a body falling onto a central-cotangent center.
  {
    using E = sesi::Euclidean<2, S>;
    const auto sys = sesi::System(E(), std::vector<S>{1.0, 1.0}, sesi::CotangentGravity<S>{1.0});
    sesi::State<E> x(2, 2);
    x.q << -0.25, 0.25, 0.0, 0.0;
    sesi::Strang<E> st;
    const Stop r = guarded(st, sys, x, 1e-3, 1000);
    report("encounters E^2 head-on sesi2 dt=0.001: stopped at step", double(r.step));
    report("encounters E^2 head-on sesi2 dt=0.001: by the floor (1) or the guard (0)", r.encounter ? 1.0 : 0.0);
    CHECK(r.step > 0);
    CHECK(r.finite);
  }
  {
    sesi::CentralCotangent<Chart> term;
    term.k = 1;
    term.center = Chart::Ambient(1.0, 0.0, 0.0);
    const auto sys = sesi::System(Chart(1.0), std::vector<S>{1.0}, term);
    sesi::State<Chart> x(2, 1);
    x.q << std::numbers::pi / 2, 0.4;
    sesi::Yoshida4<Chart> st;
    const Stop r = guarded(st, sys, x, 1e-3, 2000);
    report("encounters S^2 fall onto a central-cotangent center sesi4 dt=0.001: stopped at step", double(r.step));
    CHECK(r.step > 0);
    CHECK(r.finite);
  }
}

TEST_CASE("encounters: without floor and guard, the same collision goes unnoticed (the check can fail)") {
  // Reference for the test above: the unguarded run ends finite but with an energy error far
  // beyond the guard -- silent garbage, which the guard and the floor turn into a stop.
  using Chart = sesi::Sphere<2, S>;
  const auto sys = sesi::System(Chart(1.0), std::vector<S>{1.0, 1.0}, sesi::CotangentGravity<S>{1.0});
  auto x = two_on_equator(sys, -0.25, 0.25);
  const S e0 = sys.energy(x);
  sesi::Yoshida4<Chart> st;
  stab::run(st, sys, x, 1e-3, 1000);
  const S e1 = sys.energy(x);
  const auto guard = sesi::EnergyGuard<S>::of(sys, two_on_equator(sys, -0.25, 0.25));
  report("encounters S^2 head-on unguarded: final relative energy error", std::abs(e1 - e0) / guard.scale());
  CHECK(!guard.check(1000, 1.0, e1).ok());
}
