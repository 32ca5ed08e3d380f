#pragma once
/// @file thermostats/csvr.hpp
/// Stochastic velocity rescaling, CSVR (issue #25; docs/thermostats.md).
///
/// Bussi, Donadio and Parrinello, "Canonical sampling through velocity rescaling", J. Chem. Phys.
/// 126, 014101 (2007). The total kinetic energy K of N_f degrees of freedom follows
///   dK = (K_bar - K) dt / tau + 2 sqrt(K K_bar / N_f) dW / sqrt(tau),   K_bar = N_f kT / 2,
/// whose stationary law is the canonical one, K ~ Gamma(N_f / 2, kT), and whose exact solution over
/// a time h is their eq. (A7):
///   alpha^2 = c + (1 - c) (S + R_1^2) K_bar / (N_f K) + 2 R_1 sqrt(c (1 - c) K_bar / (N_f K)),
///   c = exp(-h / tau), R_1 ~ N(0, 1), S ~ chi-squared(N_f - 1), K' = alpha^2 K,
/// with the sign of alpha that of R_1 + sqrt(c N_f K / ((1 - c) K_bar)) (the paper's choice below
/// (A7), which makes alpha a continuous function of the noise). Written as
///   alpha = sign(a) sqrt(a^2 + r^2 S),   a = sqrt(c) + r R_1,   r^2 = (1 - c) kT / (2 K),
/// the same number, and a sum of squares: never negative under round-off. 1 - c is -expm1(-h/tau),
/// without cancellation for h << tau.
///
/// The draw is exact (no discretisation error in K's law): CSVR(h/2) step CSVR(h/2) around the
/// kick-drift-kick Strang step (sesi::Thermostat, thermostat.hpp) leaves the canonical law of K
/// invariant and is second order in the dynamics; H minus the heat the rescalings put in (Bussi's
/// effective energy) is conserved up to the NVE step's error.
///
/// Random numbers (random.hpp): R_1 = normal(seed, stream::csvr, step, half, 0) and
/// S = chi_squared(N_f - 1, seed, stream::csvr, step, half, 0) (other Philox counters than R_1's),
/// so that alpha is a pure function of (K, N_f, kT, h, tau, seed, step, half): no generator state,
/// the same bits on any thread count and after a resume. half tells apart the two rescalings of one
/// step (0: before the step, 1: after).
///
/// Requires Random123 (random.hpp).

#include <cmath>
#include <cstdint>

#include "sesi/config.hpp"
#include "sesi/random.hpp"

namespace sesi::thermostats {

/// The factor alpha by which every momentum is scaled (K' = alpha^2 K) for a CSVR step of length
/// h >= 0 with relaxation time tau > 0, target K_bar = N_f kT / 2 (kT >= 0, N_f > 0; N_f need
/// not be an integer), drawn from the keys (seed, random::stream::csvr, step, half).
/// K = 0 (no momenta: no factor moves them) gives 1. kT = 0 gives sqrt(c): exponential cooling.
template <class Scalar>
Scalar csvr_factor(Scalar K, Scalar Nf, Scalar kT, Scalar h, Scalar tau, std::uint64_t seed, std::uint64_t step,
                   std::uint64_t half) {
  SESI_CHECK(Nf > Scalar(0), "CSVR: the number of degrees of freedom must be > 0");
  SESI_CHECK(kT >= Scalar(0), "CSVR: the temperature must be >= 0");
  SESI_CHECK(tau > Scalar(0), "CSVR: the relaxation time tau must be > 0");
  SESI_CHECK(h >= Scalar(0), "CSVR: the step must be >= 0 (the rescaling is not reversible)");
  if (!(K > Scalar(0))) return Scalar(1);
  using std::exp;
  using std::expm1;
  using std::sqrt;
  const Scalar c = exp(-h / tau);
  const Scalar one_minus_c = -expm1(-h / tau);
  const Scalar r = sqrt(one_minus_c * kT / (Scalar(2) * K));
  const auto R1 = static_cast<Scalar>(random::normal(seed, random::stream::csvr, step, half, 0));
  const auto S = static_cast<Scalar>(
      random::chi_squared(static_cast<double>(Nf - Scalar(1)), seed, random::stream::csvr, step, half, 0));
  const Scalar a = sqrt(c) + r * R1;
  const Scalar alpha = sqrt(a * a + r * r * S);
  return a < Scalar(0) ? -alpha : alpha;
}

}  // namespace sesi::thermostats
