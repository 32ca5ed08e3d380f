// Nose-Hoover chains (include/sesi/thermostats/nose_hoover.hpp) alone and as the stage of the
// thermostatted engine (sesi::Thermostatted, thermostat.hpp); issue #25, docs/thermostats.md.
//
//  - the chain's propagator is time reversible: advance(-h) undoes advance(h) to round-off;
//  - the chain's part alone (q fixed) conserves K + extended_energy() to the order of its
//    Suzuki-Yoshida composition (4);
//  - with the dynamics, H + extended_energy() stays bounded over many periods with an error
//    that falls as dt^2 (the thermostatted Strang step is second order);
//  - the mean kinetic temperature of 500 bodies in wells on S^2 is kT within its statistical bound.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include <doctest/doctest.h>

#include "common.hpp"

#include <sesi/thermostat.hpp>
#include <sesi/thermostats/nose_hoover.hpp>

namespace {

using namespace coretest;
using S2 = sesi::Sphere<2, double>;

// ---- the chain alone --------------------------------------------------------------------------

template <class Scalar>
void check_reversible(int chain, int substeps) {
  sesi::thermostats::NoseHooverChain<Scalar> nhc(chain, Scalar(0.4), substeps);
  // A chain away from rest: xi_j = 0.1 j (0-based), v_j = (0.7 or -1.1) / (tau (j + 1)).
  std::vector<Scalar> start(static_cast<std::size_t>(2 * chain));
  for (int j = 0; j < chain; ++j) {
    start[static_cast<std::size_t>(j)] = Scalar(0.1) * Scalar(j);
    start[static_cast<std::size_t>(chain + j)] = Scalar(j % 2 == 0 ? 0.7 : -1.1) / Scalar(0.4) / Scalar(j + 1);
  }
  nhc.load(start);
  const Scalar K(3.7), Nf(10), kT(1.3), h(0.05);
  const Scalar s = nhc.advance(K, Nf, kT, h);
  CHECK(s != Scalar(1));
  CHECK(nhc.save() != start);  // it moved
  const Scalar back = nhc.advance(s * s * K, Nf, kT, -h);
  // Round-off only: the propagator is a palindrome of exact sub-flows, each undone by its
  // negative-time twin; about 3 weights x (4 M + 4) operations per sub-step, each with a
  // relative error eps on O(1) numbers (|v_j| tau, |xi_j|, K/kT below 3), amplified at most by
  // the exp(|delta v|) < 1.2 factors: 256 eps covers (3 x 16 x n_c ops) x 1.2^2 for M, n_c <= 4.
  const Scalar tol = Scalar(256) * eps<Scalar>();
  CHECK(std::abs(static_cast<double>(s * back - Scalar(1))) < static_cast<double>(tol));
  const auto end = nhc.save();
  for (std::size_t i = 0; i < end.size(); ++i) {
    INFO("chain ", chain, ", entry ", i);
    CHECK(std::abs(static_cast<double>(end[i] - start[i])) < static_cast<double>(tol * Scalar(10)));
  }
}

TEST_CASE("nose-hoover: advance(-h) undoes advance(h) to round-off (M = 1, 3, 4; n_c = 1, 4)") {
  // The entries are O(10) at most (v_j up to 1.1 / 0.4 = 2.75 scaled by 1 / (j + 1)): tol x 10.
  check_reversible<double>(1, 1);
  check_reversible<double>(3, 1);
  check_reversible<double>(4, 4);
  check_reversible<long double>(3, 1);
  check_reversible<float>(3, 1);
}

/// K + extended energy after the chain alone ran for time T = 2 in steps of h (q fixed: only K,
/// the chain's positions and velocities move), minus its start.
double chain_alone_error(double h) {
  sesi::thermostats::NoseHooverChain<double> nhc(3, 0.5);
  nhc.load({0.0, 0.0, 0.0, 0.9, -0.6, 0.4});
  const double Nf = 12, kT = 0.8;
  double K = Nf * kT;  // twice K_bar: the chain pulls K down
  const double e0 = K + nhc.extended_energy(Nf, kT);
  const int n = static_cast<int>(std::lround(2.0 / h));
  for (int k = 0; k < n; ++k) {
    const double s = nhc.advance(K, Nf, kT, h);
    K *= s * s;
  }
  CHECK(std::abs(K - Nf * kT) > 0.1 * K);  // the chain did act
  return K + nhc.extended_energy(Nf, kT) - e0;
}

TEST_CASE("nose-hoover: the chain alone conserves K + extended energy to its order, 4") {
  // With q fixed the chain's equations (and K' = -2 v_1 K) conserve K + extended_energy exactly
  // (Martyna, Klein and Tuckerman 1992); the Yoshida triple jump of the symmetric
  // step is of order 4, so over a fixed time the error is C h^4 (1 + O((v h)^2)): halving h
  // divides it by 16. At h = 0.05 the largest |v_j| h is 0.17, (v h)^2 = 0.03, so with a
  // constant of a few the correction is within 25 %: ratio in [12, 20] (measured 15.5; at
  // h = 0.1, 0.05 it is 14.0, and 15.1 at twice the heat: the asymptotic regime).
  const double e1 = chain_alone_error(0.05), e2 = chain_alone_error(0.025);
  MESSAGE("chain alone: error ", e1, " at h = 0.05, ", e2, " at h = 0.025, ratio ", e1 / e2);
  CHECK(std::abs(e1) > 1e-12);  // above round-off (the ratio means something)
  CHECK(std::abs(e1 / e2) > 12.0);
  CHECK(std::abs(e1 / e2) < 20.0);
}

TEST_CASE("nose-hoover: save and load give back the chain bit for bit") {
  sesi::thermostats::NoseHooverChain<double> a(3, 0.3), b(3, 0.3);
  double K = 5.0;
  for (int k = 0; k < 7; ++k) {
    const double s = a.advance(K, 8.0, 1.0, 0.01);
    K *= s * s;
  }
  b.load(a.save());
  CHECK(b.save() == a.save());
  CHECK(a.advance(K, 8.0, 1.0, 0.01) == b.advance(K, 8.0, 1.0, 0.01));
  CHECK(a.extended_energy(8.0, 1.0) == b.extended_energy(8.0, 1.0));
}

// ---- with the dynamics: bodies in a well on S^2 ------------------------------------------------

// n bodies of unit mass on the unit S^2 in the well V = m k/2 |x - c|^2 = m k (1 - cos a) about
// the equator point c = embed(pi/2, 0) (frequency sqrt(k) near c). k = 20 at kT <= 1.5: reaching
// within 0.1 rad of a chart pole (1.47 rad from c) costs V = 18 m: Boltzmann factor e^-12 per body
// and sample, so no body comes near the chart's singular points and no re-charting is needed.
struct Wells {
  S2 chart{1.0};
  sesi::System<S2, Trap<S2>> sys;
  explicit Wells(int n, double k)
      : sys(chart, std::vector<double>(static_cast<std::size_t>(n), 1.0), Trap<S2>{k, equator(chart)}) {}
  static S2::Ambient equator(const S2& chart) {
    S2::Point q(2);
    q << std::numbers::pi / 2, 0.0;
    S2::Ambient c(3);
    chart.embed(q, c);
    return c;
  }
  /// Bodies within 0.3 rad of the centre with normal momenta of variance kT0 (a fixed seed).
  sesi::State<S2> start(double kT0, std::uint32_t seed) const {
    const int n = sys.bodies();
    sesi::State<S2> x(2, n);
    std::mt19937 rng(seed);
    std::normal_distribution<double> z(0.0, 1.0);
    for (int b = 0; b < n; ++b)
      x.set_body(b, {std::numbers::pi / 2 + 0.15 * z(rng), 0.15 * z(rng)},
                 {std::sqrt(kT0) * z(rng), std::sqrt(kT0) * z(rng)});
    return x;
  }
};

sesi::Thermostat<S2> nose_hoover(double kT, double tau, int chain) {
  sesi::ThermostatParams<double> p;
  p.kind = sesi::ThermostatKind::nose_hoover;
  p.kT = kT;
  p.tau = tau;
  p.chain = chain;
  return sesi::Thermostat<S2>(p);
}

struct ConservedRun {
  double max_error;   // max_t |E(t) - E(0)| / (K0 + |V0|), E = H + extended energy
  double late_error;  // the same over the run's last quarter, about the first quarter's mean
  double kinetic_temperature;
};

/// n bodies, kT = 1, tau = 0.5, M = 3, for time T at step dt from a hot start (kT0 = 2).
ConservedRun conserved_run(double dt, double T) {
  const Wells w(50, 20.0);
  auto x = w.start(2.0, 17);
  if (T < 0) {  // the NVE step from the same start for time -T: its own largest error
    sesi::Composition<sesi::coefficients::Strang, S2, sesi::Splitting::kick_drift_kick> plain;
    const double scale = w.sys.kinetic_energy(x) + std::abs(w.sys.potential_energy(x)), e0 = w.sys.energy(x);
    ConservedRun r{0, 0, 0};
    for (int k = 0; k < static_cast<int>(std::lround(-T / dt)); ++k) {
      plain.do_step(w.sys, x, k * dt, dt);
      r.max_error = std::max(r.max_error, std::abs(w.sys.energy(x) - e0) / scale);
    }
    return r;
  }
  sesi::Thermostatted<S2> stepper(nose_hoover(1.0, 0.5, 3));
  const double scale = w.sys.kinetic_energy(x) + std::abs(w.sys.potential_energy(x));
  const auto conserved = [&] { return w.sys.energy(x) + stepper.stage().conserved_offset(); };
  const double e0 = conserved();  // the chain starts at rest at xi = 0: its extended energy is 0
  const int n = static_cast<int>(std::lround(T / dt));
  ConservedRun r{0, 0, 0};
  double first_quarter = 0;
  int first_count = 0;
  std::vector<double> late;
  for (int k = 0; k < n; ++k) {
    stepper.do_step(w.sys, x, k * dt, dt);
    const double e = (conserved() - e0) / scale;
    r.max_error = std::max(r.max_error, std::abs(e));
    if (4 * k < n) {
      first_quarter += e;
      ++first_count;
    }
    if (4 * k >= 3 * n) late.push_back(e);
  }
  first_quarter /= first_count;
  for (const double e : late) r.late_error = std::max(r.late_error, std::abs(e - first_quarter));
  r.kinetic_temperature = 2 * w.sys.kinetic_energy(x) / (2.0 * w.sys.bodies());
  return r;
}

TEST_CASE("nose-hoover: H + extended energy stays bounded over 30 periods, error O(dt^2)") {
  // 50 bodies (N_f = 100), omega = sqrt(20) = 4.5 (period 1.4), tau = 0.5, T = 40: about 30
  // periods and 80 thermostat times, from a start at twice the temperature (the chain moves
  // heat). NHC(h/2) Strang NHC(h/2) is symmetric and second order (Martyna et al. 1996), so the
  // conserved quantity's error is C dt^2 (1 + O(dt^2)) with no drift: halving dt divides the
  // largest error over the run by 4; at omega dt <= 0.09 the O(dt^2) correction is below 1 %,
  // and the largest error is read on two trajectories that part (chaos through the shared
  // chain), a sample maximum of a bounded fluctuation: allow a factor 1.5 either way, [2.7, 6].
  // And its size is the NVE step's: within a factor 3 of the NVE run's largest error from the
  // same start at the same dt (the same modified-energy correction; the chain cools the system;
  // measured 0.89: 1.08e-3 against 1.21e-3).
  const double T = 40;
  const ConservedRun a = conserved_run(0.02, T), b = conserved_run(0.01, T), plain = conserved_run(0.02, -T);
  MESSAGE("nose-hoover conserved quantity: max relative error ", a.max_error, " at dt = 0.02, ", b.max_error,
          " at dt = 0.01 (ratio ", a.max_error / b.max_error, "); last quarter about the first: ", a.late_error,
          ", ", b.late_error, "; final kinetic temperature ", a.kinetic_temperature);
  MESSAGE("NVE from the same start at dt = 0.02: ", plain.max_error);
  CHECK(a.max_error / b.max_error > 2.7);
  CHECK(a.max_error / b.max_error < 6.0);
  CHECK(a.max_error < 3 * plain.max_error);
  // The constant C = max error / (omega dt)^2 is 0.135 at dt = 0.02 and 0.141 at dt = 0.01
  // (measured, g++ 12 -O2): the Strang step's own energy error constant for this well.
  // No drift: the last quarter stays within the run's largest error of the first quarter's
  // mean (a drift at the rate the error grows early would double it over the run).
  CHECK(a.late_error <= a.max_error);
  CHECK(b.late_error <= b.max_error);
}

TEST_CASE("nose-hoover: the thermostatted step is time reversible (p, v -> -p, -v)") {
  // NHC(h/2) Strang NHC(h/2) is a palindrome of steps each reversed by (q, p, xi, v) -> (q, -p, xi,
  // -v) (the chain's equations are invariant under it with t -> -t: G_j and v_j v_{j+1} are even),
  // so 40 steps, the flip, 40 steps and the flip give back the start. Round-off only: about 10^2
  // operations of relative error eps per body and step on O(1) numbers, 80 steps, amplified by
  // the flow's divergence at most e^(omega T) = e^(4.5 x 0.8) = 37: 80 x 100 x 37 eps = 7e-11.
  const Wells w(20, 20.0);
  const auto x0 = w.start(1.0, 5);
  auto x = x0;
  sesi::Thermostatted<S2> stepper(nose_hoover(1.0, 0.3, 3));
  const double dt = 0.01;
  // A chain away from rest, so that its velocities matter: 20 steps first.
  for (int k = 0; k < 20; ++k) stepper.do_step(w.sys, x, k * dt, dt);
  const auto flip = [&] {
    x.p = -x.p;
    auto saved = stepper.stage().save();  // {step, heat, kT, N_f, xi_1..xi_M, v_1..v_M}
    for (std::size_t j = 4 + 3; j < saved.size(); ++j) saved[j] = -saved[j];
    stepper.stage().load(saved);
  };
  const auto start = x;
  const auto chain_start = stepper.stage().save();
  for (int k = 0; k < 40; ++k) stepper.do_step(w.sys, x, k * dt, dt);
  CHECK(coretest::distance(x, start) > 0.1);  // it moved
  flip();
  for (int k = 0; k < 40; ++k) stepper.do_step(w.sys, x, k * dt, dt);
  flip();
  const double tol = 7e-11;
  MESSAGE("reversed: max |dq| ", (x.q - start.q).cwiseAbs().maxCoeff(), ", max |dp| ",
          (x.p - start.p).cwiseAbs().maxCoeff(), "; chain v_1 at the flip ", chain_start[4 + 3]);
  CHECK(std::abs(chain_start[4 + 3]) > 0.01);  // the chain was moving: its reversal matters
  CHECK((x.q - start.q).cwiseAbs().maxCoeff() < tol);
  CHECK((x.p - start.p).cwiseAbs().maxCoeff() < tol);
  const auto chain_end = stepper.stage().save();
  REQUIRE(chain_end.size() == chain_start.size());
  for (std::size_t j = 4; j < chain_end.size(); ++j) CHECK(std::abs(chain_end[j] - chain_start[j]) < tol);
}

TEST_CASE("nose-hoover: 500 bodies in wells on S^2 have the mean kinetic temperature kT") {
  // N_f = 1000 degrees of freedom, kT = 1.5, tau = 0.2, M = 3, dt = 0.005 (omega dt = 0.022: the
  // step's bias on the kinetic temperature, O((omega dt)^2) = 5e-4 relative, is far below the
  // statistical bound). From a cold start (kT0 = 0.5), 5 time units to equilibrate, then the mean
  // of 2K/N_f over 40 time units, every step. Its standard error by batch means: 20 batches of 2
  // time units (10 thermostat times, 1.4 periods of the wells), SE = sd(batch means) / sqrt(20).
  // The bound: 4 SE (the t distribution with 19 degrees of freedom exceeds 4 with probability
  // 8e-4), plus the step's bias. The deviation is exactly kT tau^2 (<v_1 v_2> + (v_1(T) - v_1(0))
  // / T) (the time average of the chain's v_1 equation), whose correlation time grows with tau:
  // at tau = 0.5, near the wells' frequency, batches of 2 time units underestimate the error
  // (deviation / SE from -3.1 to 1.5 over seeds 23..28), at tau = 0.2 they do not (-0.2 to 1.4).
  const double kT = 1.5, dt = 0.005;
  const Wells w(500, 20.0);
  auto x = w.start(0.5, 23);
  sesi::Thermostatted<S2> stepper(nose_hoover(kT, 0.2, 3));
  const double Nf = 1000;
  const int burn = static_cast<int>(std::lround(5 / dt)), batches = 20,
            per_batch = static_cast<int>(std::lround(2 / dt));
  int k = 0;
  for (; k < burn; ++k) stepper.do_step(w.sys, x, k * dt, dt);
  std::vector<double> means;
  for (int j = 0; j < batches; ++j) {
    double sum = 0;
    for (int i = 0; i < per_batch; ++i, ++k) {
      stepper.do_step(w.sys, x, k * dt, dt);
      sum += 2 * w.sys.kinetic_energy(x) / Nf;
    }
    means.push_back(sum / per_batch);
  }
  double mean = 0;
  for (const double m : means) mean += m;
  mean /= batches;
  double var = 0;
  for (const double m : means) var += (m - mean) * (m - mean);
  const double se = std::sqrt(var / (batches - 1) / batches);
  // The canonical spread of one reading, kT sqrt(2 / N_f) = 0.067: the batch means must be
  // tighter than that (else the batches are too short for the bound to mean anything).
  MESSAGE("nose-hoover: mean kinetic temperature ", mean, " (kT = ", kT, "), standard error ", se);
  CHECK(se < kT * std::sqrt(2 / Nf));
  CHECK(std::abs(mean - kT) < 4 * se + 5e-4 * kT);
}

}  // namespace
