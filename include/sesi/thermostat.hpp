#pragma once
/// @file thermostat.hpp
/// Thermostats as a stage of the one composition engine (issue #25; docs/thermostats.md):
/// sesi::Thermostat<Chart> is the Stage of Composition<Table, Chart, kick_drift_kick, Stage>
/// (stepper.hpp), one runtime type for four kinds, so that a program instantiates one
/// thermostatted engine per chart. There is no second step loop: the engine places the hooks.
///
/// langevin: dq = dH/dp dt, dp = -dH/dq dt - gamma p dt + noise, whose invariant measure is the
/// canonical exp(-H / kT) dq dp, in the BAOAB arrangement (Leimkuhler and Matthews, "Rational
/// construction of stochastic numerical methods for molecular sampling", AMRX 2013(1), 34-56):
///   B  potential half kick, p -= h/2 dV/dq;
///   A  the kinetic flows K_1 .. K_n, each exact, for h/2;
///   O  the exact Ornstein-Uhlenbeck flow of the momenta for h (below);
///   A  the kinetic flows K_n .. K_1 for h/2 (the adjoint order, so the step is symmetric);
///   B  potential half kick.
/// The engine's kick-drift-kick Strang step with O (the per-body hook) between the two halves of
/// the top level's flow. With gamma = 0 no O runs and no number is drawn: the two half flows of
/// the top level fuse into one, and the step is the kick-drift-kick Strang step bit for bit
/// (also its reuse of the last gradient: one force evaluation per step).
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
/// brownian: the overdamped dynamics gamma m dq = F dt + sqrt(2 gamma m kT) dW as the BAOAB
/// limit (Leimkuhler and Matthews 2013; Leimkuhler, Matthews and Stoltz, IMA J. Numer. Anal. 36
/// (2016) 13-79): O with c = 0 (fresh momenta p_i = sqrt(kT / a_i) xi_i), and the engine's step
/// h = sqrt(2 dt / gamma) for a time step dt. Why: on E^n one step is
///   q' = q + h^2/(2m) F + (h/2) sqrt(kT/m) (xi_n + xi_{n-1}),
/// a drift h^2/(2m) F = dt F / (m gamma), and a noise whose increments telescope to
/// (h/2)^2 (kT/m) 4 = h^2 kT / m = 2 kT dt / (m gamma) per step: the overdamped law's variance
/// 2 kT / (m gamma) per unit time. Second order in the invariant measure (the papers above); the
/// momenta carry no dynamics, there is no conserved quantity (conserved_offset() is NaN).
///
/// nose_hoover: NHC(h/2) step NHC(h/2), the chain's half steps as the engine's outer hook, acting
/// on all momenta through the total kinetic energy (sesi/thermostats/nose_hoover.hpp); csvr: the
/// same place for Bussi's stochastic rescale (sesi/thermostats/csvr.hpp). Scaling every p by s is
/// exact on a hierarchical chart (K quadratic in p) and moves no q.
///
/// Heat: every stage's kinetic-energy change, summed in body order (per-body values into a buffer,
/// summed serially), so heat() is bit-identical for any thread count.
///
/// Order: weak order 2; the configurational averages have an O(h^2) bias in the invariant measure
/// (Leimkuhler and Matthews 2013). Here A is the hierarchical sweep, exact only to O(h^2) per
/// half step, so expect an O(h^2) configurational bias of the size of the NVE step's error.
///
/// Noise: random.hpp, keyed by (seed, random::stream::langevin, step, body, component), where
/// step is the thermostat's own step counter (step(), set_step(): a resumed run sets it, and
/// load() restores it). Bit-identical for any thread count.
///
/// Frames: O acts on chart momenta only and the kinetic energy has the same form in every body
/// frame (frames are isometries), so per-body frames and the cluster frame are handled as in the
/// engine; Recharting<Composition<..., Thermostat<Chart>>> re-charts after each step
/// (recharting.hpp). A turn (p -> -p) leaves the canonical measure invariant.
///
/// Requires Random123 (random.hpp).

#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <type_traits>
#include <utility>
#include <vector>

#include "sesi/chart.hpp"
#include "sesi/config.hpp"
#include "sesi/random.hpp"
#include "sesi/state.hpp"
#include "sesi/stepper.hpp"
#include "sesi/system.hpp"
#include "sesi/thermostats/csvr.hpp"
#include "sesi/thermostats/nose_hoover.hpp"

namespace sesi {

enum class ThermostatKind { langevin, nose_hoover, csvr, brownian };

/// A thermostat's settings (docs/thermostats.md).
template <class Scalar>
struct ThermostatParams {
  ThermostatKind kind = ThermostatKind::langevin;
  Scalar kT = 0;           ///< temperature in energy units (k_B = 1), >= 0
  Scalar gamma = 0;        ///< langevin, brownian: friction (1/time); langevin gamma = 0 is NVE bit for bit
  Scalar tau = 0;          ///< nose_hoover, csvr: relaxation time (> 0)
  int chain = 3;           ///< nose_hoover: chain length M >= 1
  std::uint64_t seed = 0;  ///< langevin, csvr, brownian: the noise's key
};

/// A thermostat as a stage of the composition engine (stepper.hpp): one runtime type for every kind.
template <HierarchicalChart Chart>
class Thermostat {
 public:
  using Scalar = typename Chart::Scalar;

  explicit Thermostat(ThermostatParams<Scalar> params) : params_(params) {
    check_temperature(params.kT);
    switch (params.kind) {
      case ThermostatKind::langevin:
        SESI_CHECK(params.gamma >= Scalar(0), "Langevin: the friction must be >= 0");
        break;
      case ThermostatKind::brownian:
        SESI_CHECK(params.gamma > Scalar(0), "Brownian dynamics: the friction must be > 0");
        break;
      case ThermostatKind::nose_hoover:
        SESI_CHECK(params.tau > Scalar(0), "Nose-Hoover: the relaxation time tau must be > 0");
        SESI_CHECK(params.chain >= 1, "Nose-Hoover: the chain length must be >= 1");
        chain_.emplace(params.chain, params.tau);
        break;
      case ThermostatKind::csvr:
        SESI_CHECK(params.tau > Scalar(0), "CSVR: the relaxation time tau must be > 0");
        break;
    }
  }

  const ThermostatParams<Scalar>& params() const { return params_; }
  ThermostatKind kind() const { return params_.kind; }
  /// A new temperature from the next step on (a schedule).
  void set_temperature(Scalar kT) {
    check_temperature(kT);
    params_.kT = kT;
  }
  /// A domain of a simulation across processes (System::set_domain): body b's noise is keyed by
  /// keys[b], its index in the whole simulation, so that each body draws the numbers it draws in
  /// one process (empty, the default: b).
  void set_body_keys(std::vector<std::uint64_t> keys) { keys_ = std::move(keys); }
  /// The noise's step key: steps done since the start (incremented by every step).
  std::uint64_t step() const { return step_; }
  void set_step(std::uint64_t k) { step_ = k; }
  /// Energy the thermostat's stages put into the system so far.
  Scalar heat() const { return heat_; }
  /// H + conserved_offset() is conserved up to the integrator's error (api: nose_hoover the chain's
  /// extended energy; langevin, csvr -heat(), Bussi's effective energy; brownian NaN).
  Scalar conserved_offset() const {
    switch (params_.kind) {
      case ThermostatKind::nose_hoover:
        return chain_->extended_energy(nf_, params_.kT);
      case ThermostatKind::brownian:
        return std::numeric_limits<Scalar>::quiet_NaN();
      default:
        return -heat_;
    }
  }

  /// Everything besides the params that a checkpoint must hold to resume bit for bit, as exact
  /// doubles: {step, heat, kT (set_temperature's), N_f, the chain's state...}.
  std::vector<double> save() const {
    std::vector<double> out{static_cast<double>(step_), static_cast<double>(heat_), static_cast<double>(params_.kT),
                            static_cast<double>(nf_)};
    if (chain_) {
      for (const auto v : chain_->save()) out.push_back(static_cast<double>(v));
    }
    return out;
  }
  void load(const std::vector<double>& saved) {
    SESI_CHECK(saved.size() >= 4, "thermostat: a saved state holds at least step, heat, kT and N_f");
    SESI_CHECK(saved[0] >= 0 && saved[0] == std::floor(saved[0]), "thermostat: the saved step must be a count");
    step_ = static_cast<std::uint64_t>(saved[0]);
    heat_ = static_cast<Scalar>(saved[1]);
    set_temperature(static_cast<Scalar>(saved[2]));
    nf_ = static_cast<Scalar>(saved[3]);
    nf_counted_ = false;
    if (chain_) {
      using Saved = std::remove_cvref_t<decltype(chain_->save())>;
      Saved rest;
      for (std::size_t i = 4; i < saved.size(); ++i) rest.push_back(static_cast<typename Saved::value_type>(saved[i]));
      chain_->load(rest);
    }
  }

  // ---- the engine's hooks (stepper.hpp) ----

  /// The engine's step h for a time step dt: dt, or for Brownian dynamics sqrt(2 dt / gamma) (the
  /// mapping in the file's comment).
  Scalar time_step(Scalar dt) const {
    using std::sqrt;
    return params_.kind == ThermostatKind::brownian ? sqrt(Scalar(2) * dt / params_.gamma) : dt;
  }
  bool acts_on_total() const {
    return params_.kind == ThermostatKind::nose_hoover || params_.kind == ThermostatKind::csvr;
  }
  bool acts_on_bodies() const {
    return params_.kind == ThermostatKind::brownian ||
           (params_.kind == ThermostatKind::langevin && params_.gamma != Scalar(0));
  }

  /// The outer hook for time h (which = 0 at the step's start, 1 at its end): the total kinetic
  /// energy K (per body into a buffer, summed in body order: System::sum_rows, a domain's over
  /// the whole simulation), the kind's factor s, p <- s p.
  template <class Sys, class Workspace>
  void total(const Sys& sys, State<Chart>& x, Workspace& ws, Scalar h, int which) {
    const int n = sys.bodies();
    if (!nf_counted_) {
      // N_f = N n over the whole simulation: a sum of n a body (exact in Scalar), once.
      buffer_.assign(static_cast<std::size_t>(n), static_cast<Scalar>(sys.dim()));
      nf_ = sys.sum_rows(buffer_);
      nf_counted_ = true;
    }
    buffer_.resize(static_cast<std::size_t>(n));
    sys.for_bodies(ws, [&](int b, auto& sc) {
      sc.q = x.q.col(b);
      sc.p = x.p.col(b);
      buffer_[static_cast<std::size_t>(b)] = sesi::kinetic_energy(sys.chart(), sc.q, sc.p, sys.mass(b));
    });
    const Scalar K = sys.sum_rows(buffer_);
    Scalar s(1);
    if (params_.kind == ThermostatKind::nose_hoover) {
      s = chain_->advance(K, nf_, params_.kT, h);
    } else {
      s = thermostats::csvr_factor<Scalar>(K, nf_, params_.kT, h, params_.tau, params_.seed, step_,
                                           static_cast<std::uint64_t>(which));
    }
    x.p *= s;
    heat_ += (s * s - Scalar(1)) * K;  // K -> s^2 K (K quadratic in p)
  }

  /// The per-body hook: prepare O for a step h on n bodies.
  void begin_bodies(int n, Scalar h) {
    using std::exp;
    using std::expm1;
    if (params_.kind == ThermostatKind::brownian) {
      c_ = Scalar(0);  // the overdamped limit: fresh momenta
      var_ = params_.kT;
    } else {
      c_ = exp(-params_.gamma * h);
      var_ = -expm1(Scalar(-2) * params_.gamma * h) * params_.kT;  // (1 - c^2) kT
    }
    buffer_.resize(static_cast<std::size_t>(n));
  }
  /// O on body b: p_i <- c p_i + sqrt(var / a_i) xi_i, a_i = dK_i/dp_i at p_i = 1 (= g^ii / m);
  /// its kinetic-energy change sum_i a_i (p_i'^2 - p_i^2) / 2 into the buffer. One Philox call
  /// per two components; writes only body b's data (threads).
  template <class Q, class P>
  void body(const Chart& chart, int b, Scalar m, const Q& q, P& p) {
    using std::sqrt;
    const int n = static_cast<int>(p.size());
    Scalar dk(0);
    for (int i = 0; i < n; i += 2) {
      const std::uint64_t key = keys_.empty() ? static_cast<std::uint64_t>(b) : keys_[static_cast<std::size_t>(b)];
      const auto z = random::normal_pair(params_.seed, random::stream::langevin, step_, key, static_cast<std::uint64_t>(i / 2));
      for (int j = i; j < n && j < i + 2; ++j) {
        const Scalar a = chart.kinetic_dp(j, q, Scalar(1), m);
        const Scalar old = p[j];
        p[j] = c_ * p[j] + sqrt(var_ / a) * static_cast<Scalar>(z[static_cast<std::size_t>(j - i)]);
        const Scalar d = p[j] * p[j] - old * old;
        if (d != Scalar(0)) dk += a * d / Scalar(2);
      }
    }
    buffer_[static_cast<std::size_t>(b)] = dk;
  }
  /// After the pass: the heat of O, summed in body order (System::sum_rows).
  template <class Sys>
  void end_bodies(const Sys& sys) {
    heat_ += sys.sum_rows(buffer_);
  }
  void end_step() { ++step_; }

 private:
  static void check_temperature([[maybe_unused]] Scalar kT) {
    SESI_CHECK(kT >= Scalar(0), "thermostat: the temperature must be >= 0");
  }

  ThermostatParams<Scalar> params_;
  std::uint64_t step_ = 0;
  Scalar heat_ = 0;
  Scalar nf_ = 0;  // N_f = bodies x dim, from the first outer hook (for the chain's extended energy)
  bool nf_counted_ = false;  // (counted by every process of a domain alike: a collective sum)
  std::vector<std::uint64_t> keys_;  // a domain's bodies' noise keys (set_body_keys)
  Scalar c_ = 1, var_ = 0;  // this step's O: c = exp(-gamma h), var = (1 - c^2) kT
  std::vector<Scalar> buffer_;  // per-body kinetic energies or heats, summed in body order
  std::optional<thermostats::NoseHooverChain<Scalar>> chain_;
};

/// The thermostatted engine: the kick-drift-kick Strang step with the thermostat's stages.
template <HierarchicalChart Chart>
using Thermostatted = Composition<coefficients::Strang, Chart, Splitting::kick_drift_kick, Thermostat<Chart>>;

/// Langevin dynamics at temperature kT (energy units) with friction gamma (1/time), BAOAB: a
/// Thermostatted<Chart> with a langevin Thermostat. order() is the weak order, 2.
template <HierarchicalChart Chart>
class LangevinBAOAB : public Thermostatted<Chart> {
  using Base = Thermostatted<Chart>;

 public:
  using Scalar = typename Chart::Scalar;

  /// kT >= 0, gamma >= 0; seed: the noise's key; first_step: the step counter's start (a
  /// resumed run passes the number of steps done).
  LangevinBAOAB(Scalar kT, Scalar gamma, std::uint64_t seed, std::uint64_t first_step = 0)
      : Base(Thermostat<Chart>(ThermostatParams<Scalar>{ThermostatKind::langevin, kT, gamma, Scalar(0), 3, seed})) {
    this->stage().set_step(first_step);
  }

  Scalar temperature() const { return this->stage().params().kT; }
  Scalar friction() const { return this->stage().params().gamma; }
  std::uint64_t seed() const { return this->stage().params().seed; }
  /// The step counter: the key of the next step's noise (incremented by every do_step).
  std::uint64_t step() const { return this->stage().step(); }
  void set_step(std::uint64_t k) { this->stage().set_step(k); }
  /// A new temperature from the next step on (a schedule).
  void set_temperature(Scalar kT) { this->stage().set_temperature(kT); }
};

}  // namespace sesi
