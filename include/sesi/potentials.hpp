#pragma once
/// @file potentials.hpp
/// Potential terms. Terms see embedding points only, so each is written once for every chart;
/// the system pulls their ambient gradients back to chart coordinates.
///
/// Two kinds, told apart by the concepts below:
///  - an external term V(x) per body: value(space, x, m) and gradient(space, x, m, g) = dV/dx;
///  - a pair term W(d_ij) over unordered pairs i < j, of the geodesic distance or of the chord
///    |x_i - x_j|: value(space, d, m_i, m_j) and derivative(space, d, m_i, m_j) = dW/dd.
/// A user term is any small type with those members, or a pair of lambdas wrapped by
/// make_external / make_pair.
///
/// The configurational temperature (diagnostics.hpp) also needs each term's Laplace-Beltrami
/// operator: an optional laplacian(space, x, m) of an external term (laplacian(space, q, m) of a
/// ChartTerm), and an optional second_derivative(space, d, m_i, m_j) = d^2W/dd^2 of a pair term
/// (the System adds the curvature's part, special::radial_laplacian, chord_laplacian). The
/// built-in terms have them; a term without one makes the Laplacian sum NaN.

#include <cmath>
#include <concepts>
#include <limits>
#include <numbers>
#include <utility>

#include "sesi/chart.hpp"
#include "sesi/special_functions.hpp"

namespace sesi {

/// Pair terms declare which distance they are a function of.
struct geodesic_distance {};
struct chord_distance {};

template <class T, class Space>
concept ExternalTerm = EmbeddedChart<Space> &&
    requires(const T& t, const Space& s, const typename Space::Ambient& x,
             typename Space::Scalar m, typename Space::Ambient& g) {
      { t.value(s, x, m) } -> std::convertible_to<typename Space::Scalar>;
      t.gradient(s, x, m, g);
    };

/// Terms on chart coordinates say so with `using coordinates = sesi::chart_coordinates;` (on E^n
/// a point and a coordinate vector have the same type).
struct chart_coordinates {};

/// A potential on chart coordinates: V(q) of one body and dV/dq, with no embedding. Any
/// HierarchicalChart takes it (sesi::System, docs/concepts.md); q is the body's coordinates as
/// stepped, so the bodies must stay in the chart itself (no per-body frames).
template <class T, class Space>
concept ChartTerm = HierarchicalChart<Space> && std::same_as<typename T::coordinates, chart_coordinates> &&
    requires(const T& t, const Space& s, const typename Space::Point& q, typename Space::Scalar m,
             typename Space::Point& g) {
      { t.value(s, q, m) } -> std::convertible_to<typename Space::Scalar>;
      t.gradient(s, q, m, g);
    };

template <class T, class Space>
concept PairTerm = EmbeddedChart<Space> &&
    requires(const T& t, const Space& s, typename Space::Scalar d, typename Space::Scalar m) {
      typename T::distance_kind;
      { t.value(s, d, m, m) } -> std::convertible_to<typename Space::Scalar>;
      { t.derivative(s, d, m, m) } -> std::convertible_to<typename Space::Scalar>;
    };

template <class T>
constexpr bool is_chord_term = std::same_as<typename T::distance_kind, chord_distance>;

/// A pair term of finite range: W and dW/dd vanish for d >= range(space). The system finds its
/// pairs through a neighbour index (neighbours.hpp) instead of looping over all pairs.
template <class T, class Space>
concept ShortRangeTerm = PairTerm<T, Space> && requires(const T& t, const Space& s) {
  { t.range(s) } -> std::convertible_to<typename Space::Scalar>;
};

/// A pair term with an algebraic form on a space's PairGeometry (chart.hpp): value(space, g,
/// m_i, m_j) and dW/dd = derivative(space, g, m_i, m_j) with no transcendental function, used by
/// the system where the space provides pair_geometry (cotangent gravity: ctn = cs / sn).
template <class T, class Space>
concept AlgebraicPairTerm =
    PairTerm<T, Space> && HasPairGeometry<Space> &&
    requires(const T& t, const Space& s, const PairGeometry<typename Space::Scalar>& g,
             typename Space::Scalar m) {
      { t.value(s, g, m, m) } -> std::convertible_to<typename Space::Scalar>;
      { t.derivative(s, g, m, m) } -> std::convertible_to<typename Space::Scalar>;
    };

namespace detail {
template <class Space>
typename Space::Scalar radius_or_one(const Space& s) {
  if constexpr (requires { s.radius(); }) {
    return s.radius();
  } else {
    return typename Space::Scalar(1);
  }
}
/// Distance from d to the singular set of a ctn-based term: d itself, and on S^n also the
/// antipode (ctn = cot(d/R)/R is singular at d = pi R).
template <class Space, class Scalar>
Scalar ctn_singular_gap(const Space& space, Scalar d) {
  if constexpr (requires { space.curvature(); }) {
    if (space.curvature() > Scalar(0)) {
      using std::min;
      return min(d, std::numbers::pi_v<Scalar> * radius_or_one(space) - d);
    }
  }
  return d;
}
}  // namespace detail

/// The default close-encounter floor of a singular term of length scale L: L eps^(1/3)
/// (6.1e-6 L in double; docs/stability.md). Closer than that, the round-off of the points
/// (eps L) already moves a 1/d potential by eps^(1/3) of its scale 1/L.
template <class Scalar>
Scalar default_min_distance(Scalar length) {
  using std::cbrt;
  return length * cbrt(std::numeric_limits<Scalar>::epsilon());
}

/// The seed paper's pair term (eq. 11 and Suppl. "Finding an explicit solution"):
/// W(s) = ((sqrt(1 - s^2) - cos theta0) / s)^2 with s = chord / (sqrt(3) R) = 2 sin(L/2R)/sqrt(3),
/// energy = strength * W per unordered pair. The seed sums over ordered pairs: strength = 2.
template <class Scalar>
class ChordWell {
 public:
  using distance_kind = chord_distance;

  explicit ChordWell(Scalar theta0, Scalar strength = Scalar(2))
      : theta0_(theta0), strength_(strength), cos_theta0_(std::cos(theta0)) {}

  Scalar theta0() const { return theta0_; }
  Scalar strength() const { return strength_; }

  template <class Space>
  Scalar value(const Space& space, Scalar chord, Scalar, Scalar) const {
    using std::sqrt;
    const Scalar s = chord * scale(space);
    const Scalar w = (sqrt(Scalar(1) - s * s) - cos_theta0_) / s;
    return strength_ * w * w;
  }
  /// dW/ds = 2 (a - c0)(c0 - 1/a) / s^3 with a = sqrt(1 - s^2), c0 = cos theta0.
  template <class Space>
  Scalar derivative(const Space& space, Scalar chord, Scalar, Scalar) const {
    using std::sqrt;
    const Scalar k = scale(space);
    const Scalar s = chord * k;
    const Scalar a = sqrt(Scalar(1) - s * s);
    return strength_ * Scalar(2) * (a - cos_theta0_) * (cos_theta0_ - Scalar(1) / a) / (s * s * s) * k;
  }
  /// d^2W/ds^2 = 2 (w'^2 + w w'') of w = (a - c0)/s, with w' = (c0 - 1/a)/s^2 and
  /// w'' = -1/(a^3 s) - 2 (c0 - 1/a)/s^3 (a' = -s/a); times k^2 for the chord.
  template <class Space>
  Scalar second_derivative(const Space& space, Scalar chord, Scalar, Scalar) const {
    using std::sqrt;
    const Scalar k = scale(space);
    const Scalar s = chord * k;
    const Scalar s2 = s * s;
    const Scalar a = sqrt(Scalar(1) - s2);
    const Scalar u = cos_theta0_ - Scalar(1) / a;  // s^2 w'
    const Scalar v = a - cos_theta0_;              // s w
    return strength_ * Scalar(2) * ((u * u - Scalar(2) * v * u) / (s2 * s2) - v / (a * a * a * s2)) * k * k;
  }

 private:
  /// 1 / (sqrt(3) R): s = chord / (sqrt(3) R).
  template <class Space>
  static Scalar scale(const Space& space) {
    return Scalar(1) / (std::numbers::sqrt3_v<Scalar> * detail::radius_or_one(space));
  }

  Scalar theta0_;
  Scalar strength_;
  Scalar cos_theta0_;
};

/// The curved N-body problem (Diacu, Perez-Chavela, Santoprete): V = -G sum_{i<j} m_i m_j ctn(d_ij),
/// ctn = cot(d/R)/R on S^n, coth(d/R)/R on H^n, 1/d on E^n (special_functions.hpp).
template <class Scalar>
struct CotangentGravity {
  using distance_kind = geodesic_distance;
  Scalar G = Scalar(1);
  /// Close-encounter floor (sesi::closest_encounter): < 0 the default, R eps^(1/3); 0 none.
  Scalar min_distance = Scalar(-1);

  template <class Space>
  Scalar encounter_floor(const Space& space) const {
    return min_distance < Scalar(0) ? default_min_distance(detail::radius_or_one(space)) : min_distance;
  }
  template <class Space>
  Scalar singular_gap(const Space& space, Scalar d) const {
    return detail::ctn_singular_gap(space, d);
  }

  template <class Space>
  Scalar value(const Space& space, Scalar d, Scalar mi, Scalar mj) const {
    return -G * mi * mj * special::ctn(space.curvature(), d);
  }
  template <class Space>
  Scalar derivative(const Space& space, Scalar d, Scalar mi, Scalar mj) const {
    return -G * mi * mj * special::ctn_derivative(space.curvature(), d);
  }
  /// d^2W/dd^2 = -G m_i m_j ctn''(d), ctn'' = 2 cs / sn^3.
  template <class Space>
  Scalar second_derivative(const Space& space, Scalar d, Scalar mi, Scalar mj) const {
    return -G * mi * mj * special::ctn_second_derivative(space.curvature(), d);
  }
  /// The algebraic form (AlgebraicPairTerm): ctn(d) = cs / sn on S^n, H^n and E^n alike, and
  /// d ctn / dd = -1 / sn^2 (cot(d/R)/R, coth(d/R)/R and 1/d differentiated; sn = R sin(d/R),
  /// R sinh(d/R), d).
  template <class Space>
  Scalar value(const Space&, const PairGeometry<Scalar>& g, Scalar mi, Scalar mj) const {
    return -G * mi * mj * g.cs() / g.sn;
  }
  template <class Space>
  Scalar derivative(const Space&, const PairGeometry<Scalar>& g, Scalar mi, Scalar mj) const {
    return (G * mi * mj) / (g.sn * g.sn);
  }
  /// dW/dd / sn, what the gradient needs (one division per pair instead of two).
  template <class Space>
  Scalar derivative_over_sn(const Space&, const PairGeometry<Scalar>& g, Scalar mi, Scalar mj) const {
    return (G * mi * mj) / (g.sn * g.sn * g.sn);
  }
  template <class Space>
  Scalar second_derivative(const Space&, const PairGeometry<Scalar>& g, Scalar mi, Scalar mj) const {
    return -G * mi * mj * Scalar(2) * g.cs() / (g.sn * g.sn * g.sn);
  }
};

/// Harmonic spring on the geodesic distance: k/2 (d - d0)^2 per pair.
template <class Scalar>
struct HarmonicPair {
  using distance_kind = geodesic_distance;
  Scalar k = Scalar(1);
  Scalar d0 = Scalar(0);

  template <class Space>
  Scalar value(const Space&, Scalar d, Scalar, Scalar) const {
    return k / Scalar(2) * (d - d0) * (d - d0);
  }
  template <class Space>
  Scalar derivative(const Space&, Scalar d, Scalar, Scalar) const {
    return k * (d - d0);
  }
  template <class Space>
  Scalar second_derivative(const Space&, Scalar, Scalar, Scalar) const {
    return k;
  }
};

/// Lennard-Jones on the geodesic distance, 4 eps ((sigma/d)^12 - (sigma/d)^6), shifted to zero at
/// the cutoff and zero beyond it (truncated and shifted, Allen & Tildesley, 2nd ed., sec. 1.4.3).
template <class Scalar>
struct LennardJones {
  using distance_kind = geodesic_distance;
  Scalar epsilon = Scalar(1);
  Scalar sigma = Scalar(1);
  Scalar cutoff = Scalar(2.5);
  /// Close-encounter floor (sesi::closest_encounter): < 0 the default, sigma eps^(1/3); 0 none.
  Scalar min_distance = Scalar(-1);

  template <class Space>
  Scalar encounter_floor(const Space&) const {
    return min_distance < Scalar(0) ? default_min_distance(sigma) : min_distance;
  }
  template <class Space>
  Scalar singular_gap(const Space&, Scalar d) const {
    return d;
  }
  /// Zero from the cutoff on (ShortRangeTerm).
  template <class Space>
  Scalar range(const Space&) const {
    return cutoff;
  }

  Scalar raw(Scalar d) const {
    const Scalar s2 = sigma * sigma / (d * d);
    const Scalar s6 = s2 * s2 * s2;
    return Scalar(4) * epsilon * (s6 * s6 - s6);
  }
  template <class Space>
  Scalar value(const Space&, Scalar d, Scalar, Scalar) const {
    return d < cutoff ? raw(d) - raw(cutoff) : Scalar(0);
  }
  template <class Space>
  SESI_INLINE Scalar derivative(const Space&, Scalar d, Scalar, Scalar) const {
    if (!(d < cutoff)) return Scalar(0);
    const Scalar s2 = sigma * sigma / (d * d);
    const Scalar s6 = s2 * s2 * s2;
    return Scalar(-24) * epsilon * (Scalar(2) * s6 * s6 - s6) / d;
  }
  /// dW/dd / s for a given s (the pair kernel's dW/dd / sn, sesi::System): one division fewer
  /// than derivative(d) / s, which matters in the many-body step's inner loop.
  template <class Space>
  SESI_INLINE Scalar derivative_over(const Space&, Scalar d, Scalar s) const {
    if (!(d < cutoff)) return Scalar(0);
    const Scalar s2 = sigma * sigma / (d * d);
    const Scalar s6 = s2 * s2 * s2;
    return Scalar(-24) * epsilon * (Scalar(2) * s6 * s6 - s6) / (d * s);
  }
  /// d^2W/dd^2 = 24 eps (26 (sigma/d)^12 - 7 (sigma/d)^6) / d^2 inside the cutoff. The force's
  /// jump at the cutoff is a surface term of the Laplacian that no pair function gives: the
  /// configurational temperature omits it (docs/concepts.md).
  template <class Space>
  Scalar second_derivative(const Space&, Scalar d, Scalar, Scalar) const {
    if (!(d < cutoff)) return Scalar(0);
    const Scalar s2 = sigma * sigma / (d * d);
    const Scalar s6 = s2 * s2 * s2;
    return Scalar(24) * epsilon * (Scalar(26) * s6 * s6 - Scalar(7) * s6) / (d * d);
  }
};

/// The curved Kepler problem: V = -k m ctn(d(x, center)) (Kozlov & Harin; Cariñena et al.).
template <class Space>
struct CentralCotangent {
  using Scalar = typename Space::Scalar;
  Scalar k = Scalar(1);
  typename Space::Ambient center;
  /// Close-encounter floor (sesi::closest_encounter): < 0 the default, R eps^(1/3); 0 none.
  Scalar min_distance = Scalar(-1);

  Scalar encounter_floor(const Space& space) const {
    return min_distance < Scalar(0) ? default_min_distance(detail::radius_or_one(space)) : min_distance;
  }
  /// Distance from x to the term's singular set (the center, and its antipode on S^n).
  Scalar singular_gap(const Space& space, const typename Space::Ambient& x) const {
    return detail::ctn_singular_gap(space, space.distance(x, center));
  }

  Scalar value(const Space& space, const typename Space::Ambient& x, Scalar m) const {
    return -k * m * special::ctn(space.curvature(), space.distance(x, center));
  }
  void gradient(const Space& space, const typename Space::Ambient& x, Scalar m,
                typename Space::Ambient& g) const {
    const Scalar d = space.distance(x, center);
    space.distance_gradient(x, center, g);
    g *= -k * m * special::ctn_derivative(space.curvature(), d);
  }
  /// Delta V = -k m Delta ctn(d) = -k m (3 - n) cs / sn^3 (special::radial_laplacian with
  /// ctn' = -1/sn^2, ctn'' = 2 cs / sn^3): zero on S^3, H^3 and E^3, where ctn is harmonic.
  Scalar laplacian(const Space& space, const typename Space::Ambient& x, Scalar m) const {
    const Scalar d = space.distance(x, center);
    const Scalar kappa = space.curvature();
    return special::radial_laplacian(dim_of(space), special::sn(kappa, d), special::cs(kappa, d),
                                     -k * m * special::ctn_derivative(kappa, d),
                                     -k * m * special::ctn_second_derivative(kappa, d));
  }
};

/// A user external term from two callables: value(x, m) -> Scalar, gradient(x, m) -> Ambient.
template <class Value, class Gradient>
struct External {
  Value value_fn;
  Gradient gradient_fn;
  template <class Space>
  auto value(const Space&, const typename Space::Ambient& x, typename Space::Scalar m) const {
    return value_fn(x, m);
  }
  template <class Space>
  void gradient(const Space&, const typename Space::Ambient& x, typename Space::Scalar m,
                typename Space::Ambient& g) const {
    g = gradient_fn(x, m);
  }
};
template <class Value, class Gradient>
External<Value, Gradient> make_external(Value v, Gradient g) {
  return {std::move(v), std::move(g)};
}

/// A user potential on chart coordinates from two callables: value(q, m) -> Scalar and
/// gradient(q, m) -> Point (dV/dq), for any HierarchicalChart (ChartTerm).
template <class Value, class Gradient>
struct ChartPotential {
  using coordinates = chart_coordinates;
  Value value_fn;
  Gradient gradient_fn;
  template <class Space>
  auto value(const Space&, const typename Space::Point& q, typename Space::Scalar m) const {
    return value_fn(q, m);
  }
  template <class Space>
  void gradient(const Space&, const typename Space::Point& q, typename Space::Scalar m,
                typename Space::Point& g) const {
    g = gradient_fn(q, m);
  }
};
template <class Value, class Gradient>
ChartPotential<Value, Gradient> make_chart_potential(Value v, Gradient g) {
  return {std::move(v), std::move(g)};
}

/// A user pair term from two callables of (d, m_i, m_j): W and dW/dd, on the distance Kind.
template <class Kind, class Value, class Derivative>
struct Pair {
  using distance_kind = Kind;
  Value value_fn;
  Derivative derivative_fn;
  template <class Space, class Scalar>
  Scalar value(const Space&, Scalar d, Scalar mi, Scalar mj) const {
    return value_fn(d, mi, mj);
  }
  template <class Space, class Scalar>
  Scalar derivative(const Space&, Scalar d, Scalar mi, Scalar mj) const {
    return derivative_fn(d, mi, mj);
  }
};
template <class Kind = geodesic_distance, class Value, class Derivative>
Pair<Kind, Value, Derivative> make_pair(Value v, Derivative d) {
  return {std::move(v), std::move(d)};
}

/// A user pair term that vanishes (with its derivative) from distance `range` on: the system
/// finds its pairs through a neighbour index (ShortRangeTerm).
template <class Kind, class Value, class Derivative, class Scalar>
struct ShortRangePair : Pair<Kind, Value, Derivative> {
  Scalar reach;
  template <class Space>
  Scalar range(const Space&) const {
    return reach;
  }
};
template <class Kind = geodesic_distance, class Value, class Derivative, class Scalar>
ShortRangePair<Kind, Value, Derivative, Scalar> make_short_range_pair(Value v, Derivative d, Scalar range) {
  return {{std::move(v), std::move(d)}, range};
}

}  // namespace sesi
