#pragma once
/// @file recharting.hpp
/// Pole-safe and far-safe charts (issue #5; docs/charts.md). Each body may carry its own chart
/// frame F (an isometry of the ambient space: orthogonal on S^n, Lorentz on H^n), with
/// world point x = F embed(q). Between steps, a body that comes within a threshold of its
/// chart's singular set (or, on H^n, too far from its chart's origin) is re-charted: it gets a
/// frame in which it sits where the chart is best conditioned, moving along a well-conditioned
/// direction, and (q, p) are transformed by the cotangent lift of the chart change, which is
/// canonical, so the method stays symplectic and explicit. Potentials see world points only.

#include <cmath>
#include <cstddef>
#include <functional>
#include <type_traits>
#include <utility>

#include <Eigen/Core>

#include "sesi/chart.hpp"
#include "sesi/state.hpp"
#include "sesi/stepper.hpp"

namespace sesi {

/// When and where to re-chart (defaults documented in docs/charts.md).
template <class Scalar>
struct RechartPolicy {
  /// Re-chart when a polar angle's |sin q_k| falls below this (S^n, n >= 2; angles of H^n).
  /// 1/4 keeps the chart's 1/sin^2 factors below 16.
  Scalar min_sine = Scalar(1) / Scalar(4);
  /// H^n, n >= 2: re-chart when the radius q_1 falls below this (the polar origin is singular).
  Scalar min_radius = Scalar(1) / Scalar(4);
  /// H^n: re-chart when the radius exceeds this (sinh and cosh grow like e^{q_1}).
  Scalar max_radius = Scalar(3);
  /// H^n, n >= 2: the radius at which a re-charted body is placed, moving tangentially, so that
  /// its geodesic's closest approach to the new origin is this radius.
  Scalar home_radius = Scalar(1);
};

/// Charts that know their singular set and how to re-chart a body (built-in S^n and H^n).
template <class C>
concept Rechartable =
    EmbeddedChart<C> &&
    requires(const C& c, const typename C::Point& q, typename C::Point& qo, typename C::Point& po,
             const typename C::Ambient& x, const RechartPolicy<typename C::Scalar>& policy,
             typename State<C>::Frame& frame, typename C::Scalar m) {
      { c.needs_rechart(q, policy) } -> std::convertible_to<bool>;
      c.home(x, x, m, policy, frame, qo, po);  // frame <- the chart change L (see below)
    };

/// Re-chart every body of s that needs it under policy; returns how many were re-charted.
/// The first call gives s identity frames.
template <class Sys>
int rechart(const Sys& sys, State<typename Sys::Chart>& s,
            const RechartPolicy<typename Sys::Scalar>& policy) {
  using Chart = typename Sys::Chart;
  if constexpr (!Rechartable<Chart>) {
    return 0;
  } else {
    const Chart& chart = sys.chart();
    if (!s.framed()) s.enable_frames(chart.ambient_dim());
    typename Chart::Point q(chart.dim()), p(chart.dim());
    typename Chart::Ambient x(chart.ambient_dim()), v(chart.ambient_dim());
    int count = 0;
    for (int b = 0; b < s.bodies(); ++b) {
      q = s.q.col(b);
      if (!chart.needs_rechart(q, policy)) continue;
      p = s.p.col(b);
      chart.embed(q, x);
      chart.velocity(q, p, sys.mass(b), v);
      // The change L is computed from the body's point in its current chart, where all entries
      // are moderate (the policy keeps it there), and composed: world = F L x_new. On H^n this
      // keeps every L well conditioned however far the body is from the world origin.
      typename State<Chart>::Frame change(chart.ambient_dim(), chart.ambient_dim());
      chart.home(x, v, sys.mass(b), policy, change, q, p);
      auto& frame = s.frames[static_cast<std::size_t>(b)];
      frame = (frame * change).eval();
      s.q.col(b) = q;
      s.p.col(b) = p;
      ++count;
    }
    return count;
  }
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
    if (!s.framed()) return out;
    const Chart& chart = sys.chart();
    typename Chart::Point q(chart.dim()), p(chart.dim());
    typename Chart::Ambient x(chart.ambient_dim()), v(chart.ambient_dim());
    for (int b = 0; b < s.bodies(); ++b) {
      const auto& frame = s.frames[static_cast<std::size_t>(b)];
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
    recharts_ += rechart(detail::unwrap<Raw>::get(system), x, policy_);
  }

  const RechartPolicy<Scalar>& policy() const { return policy_; }
  /// Re-chartings done so far.
  long recharts() const { return recharts_; }

 private:
  RechartPolicy<Scalar> policy_{};
  long recharts_ = 0;
};

}  // namespace sesi
