// float and long double (issue #5): the stability checks at each precision, with the bounds
// that depend on round-off scaled by that precision's epsilon (double: the other files).
#include <doctest/doctest.h>

#include <cmath>
#include <numbers>

#include <sesi/scenes/paper.hpp>

#include "common.hpp"

namespace {

using stab::Mat;
using stab::report;
using stab::Vec;

template <class S>
const char* type_name() {
  return std::is_same_v<S, float> ? "float" : std::is_same_v<S, double> ? "double" : "long double";
}

/// Pole grazing, free motion on S^2 (as poles.cpp): an orbit delta from the pole, with
/// re-charting, against the same orbit tilted 45 degrees away; graze <= 10 tilted.
template <class S>
void pole_grazing() {
  // The dynamic chart: with Sphere<2, float>, g++ 12 reports a false -Warray-bounds inside
  // Eigen's vectorised copy of a Vector3f (sesi::embedding_points).
  using Chart = sesi::Sphere<Eigen::Dynamic, S>;
  const auto sys = sesi::System(Chart(S(1), 2), std::vector<S>{S(1)});
  const S dt = S(0.01);
  const long steps = 300;
  for (const double delta : {1e-3, 1e-6, 1e-9}) {
    double err[2] = {0, 0};
    for (int mode = 0; mode < 2; ++mode) {
      const S off = S(delta + (mode == 1 ? std::numbers::pi / 4 : 0.0));
      Vec<S> c(3), m(3);
      c << std::sin(off) * std::cos(S(0.7)), std::sin(off) * std::sin(S(0.7)), std::cos(off);
      m << -std::sin(S(0.7)), std::cos(S(0.7)), S(0);
      const S th = S(1.5);
      auto at = [&](S t) { return Vec<S>(std::cos(t) * c + std::sin(t) * m); };
      auto vel = [&](S t) { return Vec<S>(-std::sin(t) * c + std::cos(t) * m); };
      auto x = stab::from_world(sys, Mat<S>(at(-th)), Mat<S>(vel(-th)));
      stab::Rech<sesi::Strang, Chart> st;
      sesi::rechart(sys, x, st.policy());
      stab::run(st, sys, x, dt, steps);
      // Distances in long double from the numbers the run produced.
      const Vec<long double> got = sesi::embedding_points(sys, x).col(0).template cast<long double>();
      const Vec<long double> want = at(th).template cast<long double>();
      err[mode] = double(2 * std::atan2((got - want).norm(), (got + want).norm()));
    }
    char label[128];
    std::snprintf(label, sizeof label, "precision %s poles S^2 free sesi2 dt=0.01 delta=%g", type_name<S>(), delta);
    report(std::string(label) + " graze error", err[0]);
    report(std::string(label) + " tilted error", err[1]);
    CHECK(err[0] <= 10 * err[1]);
  }
}

/// High curvature: R = 1e-3 reproduces the unit scene scaled (extreme.cpp), to steps * eps.
template <class S, class Chart>
void scaled(const char* space) {
  const long steps = 400;
  const S R = S(1e-3L);
  auto build = [&](S r) {
    return sesi::System(Chart(r), std::vector<S>{S(1), S(0.4)}, sesi::CotangentGravity<S>{S(1)});
  };
  const auto sys1 = build(S(1)), sysr = build(R);
  sesi::State<Chart> x1(2, 2);
  x1.q << S(1.2), S(1.2), S(0.3), S(0.8);
  x1.p << S(0.49), S(-0.49), S(0.02), S(0.05);
  auto xr = x1;
  xr.p *= std::sqrt(R);
  sesi::Yoshida4<Chart> a, b;
  const S dt = S(0.005);
  stab::run(a, sys1, x1, dt, steps);
  stab::run(b, sysr, xr, dt * R * std::sqrt(R), steps);
  const double diff = double((x1.q - xr.q).cwiseAbs().maxCoeff() / x1.q.cwiseAbs().maxCoeff());
  report(std::string("precision ") + type_name<S>() + " " + space + " R=1e-3 scaled scene: max |dq|/|q|", diff);
  report(std::string("precision ") + type_name<S>() + " " + space + " R=1e-3 scaled scene: / (steps eps)",
         diff / (double(steps) * double(stab::eps<S>())));
  CHECK(diff <= double(steps) * double(stab::eps<S>()));
}

/// The energy guard on the stiff harmonic pair (stiff.cpp): quiet at 0.98 of Strang's limit 2,
/// tripped at 1.02 with the state finite.
template <class S>
void guard() {
  using Chart = sesi::Euclidean<2, S>;
  const auto sys = sesi::System(Chart(), std::vector<S>{S(1), S(1)}, sesi::HarmonicPair<S>{S(0.5), S(0)});
  for (const double x : {0.98 * 2, 1.02 * 2}) {
    sesi::State<Chart> s(2, 2);
    s.q << S(1), S(0), S(1), S(0);
    s.p << S(0), S(0), S(0.3), S(-0.3);
    const auto g = sesi::EnergyGuard<S>::of(sys, s);
    sesi::Strang<Chart> st;
    sesi::GuardResult<S> r;
    double worst = 0;
    for (long k = 1; k <= 20000 && r.ok(); ++k) {
      st.do_step(sys, s, S(k - 1) * S(x), S(x));
      r = g.check(sys, s, k, S(k) * S(x));
      worst = std::max(worst, double(r.error));
    }
    char label[128];
    std::snprintf(label, sizeof label, "precision %s stiff sesi2 w*dt=%g", type_name<S>(), x);
    report(std::string(label) + ": guard measure (max or at the trip)", worst);
    report(std::string(label) + ": guard tripped at step (0: never)", r.ok() ? 0.0 : double(r.step));
    if (x < 2) {
      CHECK(r.ok());
    } else {
      CHECK(r.status == sesi::GuardStatus::energy_error_exceeded);
      CHECK(s.q.allFinite());
    }
  }
}

/// The default encounter floor is L eps^(1/3) of the precision, and closest_encounter sees it.
template <class S>
void floor() {
  using Chart = sesi::Sphere<2, S>;
  const S f = sesi::default_min_distance<S>(S(1));
  report(std::string("precision ") + type_name<S>() + " default encounter floor (R = 1)", double(f));
  CHECK(f == doctest::Approx(double(std::cbrt(stab::eps<S>()))).epsilon(1e-6));
  const auto sys = sesi::System(Chart(S(1)), std::vector<S>{S(1), S(1)}, sesi::CotangentGravity<S>{S(1)});
  sesi::State<Chart> x(2, 2);
  x.q << std::numbers::pi_v<S> / 2, std::numbers::pi_v<S> / 2, S(0), S(0.5) * f;
  CHECK(sesi::closest_encounter(sys, x).found());
  x.q(1, 1) = S(2) * f;
  CHECK(!sesi::closest_encounter(sys, x).found());
}

/// A long run of the seed's scene: energy error bounded (last tenth <= 2 x first tenth).
template <class S>
void bounded_energy() {
  namespace paper = sesi::scenes::paper;
  const auto sys = paper::make_system<S>();
  auto x = paper::initial_state<S>();
  sesi::Strang<paper::Chart<S>> st;
  const auto t = stab::energy_tenths(st, sys, x, S(0.1), 200000, 10);
  const std::string label = std::string("precision ") + type_name<S>() + " seed scene sesi2 2e5 steps";
  report(label + ": max |dE| first tenth", t.first);
  report(label + ": last/first", t.growth());
  // Bounded, up to round-off accumulated at most linearly: steps * eps * E0. In float this term
  // matters: the free angle phi grows without bound (~3e3 rad here), and its ulp with it.
  const double e0 = double(sys.energy(paper::initial_state<S>()));
  const double allowance = 200000.0 * double(stab::eps<S>()) * e0;
  report(label + ": round-off allowance steps eps E0", allowance);
  CHECK(t.last <= 2 * t.first + allowance);
}

}  // namespace

TEST_CASE_TEMPLATE("precision: pole grazing with re-charting", S, float, long double) { pole_grazing<S>(); }

TEST_CASE_TEMPLATE("precision: R = 1e-3 to round-off", S, float, long double) {
  scaled<S, sesi::Sphere<2, S>>("S^2");
  scaled<S, sesi::Hyperbolic<2, S>>("H^2");
}

TEST_CASE_TEMPLATE("precision: the energy guard at the stability limit", S, float, long double) { guard<S>(); }

TEST_CASE_TEMPLATE("precision: the encounter floor", S, float, long double) { floor<S>(); }

TEST_CASE_TEMPLATE("precision: bounded energy error on the seed's scene", S, float, long double) {
  bounded_energy<S>();
}
