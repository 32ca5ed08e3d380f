// High curvature, the flat limit and high dimension (issue #5).
//
//  - R = 1e-3: the unit-radius scene scaled (lengths by R, times by R^(3/2), so that a
//    cotangent-gravity scene has the same dynamics in the angles; momenta by R^(1/2)). In exact
//    arithmetic the chart coordinates of the two runs coincide step by step; the test asks for
//    agreement to round-off: |dq| <= steps * eps * |q|.
//  - R = 1e6: a cotangent-gravity pair near the chart's pole of S^2 (near the chart origin of
//    H^2), mapped to the plane by the exponential map, against the same pair on E^2 (1/d
//    gravity) with the same method and step: the curvature terms are O((L/R)^2) for a scene of
//    size L, so the difference must scale as 1/R^2. The method is Kahan-Li 8: the curved and
//    flat runs split the kinetic energy differently (polar levels vs one Cartesian flow), so
//    their difference has an R-independent O(dt^p) part (3e-9 with SESI 4 at dt = 0.01), which
//    order 8 makes negligible. Its coefficient is measured at R = 1e3
//    (where it is 1e6 times round-off); at R = 1e2 the difference must be 100 times larger
//    (within a factor 2) and at R = 1e6 at most twice the 1/R^2 prediction plus the round-off of
//    the run: ambient coordinates of size R resolve eps R, so steps * eps * R / L. In double
//    that allowance (3.7e-8) hides the 1/R^2 term (7e-12); in long double (1.8e-11) it does not.
//  - n = 16 and 32: free motion on S^n and H^n against the exact geodesic, and a harmonic
//    pair, with re-charting: the observed order (from dt and dt/2, or three
//    step sizes without an exact solution) is the method's within 0.3.
#include <doctest/doctest.h>

#include <cmath>
#include <numbers>

#include "common.hpp"

namespace {

using S = double;
using stab::Mat;
using stab::report;
using stab::Vec;

// ---- high curvature: R = 1e-3 as the unit scene scaled --------------------------------------

template <class Chart>
double scaled_difference(const char* name, S radius) {
  const long steps = 400;
  const S dt1 = 0.005;
  auto build = [&](S r) {
    return sesi::System(Chart(r), std::vector<S>{1.0, 0.4}, sesi::CotangentGravity<S>{1.0});
  };
  const auto sys1 = build(1), sysr = build(radius);
  // A bound pair orbiting its centre of mass (about one period), chart coordinates.
  sesi::State<Chart> x1(2, 2);
  x1.q << 1.2, 1.2, 0.3, 0.8;
  x1.p << 0.49, -0.49, 0.02, 0.05;
  auto xr = x1;
  xr.p *= std::sqrt(radius);
  sesi::Yoshida4<Chart> a, b;
  stab::run(a, sys1, x1, dt1, steps);
  stab::run(b, sysr, xr, dt1 * radius * std::sqrt(radius), steps);
  const double diff = (x1.q - xr.q).cwiseAbs().maxCoeff() / x1.q.cwiseAbs().maxCoeff();
  const double e1 = double(sys1.energy(x1)), er = double(sysr.energy(xr)) * double(radius);
  report(std::string("extreme ") + name + " R=1e-3 scaled scene: max |dq| / |q| after 400 steps", diff);
  report(std::string("extreme ") + name + " R=1e-3 scaled scene: |E R - E_1| / |E_1|", std::abs(er - e1) / std::abs(e1));
  CHECK(diff <= double(steps) * stab::eps<S>());
  return diff;
}

TEST_CASE("high curvature: R = 1e-3 reproduces the unit scene, scaled, to round-off") {
  scaled_difference<sesi::Sphere<2, S>>("S^2", 1e-3);
  scaled_difference<sesi::Hyperbolic<2, S>>("H^2", 1e-3);
}

// ---- the flat limit: R = 1e6 against E^2 ----------------------------------------------------

/// The pair in the plane: positions and velocities (columns), masses 1 and 0.5, G = 1.
template <class T>
void planar_scene(Mat<T>& X, Mat<T>& V) {
  X.resize(2, 2);
  V.resize(2, 2);
  // Centre of mass at (3, 0) moving along (0.3, 0.2); separation 1, near-circular relative motion.
  const T sep = 1, vrel = std::sqrt(T(1.5) / sep) * T(0.9);
  X << 3 - sep / 3, 3 + 2 * sep / 3, 0, 0;
  V << T(0.3), T(0.3), T(0.2) - vrel / 3, T(0.2) + 2 * vrel / 3;
}

/// Exponential map at the chart's pole (S^2: e_3; H^2: the origin) and its inverse, for radius R.
template <bool Sphere, class T>
Vec<T> lift(const Vec<T>& a, T R) {
  const T r = a.norm();
  Vec<T> x(3);
  if (Sphere) {
    x << R * std::sin(r / R) * a / r, R * std::cos(r / R);
  } else {
    x << R * std::sinh(r / R) * a / r, R * std::cosh(r / R);
  }
  return x;
}
template <bool Sphere, class T>
Vec<T> drop(const Vec<T>& x, T R) {
  const Vec<T> h = x.head(2);
  const T n = h.norm();
  const T r = Sphere ? R * std::atan2(n, x[2]) : R * std::asinh(n / R);
  return Vec<T>(r * h / n);
}

/// Relative difference (to the scene's size 3) of the curved run from the planar reference.
template <bool Sphere, class Chart>
double flat_difference(typename Chart::Scalar R, const Mat<typename Chart::Scalar>& reference, long steps,
                       typename Chart::Scalar dt) {
  using T = typename Chart::Scalar;
  const auto sys = sesi::System(Chart(R), std::vector<T>{1, T(0.5)}, sesi::CotangentGravity<T>{1});
  Mat<T> P, W;
  planar_scene(P, W);
  Mat<T> X(3, 2), V(3, 2);
  for (int b = 0; b < 2; ++b) {
    const Vec<T> p = P.col(b), w = W.col(b);
    const T r = p.norm();
    const Vec<T> u = p / r;
    // The differential of the exponential map at p applied to w (radial and angular parts).
    const T wr = u.dot(w);
    const Vec<T> wt = w - wr * u;
    X.col(b) = lift<Sphere>(p, R);
    Vec<T> v(3);
    if (Sphere) {
      v << (std::cos(r / R) * wr) * u + (R * std::sin(r / R) / r) * wt, -std::sin(r / R) * wr;
    } else {
      v << (std::cosh(r / R) * wr) * u + (R * std::sinh(r / R) / r) * wt, std::sinh(r / R) * wr;
    }
    V.col(b) = v;
  }
  auto x = stab::from_world(sys, X, V);
  sesi::KahanLi8<Chart> st;
  stab::run(st, sys, x, dt, steps);
  const Mat<T> out = sesi::embedding_points(sys, x);
  double diff = 0;
  for (int b = 0; b < 2; ++b) {
    diff = std::max(diff, double((drop<Sphere>(Vec<T>(out.col(b)), R) - reference.col(b)).norm()));
  }
  return diff / 3.0;
}

template <bool Sphere, template <int, class> class Space, class T>
void flat_limit(const char* name) {
  using Chart = Space<2, T>;
  const long steps = 500;
  const T dt = T(0.01);
  Mat<T> P, W;
  planar_scene(P, W);
  const auto flat = sesi::System(sesi::Euclidean<2, T>(), std::vector<T>{1, T(0.5)}, sesi::CotangentGravity<T>{1});
  auto xe = stab::from_world(flat, P, W);
  sesi::KahanLi8<sesi::Euclidean<2, T>> st;
  stab::run(st, flat, xe, dt, steps);
  const Mat<T> ref = xe.q;
  const double d2 = flat_difference<Sphere, Chart>(T(1e2), ref, steps, dt);
  const double d3 = flat_difference<Sphere, Chart>(T(1e3), ref, steps, dt);
  const double d6 = flat_difference<Sphere, Chart>(T(1e6), ref, steps, dt);
  const double c = d3 * 1e6;  // the coefficient of 1/R^2, measured where round-off is negligible
  // Ambient coordinates of size R resolve eps R: each step can move the result by that much
  // (relative to the scene's size 3), at most linearly over the run.
  const double roundoff = double(steps) * double(stab::eps<T>()) * 1e6 / 3;
  const std::string label = std::string("extreme flat limit ") + name + " vs E^2 (" +
                            (std::is_same_v<T, double> ? "double" : "long double") + "), relative difference";
  report(label + " R=1e2", d2);
  report(label + " R=1e3", d3);
  report(label + " R=1e6", d6);
  report(label + " R=1e6: 1/R^2 prediction c/R^2", c * 1e-12);
  report(label + " R=1e6: round-off allowance steps eps R / L", roundoff);
  report(label + " ratio R=1e2 / R=1e3 (1/R^2: 100)", d2 / d3);
  CHECK(d2 / d3 >= 50);
  CHECK(d2 / d3 <= 200);
  CHECK(d6 <= 2 * c * 1e-12 + roundoff);
}

TEST_CASE("flat limit: R = 1e6 matches the Euclidean chart to O(1/R^2) (+ eps R round-off)") {
  flat_limit<true, sesi::Sphere, S>("S^2");
  flat_limit<false, sesi::Hyperbolic, S>("H^2");
  // In long double the round-off allowance (1.8e-11) is of the order of c/R^2 (7e-12): the
  // 1/R^2 law itself is checked at R = 1e6.
  flat_limit<true, sesi::Sphere, long double>("S^2");
  flat_limit<false, sesi::Hyperbolic, long double>("H^2");
}

// ---- high dimension -------------------------------------------------------------------------

/// A deterministic generic unit vector of R^a, and one orthogonal to it.
void generic_frame(int a, Vec<S>& u, Vec<S>& w) {
  u.resize(a);
  w.resize(a);
  for (int i = 0; i < a; ++i) {
    u[i] = std::sin(1.3 * i + 0.4) + 0.3;
    w[i] = std::cos(0.7 * i * i + 1.1);
  }
  u.normalize();
  w -= w.dot(u) * u;
  w.normalize();
}

/// A point of S^n or H^n (R = 1) at distance `dist` from the world origin of the chart, in a
/// generic direction, and a unit tangent velocity at it (generic too).
template <bool Sphere>
void generic_point(int n, S dist, S twist, Vec<S>& x, Vec<S>& v) {
  Vec<S> u, w;
  generic_frame(n, u, w);
  x.resize(n + 1);
  v.resize(n + 1);
  const S c = Sphere ? std::cos(dist) : std::cosh(dist), s = Sphere ? std::sin(dist) : std::sinh(dist);
  // Move along the geodesic from the pole e_{n+1} in direction u, then v = a unit mix of the
  // radial direction and w (tangent to the sphere of directions).
  x << s * u, c;
  Vec<S> radial(n + 1);
  radial << (Sphere ? c : c) * u, (Sphere ? -s : s);
  Vec<S> side(n + 1);
  side << w, 0;
  v = std::cos(twist) * radial + std::sin(twist) * side;
}

template <bool Sphere>
S world_distance(const Vec<S>& x, const Vec<S>& y) {
  if (Sphere) return 2 * std::atan2((x - y).norm(), (x + y).norm());
  const Vec<S> d = x - y;
  const S l = d.head(d.size() - 1).squaredNorm() - d[d.size() - 1] * d[d.size() - 1];
  return 2 * std::asinh(std::sqrt(std::max(l, S(0))) / 2);
}

/// Free motion: final distance to the exact geodesic after time T.
template <bool Sphere, template <class> class Method, class Chart>
double free_error(int n, S dt, S T) {
  const auto sys = sesi::System(Chart(1.0, n), std::vector<S>{1.0});
  Vec<S> x0, v0;
  generic_point<Sphere>(n, 0.9, 0.6, x0, v0);
  auto x = stab::from_world(sys, Mat<S>(x0), Mat<S>(v0));
  stab::Rech<Method, Chart> st;
  sesi::rechart(sys, x, st.policy());
  const long steps = std::lround(T / dt);
  stab::run(st, sys, x, dt, steps);
  const Vec<S> exact = Sphere ? Vec<S>(std::cos(T) * x0 + std::sin(T) * v0) : Vec<S>(std::cosh(T) * x0 + std::sinh(T) * v0);
  return world_distance<Sphere>(Vec<S>(sesi::embedding_points(sys, x).col(0)), exact);
}

/// A harmonic pair (rest length 0.5): world points after time T.
template <bool Sphere, template <class> class Method, class Chart>
Mat<S> pair_points(int n, S dt, S T) {
  const auto sys = sesi::System(Chart(1.0, n), std::vector<S>{1.0, 0.6}, sesi::HarmonicPair<S>{1.0, 0.5});
  Vec<S> x0, v0, x1, v1;
  generic_point<Sphere>(n, 0.9, 0.6, x0, v0);
  generic_point<Sphere>(n, 1.4, 2.0, x1, v1);
  Mat<S> X(n + 1, 2), V(n + 1, 2);
  X << x0, x1;
  V << 0.3 * v0, 0.5 * v1;
  auto x = stab::from_world(sys, X, V);
  stab::Rech<Method, Chart> st;
  sesi::rechart(sys, x, st.policy());
  stab::run(st, sys, x, dt, std::lround(T / dt));
  return sesi::embedding_points(sys, x);
}

template <bool Sphere, template <class> class Method, class Chart>
void high_dimension(const char* method, int order, S dt) {
  const char* space = Sphere ? "S" : "H";
  for (int n : {16, 32}) {
    const S T = 2;
    const double e1 = free_error<Sphere, Method, Chart>(n, dt, T);
    const double e2 = free_error<Sphere, Method, Chart>(n, dt / 2, T);
    char label[128];
    std::snprintf(label, sizeof label, "extreme %s^%d %s dt=%g", space, n, method, double(dt));
    report(std::string(label) + " free motion error", e1);
    report(std::string(label) + " free motion observed order", std::log2(e1 / e2));
    CHECK(std::abs(std::log2(e1 / e2) - order) < 0.3);
    const Mat<S> a = pair_points<Sphere, Method, Chart>(n, dt, T);
    const Mat<S> b = pair_points<Sphere, Method, Chart>(n, dt / 2, T);
    const Mat<S> c = pair_points<Sphere, Method, Chart>(n, dt / 4, T);
    double d1 = 0, d2 = 0;
    for (int k = 0; k < 2; ++k) {
      d1 = std::max(d1, double(world_distance<Sphere>(Vec<S>(a.col(k)), Vec<S>(b.col(k)))));
      d2 = std::max(d2, double(world_distance<Sphere>(Vec<S>(b.col(k)), Vec<S>(c.col(k)))));
    }
    report(std::string(label) + " harmonic pair |x(dt) - x(dt/2)|", d1);
    report(std::string(label) + " harmonic pair observed order", std::log2(d1 / d2));
    CHECK(std::abs(std::log2(d1 / d2) - order) < 0.3);
  }
}

}  // namespace

TEST_CASE("high dimension: S^16, S^32, H^16, H^32 to the method's order") {
  using SX = sesi::Sphere<Eigen::Dynamic, S>;
  using HX = sesi::Hyperbolic<Eigen::Dynamic, S>;
  high_dimension<true, sesi::Strang, SX>("sesi2", 2, 0.02);
  // sesi4 at dt = 0.025, in its asymptotic range (issue #24: order checks where the method is):
  // S^16's free motion measures 4.56 at dt = 0.1, 4.25 at 0.05 and 4.00 at 0.025, since the
  // re-chartings of the deep levels (polar-sine product below 1/4) fall on other steps at dt and
  // dt/2; at 0.025 every case here measures 3.99-4.04.
  high_dimension<true, sesi::Yoshida4, SX>("sesi4", 4, 0.025);
  high_dimension<false, sesi::Strang, HX>("sesi2", 2, 0.02);
  high_dimension<false, sesi::Yoshida4, HX>("sesi4", 4, 0.025);
}
