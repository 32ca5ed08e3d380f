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
/// Its dimension is declared once: `C::dimension`, and `c.dim()` only when that is Eigen::Dynamic
/// (sesi::dim_of reads either).
template <class C>
concept HierarchicalChart =
    requires(const C& c, const typename C::Point& q, typename C::Scalar pi, typename C::Scalar m,
             int i, int k) {
      typename C::Scalar;
      typename C::Point;  // Eigen column vector of size C::dimension (chart coordinates or momenta)
      { C::dimension } -> std::convertible_to<int>;
      { c.kinetic(i, q, pi, m) } -> std::convertible_to<typename C::Scalar>;        // K_i
      { c.kinetic_dp(i, q, pi, m) } -> std::convertible_to<typename C::Scalar>;     // dK_i/dp_i
      { c.kinetic_dq(i, k, q, pi, m) } -> std::convertible_to<typename C::Scalar>;  // dK_i/dq_k, k<i
    } &&
    (C::dimension != Eigen::Dynamic || requires(const C& c) { { c.dim() } -> std::convertible_to<int>; });

/// A chart with an embedding in an ambient vector space, so that potentials written on ambient
/// points apply to it: x = embed(q), and the pull-back of an ambient gradient, J(q)^T g. The
/// ambient dimension is declared once as the dimension is (`c.ambient_dim()` only when dynamic).
template <class C>
concept EmbeddedChart =
    HierarchicalChart<C> &&
    requires(const C& c, const typename C::Point& q, typename C::Point& out,
             const typename C::Ambient& g, typename C::Ambient& x) {
      typename C::Ambient;
      { C::ambient_dimension } -> std::convertible_to<int>;
      c.embed(q, x);         // x = embedding of q
      c.pullback(q, g, out); // out = J(q)^T g, J = dx/dq
    } &&
    (C::ambient_dimension != Eigen::Dynamic ||
     requires(const C& c) { { c.ambient_dim() } -> std::convertible_to<int>; });

/// A chart's dimension: C::dimension when fixed, else c.dim().
template <class C>
int dim_of(const C& c) {
  if constexpr (C::dimension != Eigen::Dynamic) {
    static_cast<void>(c);
    return C::dimension;
  } else {
    return c.dim();
  }
}
/// A chart's ambient dimension: C::ambient_dimension when fixed, else c.ambient_dim() (charts
/// without an embedding: their dimension).
template <class C>
int ambient_dim_of(const C& c) {
  if constexpr (!requires { C::ambient_dimension; }) {
    return dim_of(c);
  } else if constexpr (C::ambient_dimension != Eigen::Dynamic) {
    static_cast<void>(c);
    return C::ambient_dimension;
  } else {
    return c.ambient_dim();
  }
}

namespace detail {
/// The requirements of HierarchicalChart and EmbeddedChart one by one, each with its own
/// message: sesi::System instantiates these, so that a chart missing a member is told which
/// (a concept's failure names only the concept). docs/concepts.md shows the first lines.
template <class C>
constexpr bool report_hierarchical_chart() {
  static_assert(requires { typename C::Scalar; },
                "sesi: the chart needs `using Scalar = ...;` (its floating-point type)");
  static_assert(requires { typename C::Point; },
                "sesi: the chart needs `using Point = ...;` (an Eigen column vector of its dimension)");
  static_assert(requires { { C::dimension } -> std::convertible_to<int>; },
                "sesi: the chart needs `static constexpr int dimension` (Eigen::Dynamic when set at run time)");
  if constexpr (requires { { C::dimension } -> std::convertible_to<int>; }) {
    if constexpr (C::dimension == Eigen::Dynamic) {
      static_assert(requires(const C& c) { { c.dim() } -> std::convertible_to<int>; },
                    "sesi: a chart of dimension Eigen::Dynamic needs `int dim() const`");
    }
  }
  if constexpr (requires { typename C::Scalar; typename C::Point; }) {
    using S = typename C::Scalar;
    using P = typename C::Point;
    static_assert(requires(const C& c, const P& q, S pi, S m, int i) {
                    { c.kinetic(i, q, pi, m) } -> std::convertible_to<S>;
                  },
                  "sesi: the chart needs `Scalar kinetic(int i, const Point& q, Scalar p_i, Scalar m) const` (K_i)");
    static_assert(requires(const C& c, const P& q, S pi, S m, int i) {
                    { c.kinetic_dp(i, q, pi, m) } -> std::convertible_to<S>;
                  },
                  "sesi: the chart needs `Scalar kinetic_dp(int i, const Point& q, Scalar p_i, Scalar m) const` "
                  "(dK_i/dp_i)");
    static_assert(requires(const C& c, const P& q, S pi, S m, int i, int k) {
                    { c.kinetic_dq(i, k, q, pi, m) } -> std::convertible_to<S>;
                  },
                  "sesi: the chart needs `Scalar kinetic_dq(int i, int k, const Point& q, Scalar p_i, Scalar m) "
                  "const` (dK_i/dq_k for k < i)");
  }
  return true;
}
template <class C>
constexpr bool report_embedded_chart() {
  static_assert(requires { typename C::Ambient; },
                "sesi: potential terms act on embedding points; the chart needs `using Ambient = ...;` (an Eigen "
                "column vector of the ambient dimension)");
  static_assert(requires { { C::ambient_dimension } -> std::convertible_to<int>; },
                "sesi: potential terms act on embedding points; the chart needs `static constexpr int "
                "ambient_dimension`");
  if constexpr (requires { { C::ambient_dimension } -> std::convertible_to<int>; }) {
    if constexpr (C::ambient_dimension == Eigen::Dynamic) {
      static_assert(requires(const C& c) { { c.ambient_dim() } -> std::convertible_to<int>; },
                    "sesi: potential terms act on embedding points; a chart of ambient dimension "
                    "Eigen::Dynamic needs `int ambient_dim() const`");
    }
  }
  if constexpr (requires { typename C::Point; typename C::Ambient; }) {
    static_assert(requires(const C& c, const typename C::Point& q, typename C::Ambient& x) { c.embed(q, x); },
                  "sesi: potential terms act on embedding points; the chart needs `void embed(const Point& q, "
                  "Ambient& x) const`");
    static_assert(requires(const C& c, const typename C::Point& q, const typename C::Ambient& g,
                           typename C::Point& out) { c.pullback(q, g, out); },
                  "sesi: potential terms act on embedding points; the chart needs `void pullback(const Point& q, "
                  "const Ambient& g, Point& out) const` (out = J(q)^T g)");
  }
  return true;
}
}  // namespace detail

/// A chart that supplies its own exact level flow (built-in charts do: it shares the sines).
template <class C>
concept HasLevelFlow =
    requires(const C& c, typename C::Point& q, typename C::Point& p, typename C::Scalar m,
             typename C::Scalar h, int i) { c.level_flow(i, q, p, m, h); };

/// A chart that caches the sines and cosines of a body's coordinates (TrigType), so that the
/// level flows, the embedding and the pull-back of one stage share them (built-in S^n, H^n).
/// Everything the engine (stepper.hpp, system.hpp) calls on it is stated here.
template <class C>
concept HasTrigCache =
    EmbeddedChart<C> && std::default_initializable<typename C::TrigType> &&
    requires(const C& c, typename C::Point& q, typename C::Point& p, typename C::TrigType& t,
             typename C::Ambient& x, typename C::Scalar m, int i, bool own) {
      t.resize(i);                           // one entry per coordinate (the workspace sizes it)
      c.refresh(q, t);                       // t = trig of q
      c.level_flow(i, q, p, m, m, t, own);   // exact flow of K_i, t kept in sync with q; own =
                                             // false may leave level i's own entry stale
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
  for (int i = 0; i < dim_of(chart); ++i) k += chart.kinetic(i, q, p[i], m);
  return k;
}

/// What sesi::rechart does with a body (recharting.hpp, docs/charts.md): nothing, a turn (the
/// half-turn about the body: same q, p -> -p, a frame that reverses the body's tangent space),
/// or a homing (a new frame where the chart is best conditioned).
enum class RechartAction { none, turn, home };

}  // namespace sesi
