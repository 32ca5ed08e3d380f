// Threshold and frame logic per dimension (issue #5): S^n and H^n for n = 2..6.
//
// For every danger zone of the chart (each polar angle near a pole; on H^n also the radius near
// the origin and beyond max_radius) a body is placed in the zone and rechart() is asked what to
// do: approaching the zone it is turned (q kept, p negated, frame F T), receding it is left
// alone, deep in the zone or between two zones it is homed (every polar sine 1, radius
// home_radius on H^n). Every re-charting must keep the world state (point and velocity) to
// round-off and the frames isometries (F^T F = I, F^T eta F = eta). Then free motion through the
// singular set of each zone, with re-charting, against the exact geodesic: within 10x of the
// same orbit tilted away from the zone (the pole-grazing bound of poles.cpp, for every n).
#include <doctest/doctest.h>

#include <cstdio>
#include <string>

#include "common.hpp"

namespace {

using S = double;
using stab::Mat;
using stab::report;
using stab::Vec;

template <class Chart>
constexpr bool hyperbolic = std::is_same_v<Chart, sesi::Hyperbolic<Chart::dimension, S>>;

/// A generic point of the chart's domain with coordinate k set to value.
template <class Chart>
typename Chart::Point generic_point(int k, S value) {
  typename Chart::Point q(Chart::dimension);
  for (int i = 0; i < Chart::dimension; ++i) q[i] = 1.1 + 0.07 * i;
  if (hyperbolic<Chart>) q[0] = 1.3;
  q[k] = value;
  return q;
}
/// Generic momenta with p_k of the given sign.
template <class Chart>
typename Chart::Point generic_momenta(int k, S sign) {
  typename Chart::Point p(Chart::dimension);
  for (int i = 0; i < Chart::dimension; ++i) p[i] = 0.3 - 0.11 * i;
  p[k] = sign * 0.8;
  return p;
}

/// World point and velocity of body 0.
template <class Sys>
std::pair<Vec<S>, Vec<S>> world(const Sys& sys, const sesi::State<typename Sys::Chart>& x) {
  return {Vec<S>(sesi::embedding_points(sys, x).col(0)),
          Vec<S>(sesi::embedding_velocities(sys, x).col(0))};
}

/// Isometry defect of a frame: |F^T G F - G| / |F|^2 (G = I or eta).
template <class Chart>
S isometry_defect(const Mat<S>& f) {
  const int a = static_cast<int>(f.rows());
  Mat<S> g = Mat<S>::Identity(a, a);
  if (hyperbolic<Chart>) g(a - 1, a - 1) = -1;
  const S scale = f.cwiseAbs().maxCoeff();
  return (f.transpose() * g * f - g).cwiseAbs().maxCoeff() / (scale * scale);
}

/// Re-chart a body at (q, p), expect `want`, and check what every re-charting must keep.
template <class Chart>
void expect_action(const char* zone, const typename Chart::Point& q, const typename Chart::Point& p,
                   sesi::RechartAction want) {
  const auto sys = sesi::System(Chart(1.0), std::vector<S>{1.0});
  sesi::State<Chart> x(Chart::dimension, 1);
  x.q.col(0) = q;
  x.p.col(0) = p;
  const sesi::RechartPolicy<S> policy;
  CAPTURE(Chart::dimension);
  CAPTURE(std::string(Chart::name));
  CAPTURE(std::string(zone));
  CHECK(sys.chart().rechart_action(q, p, policy) == want);
  const auto [x0, v0] = world(sys, x);
  const sesi::Recharted done = sesi::rechart(sys, x, policy);
  const auto [x1, v1] = world(sys, x);
  const S scale = std::max(S(1), x0.cwiseAbs().maxCoeff());
  // World state kept: a turn is exact but for the rank-one update of F; a homing recomputes q, p
  // from the point (a few dozen operations on entries up to `scale`).
  CHECK((x1 - x0).cwiseAbs().maxCoeff() <= 64 * stab::eps<S>() * scale * scale);
  CHECK((v1 - v0).cwiseAbs().maxCoeff() <= 64 * stab::eps<S>() * scale * scale);
  CHECK(isometry_defect<Chart>(x.frames[0]) <= 16 * stab::eps<S>());
  if (want == sesi::RechartAction::turn) {
    CHECK(done.turned == 1);
    CHECK(x.q.col(0) == q);
    CHECK(x.p.col(0) == -p);
    // The turned body recedes: nothing more to do.
    CHECK(sys.chart().rechart_action(typename Chart::Point(x.q.col(0)),
                                     typename Chart::Point(x.p.col(0)), policy) ==
          sesi::RechartAction::none);
  } else if (want == sesi::RechartAction::home) {
    CHECK(done.homed == 1);
    const int first_angle = hyperbolic<Chart> ? 1 : 0;
    for (int k = first_angle; k + 1 < Chart::dimension; ++k) {
      CHECK(std::abs(std::sin(x.q(k, 0)) - 1) <= 16 * stab::eps<S>() * scale * scale);
    }
    if (hyperbolic<Chart>) CHECK(std::abs(x.q(0, 0) - policy.home_radius) <= 1e-12 * scale);
  } else {
    CHECK(done.total() == 0);
  }
}

template <class Chart>
void zones() {
  using A = sesi::RechartAction;
  const int n = Chart::dimension;
  const int first_angle = hyperbolic<Chart> ? 1 : 0;
  // Polar angles (k < n-1): sin 0.3 = 0.30 is in the zone (1/2), sin 0.1 deep (below 1/4); near
  // pi the approach is p_k > 0.
  for (int k = first_angle; k + 1 < n; ++k) {
    expect_action<Chart>("angle approaching", generic_point<Chart>(k, 0.3), generic_momenta<Chart>(k, -1), A::turn);
    expect_action<Chart>("angle approaching pi", generic_point<Chart>(k, 2.85), generic_momenta<Chart>(k, 1), A::turn);
    expect_action<Chart>("angle receding", generic_point<Chart>(k, 0.3), generic_momenta<Chart>(k, 1), A::none);
    expect_action<Chart>("angle deep", generic_point<Chart>(k, 0.1), generic_momenta<Chart>(k, 1), A::home);
    if (k + 2 < n) {  // two zones, approaching one and receding from the other: a turn cannot help
      auto q = generic_point<Chart>(k, 0.3);
      q[k + 1] = 0.3;
      auto p = generic_momenta<Chart>(k, -1);
      p[k + 1] = 0.5;
      expect_action<Chart>("two angles", q, p, A::home);
    }
  }
  expect_action<Chart>("safe", generic_point<Chart>(0, hyperbolic<Chart> ? 1.3 : 1.1), generic_momenta<Chart>(0, 1), A::none);
  if constexpr (hyperbolic<Chart>) {
    expect_action<Chart>("origin approaching", generic_point<Chart>(0, 0.2), generic_momenta<Chart>(0, -1), A::turn);
    expect_action<Chart>("origin deep", generic_point<Chart>(0, 0.1), generic_momenta<Chart>(0, 1), A::home);
    // Beyond max_radius moving out: radially (closest approach small) a turn, tangentially
    // (closest approach above max_radius / 2) a homing; one beyond it, deep.
    auto radial = generic_momenta<Chart>(0, 1);
    radial *= 0.01;
    radial[0] = 1;
    expect_action<Chart>("far, radial", generic_point<Chart>(0, 3.5), radial, A::turn);
    auto tangential = generic_momenta<Chart>(0, 1);
    tangential[0] = 0.01;
    tangential[n - 1] = 30;
    expect_action<Chart>("far, tangential", generic_point<Chart>(0, 3.5), tangential, A::home);
    expect_action<Chart>("far, inward", generic_point<Chart>(0, 3.5), generic_momenta<Chart>(0, -1), A::none);
    expect_action<Chart>("far, deep", generic_point<Chart>(0, 4.5), generic_momenta<Chart>(0, -1), A::home);
  }
}

/// Free motion at unit speed through the singular set of zone k (chart point q with q_k =
/// `graze`, moving along dq_k) for time 3 centred there, moved by the isometry `iso`, with
/// re-charting, against the exact geodesic x(t) = c(t) x0 + s(t) v0 (cos, sin on S^n; cosh, sinh
/// on H^n). Returns the error.
template <class Chart>
S through(int k, S graze, S dt, const Mat<S>& iso) {
  const auto sys = sesi::System(Chart(1.0), std::vector<S>{1.0});
  const auto& chart = sys.chart();
  const auto q = generic_point<Chart>(k, graze);
  typename Chart::Point p = Chart::Point::Zero(Chart::dimension);
  p[k] = 1;
  typename Chart::Ambient x0(chart.ambient_dim()), v0(chart.ambient_dim());
  chart.embed(q, x0);
  chart.velocity(q, p, S(1), v0);
  v0 /= std::sqrt(chart.inner(v0, v0));
  x0 = (iso * x0).eval();
  v0 = (iso * v0).eval();
  const auto at = [&](S t) {
    const S c = hyperbolic<Chart> ? std::cosh(t) : std::cos(t);
    const S s = hyperbolic<Chart> ? std::sinh(t) : std::sin(t);
    return std::pair<Vec<S>, Vec<S>>{Vec<S>(c * x0 + s * v0),
                                     Vec<S>((hyperbolic<Chart> ? s : -s) * x0 + c * v0)};
  };
  const auto [xs, vs] = at(-1.5);
  auto x = stab::from_world(sys, Mat<S>(xs), Mat<S>(vs));
  stab::Rech<sesi::Strang, Chart> st;
  sesi::rechart(sys, x, st.policy());
  const long steps = std::lround(3.0 / dt);
  stab::run(st, sys, x, dt, steps);
  return stab::max_distance(chart, sesi::embedding_points(sys, x), Mat<S>(at(S(steps) * dt - 1.5).first));
}

/// A fixed generic isometry: rotations in several planes (and on H^n a moderate boost), which
/// moves a geodesic through a singular set to a generic one, as the 45-degree tilt of poles.cpp.
template <class Chart>
Mat<S> generic_isometry() {
  const int a = Chart::dimension + 1;
  const int spatial = hyperbolic<Chart> ? a - 1 : a;
  Mat<S> g = Mat<S>::Identity(a, a);
  for (int i = 0; i + 1 < spatial; ++i) g = g * stab::givens<S>(a, i, i + 1, S(0.7) - S(0.1) * i);
  if (hyperbolic<Chart>) g = stab::boost<S>(a, 0, S(0.3)) * g;
  return g;
}

template <class Chart>
void crossings() {
  const int n = Chart::dimension;
  const S dt = 0.01;
  const Mat<S> identity = Mat<S>::Identity(n + 1, n + 1);
  // Zone k: the polar angle k (k = 0 on H^n: through the polar origin, moving along the radius).
  for (int k = 0; k + 1 < n; ++k) {
    for (const S graze : {S(1e-3), S(1e-9)}) {
      const S tilted = through<Chart>(k, graze, dt, generic_isometry<Chart>());
      const S e = through<Chart>(k, graze, dt, identity);
      char label[96];
      std::snprintf(label, sizeof label, "frames %s n=%d zone %d graze %g: error / generic orbit's",
                    Chart::name, n, k, double(graze));
      report(label, e / tilted);
      CAPTURE(n);
      CAPTURE(k);
      CHECK(std::isfinite(e));
      CHECK(e <= 10 * tilted);
    }
  }
}

}  // namespace

TEST_CASE_TEMPLATE("frames: every danger zone of S^n and H^n, n = 2..6: the action and what it keeps", Chart,
                   sesi::Sphere<2, S>, sesi::Sphere<3, S>, sesi::Sphere<4, S>, sesi::Sphere<5, S>,
                   sesi::Sphere<6, S>, sesi::Hyperbolic<2, S>, sesi::Hyperbolic<3, S>,
                   sesi::Hyperbolic<4, S>, sesi::Hyperbolic<5, S>, sesi::Hyperbolic<6, S>) {
  zones<Chart>();
}

TEST_CASE_TEMPLATE("frames: free motion through every singular set of S^n and H^n, n = 2..6", Chart,
                   sesi::Sphere<2, S>, sesi::Sphere<3, S>, sesi::Sphere<4, S>, sesi::Sphere<5, S>,
                   sesi::Sphere<6, S>, sesi::Hyperbolic<2, S>, sesi::Hyperbolic<3, S>,
                   sesi::Hyperbolic<4, S>, sesi::Hyperbolic<5, S>, sesi::Hyperbolic<6, S>) {
  crossings<Chart>();
}
