#pragma once
/// @file chart.hpp
/// The minimum API of a hierarchical chart (docs/concepts.md lists it as a table).
///
/// A chart of an n-dimensional configuration space whose kinetic energy per body splits as
///   K(q, p) = sum_{i=1..n} K_i(q_1..q_{i-1}, p_i)
/// (seed paper, Discussion). The flow of one K_i alone keeps q_{<i} and p_i fixed, so it is
/// exact and explicit: q_i += h dK_i/dp_i, p_k -= h dK_i/dq_k for k < i.
/// Levels are numbered 0..n-1 in code (level i in code is K_{i+1} of the paper).

#include <cmath>
#include <concepts>
#include <Eigen/Core>

namespace sesi {

/// Compile-time dimension helpers (Eigen::Dynamic stays Dynamic).
constexpr int plus_one(int n) { return n == Eigen::Dynamic ? Eigen::Dynamic : n + 1; }

/// The minimum a chart must provide: the level terms and their derivatives, for a body of mass m.
template <class C>
concept HierarchicalChart =
    requires(const C& c, const typename C::Point& q, typename C::Scalar pi, typename C::Scalar m,
             int i, int k) {
      typename C::Scalar;
      typename C::Point;  // Eigen column vector of size C::dimension (chart coordinates or momenta)
      { C::dimension } -> std::convertible_to<int>;
      { c.dim() } -> std::convertible_to<int>;
      { c.kinetic(i, q, pi, m) } -> std::convertible_to<typename C::Scalar>;        // K_i
      { c.kinetic_dp(i, q, pi, m) } -> std::convertible_to<typename C::Scalar>;     // dK_i/dp_i
      { c.kinetic_dq(i, k, q, pi, m) } -> std::convertible_to<typename C::Scalar>;  // dK_i/dq_k, k<i
    };

/// A chart with an embedding in an ambient vector space, so that potentials written on ambient
/// points apply to it: x = embed(q), and the pull-back of an ambient gradient, J(q)^T g.
template <class C>
concept EmbeddedChart =
    HierarchicalChart<C> &&
    requires(const C& c, const typename C::Point& q, typename C::Point& out,
             const typename C::Ambient& g, typename C::Ambient& x) {
      typename C::Ambient;
      { C::ambient_dimension } -> std::convertible_to<int>;
      { c.ambient_dim() } -> std::convertible_to<int>;
      c.embed(q, x);         // x = embedding of q
      c.pullback(q, g, out); // out = J(q)^T g, J = dx/dq
    };

/// A chart that supplies its own exact level flow (built-in charts do: it shares the sines).
template <class C>
concept HasLevelFlow =
    requires(const C& c, typename C::Point& q, typename C::Point& p, typename C::Scalar m,
             typename C::Scalar h, int i) { c.level_flow(i, q, p, m, h); };

/// A chart that caches the sines and cosines of a body's coordinates (TrigType), so that the
/// level flows, the embedding and the pull-back of one stage share them (built-in S^n, H^n).
template <class C>
concept HasTrigCache =
    EmbeddedChart<C> &&
    requires(const C& c, typename C::Point& q, typename C::Point& p, typename C::TrigType& t,
             typename C::Ambient& x, typename C::Scalar m, int i) {
      c.refresh(q, t);                 // t = trig of q
      c.level_flow(i, q, p, m, m, t);  // exact flow of K_i, t kept in sync with q
      c.embed(t, x);
      c.pullback(t, x, p);
    };

/// A space with a geodesic distance and constant curvature (needed by pair terms on the distance).
template <class C>
concept MetricSpace = EmbeddedChart<C> && requires(const C& c, const typename C::Ambient& x,
                                                   typename C::Ambient& g) {
  { c.distance(x, x) } -> std::convertible_to<typename C::Scalar>;
  c.distance_gradient(x, x, g);  // g = Euclidean d(distance)/dx at the first argument (tangent on S^n, eta g tangent on H^n)
  { c.curvature() } -> std::convertible_to<typename C::Scalar>;
};

/// What a space of constant curvature kappa knows of a pair of points x, y with one square root
/// and no transcendental function (Sphere, Hyperbolic, Euclidean::pair_geometry): the pair
/// kernels of System need nothing more (cotangent gravity is ctn(d) = cs / sn), and the gradient
/// of the distance at x is G (x - y - one_minus_cs x) / sn (G: the ambient metric, eta on H^n).
template <class Scalar>
struct PairGeometry {
  Scalar chord2 = 0;        ///< c^2 = <x - y, x - y> in the ambient metric; c = 2R sin(d/2R), 2R sinh(d/2R), d
  Scalar cochord2 = 0;      ///< |x + y|^2 on S^n (2R cos(d/2R) squared), 4R^2 + c^2 on H^n, unused on E^n
  Scalar sn = 0;            ///< R sin(d/R), R sinh(d/R), d
  Scalar one_minus_cs = 0;  ///< 1 - cos(d/R) = c^2/2R^2, 1 - cosh(d/R) = -c^2/2R^2, 0
  Scalar cs() const { return Scalar(1) - one_minus_cs; }
  Scalar chord() const {
    using std::sqrt;
    return sqrt(chord2);
  }
};

/// Spaces with pair_geometry and its distance (the algebraic pair kernels of System).
template <class C>
concept HasPairGeometry = EmbeddedChart<C> && requires(const C& c, const typename C::Ambient& x,
                                                       const PairGeometry<typename C::Scalar>& g) {
  { c.pair_geometry(x, x) } -> std::same_as<PairGeometry<typename C::Scalar>>;
  { c.distance_of(g) } -> std::convertible_to<typename C::Scalar>;
  { c.chord_of_distance(g.sn) } -> std::convertible_to<typename C::Scalar>;
};

namespace detail {
/// Ambient dimension of a chart type (its own dimension for charts without an embedding).
template <class Chart>
constexpr int ambient_dimension_of() {
  if constexpr (requires { Chart::ambient_dimension; }) {
    return Chart::ambient_dimension;
  } else {
    return Chart::dimension;
  }
}
}  // namespace detail

/// The exact flow of K_i for time h on one body, from the concept's minimum API alone:
/// q_i += h dK_i/dp_i, and p_k -= h dK_i/dq_k for k < i (all evaluated at the start, which is
/// exact because q_{<i} and p_i do not move under this flow).
template <HierarchicalChart C>
void level_flow(const C& chart, int i, typename C::Point& q, typename C::Point& p,
                typename C::Scalar m, typename C::Scalar h) {
  if constexpr (HasLevelFlow<C>) {
    chart.level_flow(i, q, p, m, h);
  } else {
    const auto pi = p[i];
    for (int k = 0; k < i; ++k) p[k] -= h * chart.kinetic_dq(i, k, q, pi, m);
    q[i] += h * chart.kinetic_dp(i, q, pi, m);
  }
}

/// Kinetic energy of one body, sum of the level terms.
template <HierarchicalChart C>
typename C::Scalar kinetic_energy(const C& chart, const typename C::Point& q,
                                  const typename C::Point& p, typename C::Scalar m) {
  typename C::Scalar k(0);
  for (int i = 0; i < chart.dim(); ++i) k += chart.kinetic(i, q, p[i], m);
  return k;
}

/// What sesi::rechart does with a body (recharting.hpp, docs/charts.md): nothing, a turn (the
/// half-turn about the body: same q, p -> -p, a frame that reverses the body's tangent space),
/// or a homing (a new frame where the chart is best conditioned).
enum class RechartAction { none, turn, home };

}  // namespace sesi
