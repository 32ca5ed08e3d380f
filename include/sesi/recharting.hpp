#pragma once
/// @file recharting.hpp
/// Pole-safe and far-safe charts (issue #5; docs/charts.md). Each body may carry its own chart
/// frame F (an isometry of the ambient space: orthogonal on S^n, Lorentz on H^n), with
/// world point x = F embed(q). Between steps, a body that comes within a threshold of its
/// chart's singular set (or, on H^n, too far from its chart's origin) is re-charted: it gets a
/// frame in which it sits where the chart is best conditioned, moving along a well-conditioned
/// direction, and (q, p) are transformed by the cotangent lift of the chart change, which is
/// canonical, so the method stays symplectic and explicit. Potentials see world points only.

#include <atomic>
#include <cmath>
#include <cstddef>
#include <functional>
#include <type_traits>
#include <utility>

#include <vector>

#include <Eigen/Core>

#include "sesi/chart.hpp"
#include "sesi/parallel.hpp"
#include "sesi/state.hpp"
#include "sesi/stepper.hpp"
#include "sesi/topology.hpp"

namespace sesi {

/// When and where to re-chart (defaults documented in docs/charts.md).
template <class Scalar>
struct RechartPolicy {
  /// A polar angle (S^n, n >= 2; the angles of H^n) is in danger when |sin q_k| falls below
  /// this, deep below half of it. 1/2 keeps the chart's 1/sin^2 factors below 4 where bodies
  /// move (a turned body recedes); the chart-dependent terms of the modified energy, and so the
  /// residual jumps at re-chartings, grow with them (docs/charts.md has the measurements).
  Scalar min_sine = Scalar(1) / Scalar(2);
  /// H^n, n >= 2: the radius q_1 is in danger below this (the polar origin is singular), deep
  /// below half of it.
  Scalar min_radius = Scalar(1) / Scalar(4);
  /// H^n: the radius is in danger above this (sinh and cosh grow like e^{q_1}), deep 1 beyond.
  Scalar max_radius = Scalar(3);
  /// H^n, n >= 2: the radius at which a homed body is placed, moving tangentially, so that its
  /// geodesic's closest approach to the new origin is this radius (below max_radius / 2, so that
  /// a homed body is turned, not homed, when it reaches max_radius).
  Scalar home_radius = Scalar(1);
  /// H^n with a cluster frame (State::cluster): the cluster is re-centred when the centre of its
  /// cluster-local points is farther than this from the frame's origin (recentre()), so that the
  /// local points, and with them every pair chord and central term, stay O(1).
  Scalar cluster_radius = Scalar(2);
};

/// Charts that know their singular set and how to re-chart a body (built-in S^n and H^n).
template <class C>
concept Rechartable =
    EmbeddedChart<C> &&
    requires(const C& c, const typename C::Point& q, typename C::Point& qo, typename C::Point& po,
             const typename C::Ambient& x, const RechartPolicy<typename C::Scalar>& policy,
             typename State<C>::Frame& frame, typename C::Scalar m) {
      { c.rechart_action(q, q, policy) } -> std::same_as<RechartAction>;
      c.turn(q, frame);                        // frame <- the half-turn about the body
      c.home(x, x, m, policy, frame, qo, po);  // frame <- the homing change L (see below)
    };

/// Re-chartings done by one call of rechart().
struct Recharted {
  int turned = 0;
  int homed = 0;
  int recentred = 0;  ///< cluster re-centrings (not counted in total(): no body is re-charted)
  int total() const { return turned + homed; }
};

/// Charts that can move a cluster frame (H^n): the standard boost to a point. Not a quotient
/// (topology.hpp): its bodies are kept in the fundamental domain instead.
template <class C>
concept ClusterChart = EmbeddedChart<C> && !HasTopology<C> && requires(const C& c, const typename C::Ambient& y,
                                                    typename State<C>::Frame& b) {
  c.boost_to(y, b);
};

namespace detail {
/// The centre of s's bodies in the cluster's frame: the mass-weighted Minkowski mean of their
/// cluster-local points F_b embed(q_b), normalised onto the hyperboloid (the centre of mass of
/// the hyperboloid model). False when it is not a future point (or not finite).
template <class Sys>
bool cluster_centre(const Sys& sys, const State<typename Sys::Chart>& s, typename Sys::Chart::Ambient& y) {
  using Chart = typename Sys::Chart;
  using Scalar = typename Sys::Scalar;
  using std::sqrt;
  const Chart& chart = sys.chart();
  const int a = ambient_dim_of(chart), n = dim_of(chart);
  typename Chart::Point q(n);
  typename Chart::Ambient x(a), mean = Chart::Ambient::Zero(a);
  const auto point = [&](int b) {  // body b's cluster-local point, into x
    q = s.q.col(b);
    chart.embed(q, x);
    if (s.framed()) x = (s.frames[static_cast<std::size_t>(b)] * x).eval();
  };
  bool domain = false;
  if constexpr (requires { sys.domain(); }) domain = sys.domain();
  if (domain) {
    // A domain of a simulation across processes (System::set_domain): component by component
    // through its sums over all the processes' bodies (the bits of the loop below: each
    // component summed alone, in body order).
    std::vector<std::vector<Scalar>> rows(static_cast<std::size_t>(a), std::vector<Scalar>(static_cast<std::size_t>(s.bodies())));
    for (int b = 0; b < s.bodies(); ++b) {
      point(b);
      for (int i = 0; i < a; ++i) rows[static_cast<std::size_t>(i)][static_cast<std::size_t>(b)] = sys.mass(b) * x[i];
    }
    if constexpr (requires { sys.sum_rows(rows[0]); }) {
      for (int i = 0; i < a; ++i) mean[i] = sys.sum_rows(rows[static_cast<std::size_t>(i)]);
    }
  } else {
    for (int b = 0; b < s.bodies(); ++b) {
      point(b);
      mean += sys.mass(b) * x;
    }
  }
  // -<m,m>_L > 0 (a sum of future points), written out: GCC 12 warns falsely (array-bounds)
  // on the vectorised dot of a dynamic head of this fixed-size vector once inlined here.
  Scalar norm2 = mean[n] * mean[n];
  for (int i = 0; i < n; ++i) norm2 -= mean[i] * mean[i];
  if (!(norm2 > Scalar(0))) return false;
  y = chart.radius() * mean / sqrt(norm2);
  return true;
}
}  // namespace detail

/// Re-centre the cluster frame of s (State::cluster) when the centre of the bodies'
/// cluster-local points x_b = F_b embed(q_b) -- their mass-weighted Minkowski mean, normalised
/// onto the hyperboloid (the centre of mass of the hyperboloid model) -- lies farther than
/// policy.cluster_radius from the frame's origin: with B the standard boost to that centre (O(1)
/// entries, Lorentz to rounding), C <- C B and F_b <- B^{-1} F_b (B^{-1} = eta B^T eta). World
/// points C F_b embed(q_b) are unchanged, q and p are untouched, and every potential, a function
/// of the local points' mutual distances (and of the centres moved with C), is unchanged: a
/// change of world coordinates, not of the dynamics, so the method stays symplectic and
/// reversible. Returns whether it re-centred. Nothing happens without a cluster frame, nor for
/// a system with force centres (System::has_movable_centres()): its frame stays at the centre,
/// where the centre is exact, since a far centre off the frame's origin is known only to
/// eps sinh D (Hyperbolic::to_frame).
template <class Sys>
bool recentre(const Sys& sys, State<typename Sys::Chart>& s,
              const RechartPolicy<typename Sys::Scalar>& policy) {
  using Chart = typename Sys::Chart;
  if constexpr (ClusterChart<Chart>) {
    if (!s.clustered || s.bodies() == 0) return false;
    // A system with force centres keeps its frame where it was put (see has_movable_centres).
    if constexpr (requires { sys.has_movable_centres(); }) {
      if (sys.has_movable_centres()) return false;
    }
    using std::cosh;
    const Chart& chart = sys.chart();
    const int a = ambient_dim_of(chart), n = dim_of(chart);
    typename Chart::Ambient y(a);
    if (!detail::cluster_centre(sys, s, y)) return false;  // (NaN: left to the finiteness check)
    // Its distance r from the frame's origin: cosh r = y_t / R.
    if (!(y[n] / chart.radius() > cosh(policy.cluster_radius))) return false;
    typename State<Chart>::Frame boost(a, a);
    chart.boost_to(y, boost);
    typename State<Chart>::Frame inverse = boost.transpose();  // eta B^T eta
    inverse.row(n) = -inverse.row(n);
    inverse.col(n) = -inverse.col(n);
    s.cluster = (s.cluster * boost).eval();
    if (!s.framed()) s.enable_frames(a);
    for (auto& frame : s.frames) frame = (inverse * frame).eval();
    return true;
  } else {
    static_cast<void>(sys);
    static_cast<void>(s);
    static_cast<void>(policy);
    return false;
  }
}

/// Put s -- bodies given in the space's own chart (no frames, no cluster frame), e.g. read
/// from world coordinates -- into a cluster frame (State::cluster) at `at`, or by default at the
/// centre of the bodies (as recentre() computes it). A system with force centres should pass
/// its centre: its frame stays there (recentre). When that point lies within
/// policy.cluster_radius of the origin, C = I: the run is the one without a cluster frame, bit
/// for bit, until it first re-centres. Otherwise C = B(y), the standard boost to it, and each
/// body is re-read in the frame from its world point and velocity by Chart::to_frame (no
/// cancellation: an error eps sinh D at distance D, what world coordinates resolve there) with
/// identity body frames. Returns whether the frame was moved from the origin; charts without a
/// cluster frame (S^n, E^n) and states already framed are left as they are.
template <class Sys>
bool enter_cluster_frame(const Sys& sys, State<typename Sys::Chart>& s,
                         const RechartPolicy<typename Sys::Scalar>& policy,
                         const typename Sys::Chart::Ambient* at = nullptr) {
  using Chart = typename Sys::Chart;
  if constexpr (ClusterChart<Chart>) {
    if (s.framed() || s.clustered) return false;
    using std::cosh;
    const Chart& chart = sys.chart();
    const int a = ambient_dim_of(chart), n = dim_of(chart);
    typename Chart::Ambient y(a);
    // Near the origin or not? The world centre of mass is accurate near the origin; far out its
    // -<m,m>_L cancels to at most eps |m|^2, so it comes out far (or not at all) there too.
    // (A sum of future points is a future point: only that cancellation, or a NaN, makes
    // cluster_centre fail.)
    bool far = false;
    if (at) {
      y = *at;
      far = y[n] / chart.radius() > cosh(policy.cluster_radius);
    } else if (s.bodies() > 0 && s.q.allFinite() && s.p.allFinite()) {
      far = !detail::cluster_centre(sys, s, y) || y[n] / chart.radius() > cosh(policy.cluster_radius);
    }
    if (!far) {
      s.set_cluster(State<Chart>::Frame::Identity(a, a));
      return false;
    }
    // Far out: the frame at the given centre, or first at body 0's point (read exactly there)
    // and then, by recentre() on the cluster-local points, at the bodies' centre.
    if (!at) chart.embed(typename Chart::Point(s.q.col(0)), y);
    typename State<Chart>::Frame c(a, a);
    chart.boost_to(y, c);
    typename Chart::Point q(n), p(n);
    typename Chart::Ambient x(a), v(a), xl(a), vl(a);
    for (int b = 0; b < s.bodies(); ++b) {
      q = s.q.col(b);
      p = s.p.col(b);
      chart.embed(q, x);
      chart.velocity(q, p, sys.mass(b), v);
      chart.to_frame(c, x, v, xl, vl);
      chart.chart(xl, q);
      if constexpr (Rechartable<Chart>) {
        // At (or near) the frame's origin, the chart's polar singularity: home the body there
        // (its own frame), as re-charting would.
        if (dim_of(chart) >= 2 && q[0] < policy.min_radius) {
          if (!s.framed()) s.enable_frames(a);
          chart.home(xl, vl, sys.mass(b), policy, s.frames[static_cast<std::size_t>(b)], q, p);
          s.q.col(b) = q;
          s.p.col(b) = p;
          continue;
        }
      }
      chart.momentum(q, vl, sys.mass(b), p);
      s.q.col(b) = q;
      s.p.col(b) = p;
    }
    s.set_cluster(c);
    if (!at) recentre(sys, s, policy);
    return true;
  } else {
    static_cast<void>(sys);
    static_cast<void>(s);
    static_cast<void>(policy);
    static_cast<void>(at);
    return false;
  }
}

/// Re-chart every body of s whose chart says so (Chart::rechart_action) under policy. The first
/// call gives s identity frames.
///
/// A body moving deeper into a danger zone (near a pole, near or far from the H^n origin) is
/// turned: its frame F becomes F T, T the half-turn about the body (the geodesic symmetry at
/// the body's point of the symmetric space S^n or H^n: an isometry fixing it and reversing its
/// tangent space), so q stays and p changes sign: in the new chart the body moves back out of
/// the zone it was entering, along the same chart curve reversed, while its world state is
/// unchanged. The compositions are symmetric and reversible under p -> -p, so their modified
/// Hamiltonian is even in p (Hairer, Lubich, Wanner, Geometric Numerical Integration, 2nd ed.,
/// IX.2 and XI.1); its chart-dependent kinetic terms are therefore the same in both charts, and
/// re-chartings add no drift (docs/charts.md; tests/stability/long.cpp).
/// A body deep in a zone, or one a turn cannot help, is homed instead (Chart::home).
template <class Sys>
Recharted rechart(const Sys& sys, State<typename Sys::Chart>& s,
                  const RechartPolicy<typename Sys::Scalar>& policy) {
  using Chart = typename Sys::Chart;
  Recharted done;
  if constexpr (Rechartable<Chart>) {
    if (s.clustered && recentre(sys, s, policy)) ++done.recentred;
    const Chart& chart = sys.chart();
    if (!s.framed()) s.enable_frames(ambient_dim_of(chart));
    // Every body on its own (it writes only its own q, p and frame), in chunks on threads: the
    // test is a pass over all the bodies at every step. (Whole counts: any order adds the same.)
    const int n = s.bodies();
    std::atomic<int> turned{0}, homed{0};
    parallel::for_chunks(n, parallel::chunks_for(n), [&](int begin, int end, int) {
      typename Chart::Point q(dim_of(chart)), p(dim_of(chart));
      typename Chart::Ambient x(ambient_dim_of(chart)), v(ambient_dim_of(chart));
      typename State<Chart>::Frame change(ambient_dim_of(chart), ambient_dim_of(chart));
      for (int b = begin; b < end; ++b) {
        q = s.q.col(b);
        p = s.p.col(b);
        const RechartAction action = chart.rechart_action(q, p, policy);
        if (action == RechartAction::none) continue;
        if (action == RechartAction::turn) {
          chart.turn(q, change);
          s.p.col(b) = -p;
          turned.fetch_add(1, std::memory_order_relaxed);
        } else {
          chart.embed(q, x);
          chart.velocity(q, p, sys.mass(b), v);
          // The change L is computed from the body's point in its current chart, where all
          // entries are moderate (the policy keeps it there), and composed: world = F L x_new. On
          // H^n this keeps every L well conditioned however far the body is from the world origin.
          chart.home(x, v, sys.mass(b), policy, change, q, p);
          s.q.col(b) = q;
          s.p.col(b) = p;
          homed.fetch_add(1, std::memory_order_relaxed);
        }
        auto& frame = s.frames[static_cast<std::size_t>(b)];
        frame = (frame * change).eval();
      }
    });
    done.turned = turned.load();
    done.homed = homed.load();
  }
  return done;
}

/// The same state in the identity frames (the space's own chart): q, p of each body recomputed
/// from its world point and velocity (the cotangent lift again, so the map is canonical), frames
/// dropped. For output in the scene's chart; a body on the chart's singular set gets the chart's
/// conventional angles there (EmbeddedChart::chart), and a re-charted body's angles are in the
/// chart's principal range (its winding is not recorded).
template <class Sys>
State<typename Sys::Chart> in_world_chart(const Sys& sys, const State<typename Sys::Chart>& s) {
  using Chart = typename Sys::Chart;
  using Scalar = typename Sys::Scalar;
  State<Chart> out(s.q.rows(), s.bodies());
  out.q = s.q;
  out.p = s.p;
  if constexpr (Rechartable<Chart>) {
    if (!s.framed() && !s.clustered) return out;
    const Chart& chart = sys.chart();
    // Body by body on threads: each writes its own columns.
    parallel::for_chunks(s.bodies(), parallel::chunks_for(s.bodies()), [&](int begin, int end, int) {
      typename Chart::Point q(dim_of(chart)), p(dim_of(chart));
      typename Chart::Ambient x(ambient_dim_of(chart)), v(ambient_dim_of(chart));
      typename State<Chart>::Frame frame(ambient_dim_of(chart), ambient_dim_of(chart));
      for (int b = begin; b < end; ++b) {
        // World = C F_b embed(q_b) (C: the cluster frame, if any). Far out this reading is as
        // ill-conditioned as the chart itself (docs/charts.md, "The cluster frame").
        if (s.framed()) {
          frame = s.frames[static_cast<std::size_t>(b)];
        } else {
          frame.setIdentity(ambient_dim_of(chart), ambient_dim_of(chart));
        }
        if (s.clustered) frame = (s.cluster * frame).eval();
        // A body never re-charted keeps its coordinates as they are (angles unwrapped).
        if (frame.isIdentity(Scalar(0))) continue;
        q = s.q.col(b);
        p = s.p.col(b);
        chart.embed(q, x);
        chart.velocity(q, p, sys.mass(b), v);
        x = (frame * x).eval();
        v = (frame * v).eval();
        chart.chart(x, q);
        chart.momentum(q, v, sys.mass(b), p);
        out.q.col(b) = q;
        out.p.col(b) = p;
      }
    });
  }
  return out;
}

/// A stepper that re-charts after every step: Method's step, then rechart().
template <class Method>
class Recharting : public Method {
 public:
  using typename Method::state_type;
  using typename Method::time_type;
  using Scalar = typename Method::value_type;

  Recharting() = default;
  /// The policy, then the method's own constructor arguments (e.g. a runtime table's weights).
  template <class... Args>
  explicit Recharting(RechartPolicy<Scalar> policy, Args&&... method_args)
      : Method(std::forward<Args>(method_args)...), policy_(policy) {}

  template <class Sys>
  void do_step(Sys&& system, state_type& x, time_type t, time_type dt) {
    Method::do_step(system, x, t, dt);
    using Raw = std::remove_cvref_t<Sys>;
    const Recharted done = rechart(detail::unwrap<Raw>::get(system), x, policy_);
    turns_ += done.turned;
    homes_ += done.homed;
  }

  const RechartPolicy<Scalar>& policy() const { return policy_; }
  /// Re-chartings done so far (turns and homings).
  long recharts() const { return turns_ + homes_; }
  /// Homings done so far (the re-chartings that change the modified energy; docs/charts.md).
  long homes() const { return homes_; }

 private:
  RechartPolicy<Scalar> policy_{};
  long turns_ = 0;
  long homes_ = 0;
};

/// The composition to re-chart with: Table's weights over the kick-drift-kick form, whose
/// chart-dependent second-order terms are purely kinetic, so that turns leave the modified
/// energy unchanged to that order (docs/charts.md; tests/stability/long.cpp).
template <class Table, class Chart>
using RechartingComposition = Recharting<Composition<Table, Chart, Splitting::kick_drift_kick>>;

}  // namespace sesi
