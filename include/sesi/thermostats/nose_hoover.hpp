#pragma once
/// @file thermostats/nose_hoover.hpp
/// A Nose-Hoover chain acting on the total kinetic energy (issue #25; docs/thermostats.md).
///
/// The chain of Martyna, Klein and Tuckerman ("Nose-Hoover chains: the canonical ensemble via
/// continuous dynamics", J. Chem. Phys. 97, 2635 (1992)): thermostat positions xi_j
/// and velocities v_j, j = 1..M, masses Q_1 = N_f kT tau^2, Q_j = kT tau^2 (j >= 2), and
///   dp/dt   = -dH/dq - v_1 p,
///   dv_1/dt = (2K - N_f kT) / Q_1 - v_1 v_2,
///   dv_j/dt = (Q_{j-1} v_{j-1}^2 - kT) / Q_j - v_j v_{j+1}   (v_{M+1} = 0),
///   dxi_j/dt = v_j,
/// which conserves H + extended_energy() = H + sum_j Q_j v_j^2 / 2 + N_f kT xi_1 + kT sum_{j>=2} xi_j
/// and, if ergodic, samples the canonical distribution of (q, p) at kT.
///
/// This class integrates the chain's part (p scaled, the chain advanced, q fixed) for a time h by
/// the time-reversible factorisation of Martyna, Tuckerman, Tobias and Klein ("Explicit
/// reversible integrators for extended systems dynamics", Mol. Phys. 87, 1117 (1996)):
/// n_c sub-steps, each a Suzuki-Yoshida composition (Yoshida, Phys. Lett. A 150, 262 (1990):
/// the fourth-order triple jump w_1 = w_3 = 1 / (2 - 2^(1/3)), w_2 = 1 - 2 w_1) of the symmetric
/// step of length delta = w h / n_c
///   v_M, v_{M-1}, ..., v_1 for delta/2;  p scaled by exp(-delta v_1), xi_j += delta v_j;
///   v_1, ..., v_{M-1}, v_M for delta/2,
/// where each v_j (j < M) half step is exp(-delta/4 v_{j+1}) scaling, delta/2 G_j kick,
/// exp(-delta/4 v_{j+1}) scaling: every piece the exact flow of a part of the vector field. The
/// whole propagator is a palindrome of exact flows, so advance(-h) undoes advance(h) up to
/// round-off (time reversibility); the triple jump makes the chain's part alone fourth order
/// (tests/core/thermostat_nhc.cpp measures it). Placed around the
/// kick-drift-kick Strang step as NHC(h/2) step NHC(h/2) (sesi::Thermostat, thermostat.hpp), the
/// thermostatted step is second order and H + extended_energy() is conserved to O(h^2) with no
/// drift.
///
/// Only the total kinetic energy K enters: the momenta are all scaled by the factor s that
/// advance() returns (K -> s^2 K), which is exact on a hierarchical chart (K quadratic in p).
/// The masses are computed from the kT and N_f of each call, so a temperature schedule changes
/// them with kT (the extended energy then changes too: it is conserved at constant kT only).
/// kT must be > 0 (the masses vanish at kT = 0: a schedule to 0 needs another thermostat).
///
/// Pure code, independent of the composition engine: no random numbers, no state beyond the
/// chain's xi and v (save(), load()).

#include <cmath>
#include <cstddef>
#include <vector>

#include "sesi/config.hpp"

namespace sesi::thermostats {

/// A Nose-Hoover chain of length M >= 1 with relaxation time tau > 0, the thermostat's time
/// scale (for free bodies, linearised about K = K_bar, the first link's v_1 and K oscillate at
/// angular frequency sqrt(2) / tau with the masses below).
template <class Scalar>
class NoseHooverChain {
 public:
  /// chain: M >= 1; tau > 0; substeps: n_c >= 1, the MTTK sub-steps per call.
  NoseHooverChain(int chain, Scalar tau, int substeps = 1)
      : tau_(tau), substeps_(substeps), xi_(static_cast<std::size_t>(chain > 0 ? chain : 1), Scalar(0)),
        v_(xi_.size(), Scalar(0)) {
    SESI_CHECK(chain >= 1, "Nose-Hoover: the chain length must be >= 1");
    SESI_CHECK(tau > Scalar(0), "Nose-Hoover: the relaxation time tau must be > 0");
    SESI_CHECK(substeps >= 1, "Nose-Hoover: the number of sub-steps must be >= 1");
  }

  int chain() const { return static_cast<int>(xi_.size()); }
  Scalar tau() const { return tau_; }
  int substeps() const { return substeps_; }
  /// The thermostat positions xi_1..xi_M and velocities v_1..v_M.
  const std::vector<Scalar>& positions() const { return xi_; }
  const std::vector<Scalar>& velocities() const { return v_; }

  /// Advance the chain for time h (negative: backwards) given the kinetic energy K of N_f
  /// degrees of freedom at temperature kT > 0; returns the factor s by which every momentum is
  /// to be scaled (K -> s^2 K). (At K = 0 there is nothing to scale: the chain cannot heat a
  /// system at rest; start it with momenta.)
  Scalar advance(Scalar K, Scalar Nf, Scalar kT, Scalar h) {
    SESI_CHECK(kT > Scalar(0), "Nose-Hoover: the temperature must be > 0");
    SESI_CHECK(Nf > Scalar(0), "Nose-Hoover: the number of degrees of freedom must be > 0");
    using std::cbrt;
    using std::exp;
    const int M = chain();
    const Scalar q1 = Nf * kT * tau_ * tau_, qj = kT * tau_ * tau_;
    const auto mass = [&](int j) { return j == 0 ? q1 : qj; };
    // The force on v_j (0-based j): G_0 from K, G_j from v_{j-1}.
    Scalar two_k = Scalar(2) * K;
    const auto force = [&](int j) {
      return j == 0 ? (two_k - Nf * kT) / q1 : (mass(j - 1) * v_[j - 1] * v_[j - 1] - kT) / qj;
    };
    // v_j's half step of length d: scale, kick, scale (the top one has no v_{j+1}: kick only).
    const auto half = [&](int j, Scalar d) {
      if (j + 1 < M) {
        const Scalar e = exp(-d / Scalar(2) * v_[j + 1]);
        v_[j] *= e;
        v_[j] += d * force(j);
        v_[j] *= e;
      } else {
        v_[j] += d * force(j);
      }
    };
    const Scalar w1 = Scalar(1) / (Scalar(2) - cbrt(Scalar(2)));
    const Scalar weights[3] = {w1, Scalar(1) - Scalar(2) * w1, w1};
    Scalar log_s(0);  // the sum of -delta v_1: s = exp(log_s)
    const Scalar k0 = two_k;
    for (int c = 0; c < substeps_; ++c) {
      for (const Scalar w : weights) {
        const Scalar delta = w * h / Scalar(substeps_);
        const Scalar d2 = delta / Scalar(2);
        for (int j = M - 1; j >= 0; --j) half(j, d2);
        log_s -= delta * v_[0];
        two_k = k0 * exp(Scalar(2) * log_s);
        for (int j = 0; j < M; ++j) xi_[j] += delta * v_[j];
        for (int j = 0; j < M; ++j) half(j, d2);
      }
    }
    return exp(log_s);
  }

  /// sum_j Q_j v_j^2 / 2 + N_f kT xi_1 + kT sum_{j>=2} xi_j, with the masses at (N_f, kT).
  Scalar extended_energy(Scalar Nf, Scalar kT) const {
    const Scalar q1 = Nf * kT * tau_ * tau_, qj = kT * tau_ * tau_;
    Scalar e = q1 * v_[0] * v_[0] / Scalar(2) + Nf * kT * xi_[0];
    for (std::size_t j = 1; j < xi_.size(); ++j) e += qj * v_[j] * v_[j] / Scalar(2) + kT * xi_[j];
    return e;
  }

  /// xi_1..xi_M then v_1..v_M, exact; load() takes what save() gave (2 M numbers).
  std::vector<Scalar> save() const {
    std::vector<Scalar> out(xi_);
    out.insert(out.end(), v_.begin(), v_.end());
    return out;
  }
  void load(const std::vector<Scalar>& saved) {
    SESI_CHECK(saved.size() == 2 * xi_.size(), "Nose-Hoover: a saved chain of another length");
    if (saved.size() != 2 * xi_.size()) return;
    const auto m = static_cast<std::ptrdiff_t>(xi_.size());
    xi_.assign(saved.begin(), saved.begin() + m);
    v_.assign(saved.begin() + m, saved.end());
  }

 private:
  Scalar tau_;
  int substeps_;
  std::vector<Scalar> xi_, v_;
};

}  // namespace sesi::thermostats
