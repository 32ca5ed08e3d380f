#pragma once
/// @file guard.hpp
/// Run-time guards against silent garbage (issue #5; docs/stability.md).
///
///  - EnergyGuard: the energy error |E - E0|, relative to the initial energy scale K0 + |V0|,
///    must stay below a threshold (default 100, which no stable run of the built-in methods
///    reaches unless its step is within 0.5% of the method's linear stability limit), and the
///    state and energy must stay finite. A step beyond a method's stability limit makes the
///    energy grow geometrically, so the guard stops such a run long before overflow.
///  - closest_encounter: the pair of bodies (or body and center) of a singular potential term
///    (cotangent gravity, Lennard-Jones, central cotangent) that came closer to the term's
///    singular set than its floor (encounter_floor(), default L eps^(1/3), potentials.hpp).
///    Systems without singular terms compile to nothing.

#include <cmath>
#include <cstddef>
#include <limits>
#include <tuple>
#include <type_traits>
#include <utility>

#include "sesi/state.hpp"
#include "sesi/system.hpp"

namespace sesi {

/// What a guard found.
enum class GuardStatus {
  ok,                     ///< within bounds
  energy_error_exceeded,  ///< |E - E0| > relative * scale
  non_finite,             ///< a coordinate, momentum or the energy is not finite
};

/// "ok", "energy error exceeded", "non-finite".
inline const char* to_string(GuardStatus status) {
  switch (status) {
    case GuardStatus::ok: return "ok";
    case GuardStatus::energy_error_exceeded: return "energy error exceeded";
    case GuardStatus::non_finite: return "non-finite";
  }
  return "unknown";
}

/// The result of one check: the status, and where it was found.
template <class Scalar>
struct GuardResult {
  GuardStatus status = GuardStatus::ok;
  long step = 0;          ///< the step checked (as given by the caller)
  Scalar time = 0;        ///< its time
  Scalar energy = 0;      ///< E at that step
  Scalar error = 0;       ///< |E - E0| / scale (|E - E0| when the scale is 0)
  bool ok() const { return status == GuardStatus::ok; }
};

/// The energy-error guard. Relative to the scale K0 + |V0| of the initial state (not |E0|, which
/// may vanish for a bound orbit); when that scale is 0 (everything at rest, no potential energy)
/// only non-finite states are caught.
template <class Scalar>
class EnergyGuard {
 public:
  /// The default threshold on |E - E0| / (K0 + |V0|) (docs/stability.md).
  static constexpr double default_relative = 100.0;

  EnergyGuard() = default;
  /// From the initial energy e0 and scale (K0 + |V0|); relative <= 0 or not finite turns the
  /// energy check off (non-finite states are still caught).
  EnergyGuard(Scalar e0, Scalar scale, Scalar relative = Scalar(default_relative))
      : e0_(e0), scale_(scale), relative_(relative) {}

  /// The guard of sys started at state s.
  template <class Sys>
  static EnergyGuard of(const Sys& sys, const State<typename Sys::Chart>& s,
                        Scalar relative = Scalar(default_relative)) {
    using std::abs;
    const Scalar k = Scalar(sys.kinetic_energy(s)), v = Scalar(sys.potential_energy(s));
    return EnergyGuard(k + v, k + abs(v), relative);
  }

  Scalar initial_energy() const { return e0_; }
  Scalar scale() const { return scale_; }
  Scalar relative() const { return relative_; }
  bool checks_energy() const {
    using std::isfinite;
    return relative_ > Scalar(0) && isfinite(relative_) && scale_ > Scalar(0);
  }

  /// Check the energy E of step `step` at time t.
  GuardResult<Scalar> check(long step, Scalar t, Scalar energy) const {
    using std::abs;
    using std::isfinite;
    GuardResult<Scalar> r;
    r.step = step;
    r.time = t;
    r.energy = energy;
    if (!isfinite(energy)) {
      r.status = GuardStatus::non_finite;
      r.error = energy;
      return r;
    }
    const Scalar diff = abs(energy - e0_);
    r.error = scale_ > Scalar(0) ? diff / scale_ : diff;
    if (checks_energy() && r.error > relative_) r.status = GuardStatus::energy_error_exceeded;
    return r;
  }

  /// Check state s of sys (coordinates, momenta and energy) at step `step`, time t.
  template <class Sys>
  GuardResult<Scalar> check(const Sys& sys, const State<typename Sys::Chart>& s, long step,
                            Scalar t) const {
    if (!s.q.allFinite() || !s.p.allFinite()) {
      GuardResult<Scalar> r;
      r.status = GuardStatus::non_finite;
      r.step = step;
      r.time = t;
      r.energy = r.error = std::numeric_limits<Scalar>::quiet_NaN();
      return r;
    }
    return check(step, t, Scalar(sys.energy(s)));
  }

 private:
  Scalar e0_ = 0;
  Scalar scale_ = 0;
  Scalar relative_ = Scalar(default_relative);
};

/// A close encounter found by closest_encounter.
template <class Scalar>
struct Encounter {
  int first = -1;   ///< body index (0-based), -1 when none
  int second = -1;  ///< the other body (0-based), or -1 for an external term's center
  int term = -1;    ///< index of the term in the system's term list
  Scalar gap = 0;   ///< distance to the term's singular set
  Scalar floor = 0; ///< the term's floor
  bool found() const { return first >= 0; }
};

/// Pair and external terms with a close-encounter floor (the built-in singular terms).
template <class T, class Space>
concept SingularPairTerm = PairTerm<T, Space> && requires(const T& t, const Space& s,
                                                          typename Space::Scalar d) {
  { t.encounter_floor(s) } -> std::convertible_to<typename Space::Scalar>;
  { t.singular_gap(s, d) } -> std::convertible_to<typename Space::Scalar>;
};
template <class T, class Space>
concept SingularExternalTerm = ExternalTerm<T, Space> && requires(const T& t, const Space& s,
                                                                  const typename Space::Ambient& x) {
  { t.encounter_floor(s) } -> std::convertible_to<typename Space::Scalar>;
  { t.singular_gap(s, x) } -> std::convertible_to<typename Space::Scalar>;
};

namespace detail {
template <class Sys, class Tuple>
struct any_singular : std::false_type {};
template <class Sys, class... Terms>
struct any_singular<Sys, std::tuple<Terms...>>
    : std::bool_constant<((SingularPairTerm<Terms, typename Sys::Chart> ||
                           SingularExternalTerm<Terms, typename Sys::Chart>) || ...)> {};
}  // namespace detail

/// Does Sys have a term with a close-encounter floor? (Else closest_encounter is a no-op.)
template <class Sys>
constexpr bool has_singular_terms =
    detail::any_singular<Sys, std::remove_cvref_t<decltype(std::declval<const Sys&>().terms())>>::value;

/// The encounter of state s that is deepest below its term's floor (smallest gap / floor), or
/// none. A floor of 0 turns a term's check off. w: sys's workspace (its points are overwritten).
template <class Sys>
Encounter<typename Sys::Scalar> closest_encounter(const Sys& sys, const State<typename Sys::Chart>& s,
                                                  typename Sys::Workspace& w) {
  using Scalar = typename Sys::Scalar;
  using Chart = typename Sys::Chart;
  Encounter<Scalar> worst;
  if constexpr (has_singular_terms<Sys>) {
    sys.embed_all(s, w);
    const Chart& chart = sys.chart();
    Scalar worst_ratio = Scalar(1);
    auto consider = [&](int i, int j, int term, Scalar gap, Scalar floor) {
      // ratio < 1: below the floor; NaN distances (a non-finite state) are left to the energy guard.
      if (!(floor > Scalar(0))) return;
      const Scalar ratio = gap / floor;
      if (ratio < worst_ratio) {
        worst_ratio = ratio;
        worst = Encounter<Scalar>{i, j, term, gap, floor};
      }
    };
    int index = 0;
    std::apply(
        [&](const auto&... term) {
          (
              [&](const auto& t) {
                using T = std::remove_cvref_t<decltype(t)>;
                if constexpr (SingularPairTerm<T, Chart>) {
                  const Scalar floor = t.encounter_floor(chart);
                  for (int i = 0; i < sys.bodies(); ++i) {
                    for (int j = i + 1; j < sys.bodies(); ++j) {
                      w.x = w.X.col(i);
                      w.y = w.X.col(j);
                      consider(i, j, index, t.singular_gap(chart, chart.distance(w.x, w.y)), floor);
                    }
                  }
                } else if constexpr (SingularExternalTerm<T, Chart>) {
                  const Scalar floor = t.encounter_floor(chart);
                  // w.X holds cluster-local points when s.clustered: a centre goes into the
                  // cluster's frame as the system evaluates it, otherwise the points go to the world.
                  if constexpr (requires { sys.in_cluster_frame(t, w); }) {
                    const T local = sys.in_cluster_frame(t, w);
                    for (int i = 0; i < sys.bodies(); ++i) {
                      w.x = w.X.col(i);
                      consider(i, -1, index, local.singular_gap(chart, w.x), floor);
                    }
                  } else {
                    for (int i = 0; i < sys.bodies(); ++i) {
                      w.x = w.X.col(i);
                      if (s.clustered) w.x = (s.cluster * w.x).eval();
                      consider(i, -1, index, t.singular_gap(chart, w.x), floor);
                    }
                  }
                }
                ++index;
              }(term),
              ...);
        },
        sys.terms());
  }
  return worst;
}

template <class Sys>
Encounter<typename Sys::Scalar> closest_encounter(const Sys& sys, const State<typename Sys::Chart>& s) {
  if constexpr (!has_singular_terms<Sys>) {
    return {};
  } else {
    auto w = sys.make_workspace();
    return closest_encounter(sys, s, w);
  }
}

}  // namespace sesi
