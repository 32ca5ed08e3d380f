#pragma once
/// @file thermostat.hpp
/// Langevin dynamics in the BAOAB arrangement over the hierarchical splitting (issue #25;
/// docs/thermostats.md).
///
/// dq = dH/dp dt, dp = -dH/dq dt - gamma p dt + noise, whose invariant measure is the canonical
/// one, exp(-H / kT) dq dp. One step of length h (Leimkuhler and Matthews, "Rational
/// construction of stochastic numerical methods for molecular sampling", AMRX 2013(1), 34-56):
///   B  potential half kick, p -= h/2 dV/dq;
///   A  the kinetic flows K_1 .. K_n, each exact, for h/2;
///   O  the exact Ornstein-Uhlenbeck flow of the momenta for h (below);
///   A  the kinetic flows K_n .. K_1 for h/2 (the adjoint order, so the step is symmetric);
///   B  potential half kick.
/// B and the level flows are the very functions the composition engine (stepper.hpp) calls:
/// System::kick_cached and the chart's level_flow, with the same trig caches; the step is the
/// engine's kick-drift-kick Strang step with O inserted between the two halves of the top level's
/// flow. With gamma = 0 no O runs and no number is drawn: the two half flows of the top level
/// fuse into one, as in the engine, and the step equals Composition<coefficients::Strang, Chart,
/// Splitting::kick_drift_kick> bit for bit (also its reuse of the last gradient: one force
/// evaluation per step). It is that KDK form, not the seed's drift-kick-drift Sesi2, that BAOAB
/// reduces to.
///
/// O. On a hierarchical chart K = sum_i a_i(q_<i) p_i^2 / 2 with a_i = g^ii / m (a diagonal
/// inverse metric), so given q the canonical momenta are independent normals, p_i ~ N(0, kT / a_i),
/// and the Ornstein-Uhlenbeck flow dp_i = -gamma p_i dt + sqrt(2 gamma kT / a_i) dW (q fixed) is
/// exact: p_i <- c p_i + sqrt((1 - c^2) kT / a_i) xi_i, c = exp(-gamma h), xi_i standard normal
/// (1 - c^2 = -expm1(-2 gamma h), without cancellation). a_i is read from the chart as
/// dK_i/dp_i at p_i = 1 (kinetic_dp(i, q, 1, m)), the inverse metric the level flows use: a user
/// chart needs nothing more, but its K_i must be quadratic in p_i (docs/concepts.md). Where a_i is
/// infinite (a body exactly at a chart pole) the noise of that component is 0.
///
/// Order: weak order 2; the configurational averages have an O(h^2) bias in the invariant measure
/// (Leimkuhler and Matthews 2013; for a harmonic well with one exact A flow BAOAB samples the
/// configuration exactly). Here A is the hierarchical sweep, exact only to O(h^2) per half step,
/// so expect an O(h^2) configurational bias of the size of the NVE step's energy error.
///
/// Noise: random.hpp, keyed by (seed, random::stream::langevin, step, body, component), where
/// step is the stepper's own step counter (step(), set_step(): a resumed run sets it, and nothing
/// else random is kept). Bit-identical for any thread count.
///
/// Frames: O acts on chart momenta only and the kinetic energy has the same form in every body
/// frame (frames are isometries), so per-body frames and the cluster frame are handled as in the
/// engine (the kicks see world points); Recharting<LangevinBAOAB<Chart>> re-charts after each
/// step (recharting.hpp). A turn (p -> -p) leaves the canonical measure invariant.
///
/// Requires Random123 (random.hpp).

#include <cmath>
#include <cstdint>
#include <type_traits>
#include <vector>

#include "sesi/chart.hpp"
#include "sesi/config.hpp"
#include "sesi/random.hpp"
#include "sesi/state.hpp"
#include "sesi/stepper.hpp"
#include "sesi/system.hpp"

namespace sesi {

/// Langevin dynamics at temperature kT (energy units) with friction gamma (1/time), BAOAB.
/// Models odeint's Stepper concept like the compositions (order() is the weak order, 2).
template <HierarchicalChart Chart>
class LangevinBAOAB {
 public:
  using Scalar = typename Chart::Scalar;
  using state_type = State<Chart>;
  using deriv_type = State<Chart>;
  using value_type = Scalar;
  using time_type = Scalar;
  using order_type = unsigned short;
  static constexpr order_type order_value = 2;

  /// kT >= 0, gamma >= 0; seed: the noise's key; first_step: the step counter's start (a
  /// resumed run passes the number of steps done).
  LangevinBAOAB(Scalar kT, Scalar gamma, std::uint64_t seed, std::uint64_t first_step = 0)
      : kT_(kT), gamma_(gamma), seed_(seed), step_(first_step) {
    SESI_CHECK(kT >= Scalar(0), "Langevin: the temperature must be >= 0");
    SESI_CHECK(gamma >= Scalar(0), "Langevin: the friction must be >= 0");
  }

  order_type order() const { return order_value; }
  Scalar temperature() const { return kT_; }
  Scalar friction() const { return gamma_; }
  std::uint64_t seed() const { return seed_; }
  /// The step counter: the key of the next step's noise (incremented by every do_step).
  std::uint64_t step() const { return step_; }
  void set_step(std::uint64_t k) { step_ = k; }
  /// A new temperature from the next step on (a schedule).
  void set_temperature(Scalar kT) {
    SESI_CHECK(kT >= Scalar(0), "Langevin: the temperature must be >= 0");
    kT_ = kT;
  }

  /// Advance x from t to t + dt in place: one BAOAB step.
  template <class Sys>
  void do_step(Sys&& system, state_type& x, time_type /*t*/, time_type dt) {
    using Raw = std::remove_cvref_t<Sys>;
    const auto& sys = detail::unwrap<Raw>::get(system);
    // As Composition::do_step: the trig caches left by the last step are valid if q is unchanged.
    const bool q_unchanged =
        last_q_.cols() == x.q.cols() && last_q_.rows() == x.q.rows() && last_q_ == x.q;
    if (!q_unchanged) sys.refresh(x, ws_);
    const bool reuse = kept_.valid(sys, x, q_unchanged);
    const Scalar half = dt / Scalar(2);
    // B: the first half kick is at the point of the last step's last kick (O moves no q).
    if (reuse) {
      x.p.noalias() -= half * kept_.gradient();
    } else {
      sys.kick_cached(x, half, ws_, kept_.gradient());
    }
    // A O A, body by body (each body's flows and noise touch only its own data).
    const int top = sys.dim() - 1;
    const bool thermal = gamma_ != Scalar(0);
    using std::exp;
    using std::expm1;
    const Scalar c = thermal ? exp(-gamma_ * dt) : Scalar(1);
    const Scalar var = thermal ? -expm1(Scalar(-2) * gamma_ * dt) * kT_ : Scalar(0);  // (1 - c^2) kT
    sys.for_bodies(ws_, [&](int b, auto& sc) {
      const Scalar m = sys.mass(b);
      sc.q = x.q.col(b);
      sc.p = x.p.col(b);
      if (!thermal) {  // the engine's kinetic part: K_1(h/2)..K_{n-1}(h/2) K_n(h) K_{n-1}(h/2)..K_1(h/2)
        for (int i = 0; i < top; ++i) flow(sys.chart(), b, i, m, half, sc);
        flow(sys.chart(), b, top, m, dt, sc);
        for (int i = top - 1; i >= 0; --i) flow(sys.chart(), b, i, m, half, sc);
      } else {
        for (int i = 0; i <= top; ++i) flow(sys.chart(), b, i, m, half, sc);
        ornstein_uhlenbeck(sys.chart(), b, m, c, var, sc);
        for (int i = top; i >= 0; --i) flow(sys.chart(), b, i, m, half, sc);
      }
      x.q.col(b) = sc.q;
      x.p.col(b) = sc.p;
    });
    // B.
    sys.kick_cached(x, half, ws_, kept_.gradient());
    kept_.keep(sys, x);
    last_q_ = x.q;
    ++step_;
  }

  /// Forget the trig caches and the last gradient (as Composition::reset); the step counter stays.
  void reset() {
    last_q_.resize(0, 0);
    kept_.forget();
  }

 private:
  /// The exact flow of level i for time h on body b: the chart's level_flow, as the engine calls it.
  template <class Scratch>
  void flow(const Chart& chart, int b, int i, Scalar m, Scalar h, Scratch& sc) {
    detail::cached_level_flow(chart, ws_, b, i, m, h, sc);
  }
  /// O on body b: p_i <- c p_i + sqrt(var / a_i) xi_i, a_i = dK_i/dp_i at p_i = 1 (= g^ii / m).
  template <class Scratch>
  void ornstein_uhlenbeck(const Chart& chart, int b, Scalar m, Scalar c, Scalar var, Scratch& sc) const {
    using std::sqrt;
    const int n = static_cast<int>(sc.p.size());
    for (int i = 0; i < n; i += 2) {
      const auto z = random::normal_pair(seed_, random::stream::langevin, step_,
                                         static_cast<std::uint64_t>(b), static_cast<std::uint64_t>(i / 2));
      for (int j = i; j < n && j < i + 2; ++j) {
        const Scalar a = chart.kinetic_dp(j, sc.q, Scalar(1), m);
        sc.p[j] = c * sc.p[j] + sqrt(var / a) * static_cast<Scalar>(z[static_cast<std::size_t>(j - i)]);
      }
    }
  }

  Scalar kT_;
  Scalar gamma_;
  std::uint64_t seed_;
  std::uint64_t step_;
  Workspace<Chart> ws_;
  typename state_type::Matrix last_q_;  // q after the last step: its trig is in ws_
  detail::KeptGradient<Chart> kept_;    // dV/dq at last_q_ (the last kick's), reused by the next
};

}  // namespace sesi
