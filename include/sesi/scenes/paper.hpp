#pragma once
/// @file paper.hpp
/// The seed paper's benchmark scene made exact (shared/paper-scene.md; seed paper, eq. 11 and
/// Supplementary Material): three unit masses on the unit sphere S^2 with the chord-well pair
/// term summed over ORDERED pairs (ChordWell strength 2), theta0 = pi/4, and its exact solution.
///
/// The three-fold symmetry holds for all time: theta_i = theta, phi_i = phi + 2 pi (i-1)/3.
/// With psi = cos theta, E' = 2E/3 and l = p_phi, psi'' = -(E' + 4) psi + 4 cos theta0, so
///   psi(t) = A + B sin(w t + d),  w^2 = E' + 4,  A = 4 cos(theta0) / w^2,
///   phi(t) = phi(0) + l * integral_0^t ds / (1 - psi(s)^2),
/// the integral in closed form through 1/(1-psi^2) = (1/(1-psi) + 1/(1+psi))/2 and
/// integral_0^u dx / (a + b sin x) = (2/k) [atan((a tan(u/2) + b)/k) - atan(b/k)], k^2 = a^2 - b^2,
/// on (-pi, pi), plus 2 pi / k per whole period.

#include <array>
#include <cmath>
#include <numbers>
#include <vector>

#include <Eigen/Core>

#include "sesi/potentials.hpp"
#include "sesi/spaces/sphere.hpp"
#include "sesi/state.hpp"
#include "sesi/system.hpp"

namespace sesi::scenes::paper {

/// Constants of the scene (shared/paper-scene.md).
template <class Scalar>
struct Constants {
  static Scalar theta0() { return std::numbers::pi_v<Scalar> / Scalar(4); }
  static Scalar p_theta() { return Scalar(1) / Scalar(4); }
  static Scalar p_phi() { return Scalar(0.1727174029854043L); }
  static constexpr double tau = 0.1;     ///< the seed's step
  static constexpr double t_end = 800.0; ///< the seed's final time (8000 steps)
};

template <class Scalar = double>
using Chart = Sphere<2, Scalar>;

/// The system: Sphere<2>(1), three unit masses, ChordWell(theta0 = pi/4, strength 2).
template <class Scalar = double>
auto make_system() {
  return System(Chart<Scalar>(Scalar(1)), std::vector<Scalar>(3, Scalar(1)),
                ChordWell<Scalar>{Constants<Scalar>::theta0(), Scalar(2)});
}

/// The initial state: theta = pi/4, phi = 0, 2pi/3, 4pi/3, p_theta = 1/4, p_phi = 0.1727...
template <class Scalar = double>
State<Chart<Scalar>> initial_state() {
  State<Chart<Scalar>> x(2, 3);
  for (int b = 0; b < 3; ++b) {
    x.q(0, b) = Constants<Scalar>::theta0();
    x.q(1, b) = Scalar(2) * std::numbers::pi_v<Scalar> * Scalar(b) / Scalar(3);
    x.p(0, b) = Constants<Scalar>::p_theta();
    x.p(1, b) = Constants<Scalar>::p_phi();
  }
  return x;
}

/// The exact solution, evaluated in long double.
class Exact {
 public:
  using Real = long double;

  Exact() {
    using std::atan2;
    using std::cos;
    using std::sin;
    using std::sqrt;
    const Real th = std::numbers::pi_v<Real> / 4, c0 = cos(std::numbers::pi_v<Real> / 4);
    const Real pt = Constants<Real>::p_theta();
    l_ = Constants<Real>::p_phi();
    // Energy: kinetic 3 (pt^2 + l^2 / sin^2 th) / 2; the potential is zero at t = 0.
    energy_ = Real(3) * (pt * pt + l_ * l_ / (sin(th) * sin(th))) / Real(2);
    const Real e1 = Real(2) * energy_ / Real(3);
    w_ = sqrt(e1 + Real(4));
    a_ = Real(4) * c0 / (w_ * w_);
    const Real psi0 = cos(th), dpsi0 = -sin(th) * pt;
    b_ = sqrt((psi0 - a_) * (psi0 - a_) + dpsi0 * dpsi0 / (w_ * w_));
    d_ = atan2(psi0 - a_, dpsi0 / w_);
    i0_ = phase_integral(d_);
  }

  /// Total energy E = 0.183243903882068.
  Real energy() const { return energy_; }
  /// Radial frequency w = sqrt(2E/3 + 4); the radial period is 2 pi / w.
  Real frequency() const { return w_; }
  Real psi(Real t) const { return a_ + b_ * std::sin(w_ * t + d_); }
  Real theta(Real t) const { return std::acos(psi(t)); }
  /// phi of body 1 (body b adds 2 pi b / 3).
  Real phi(Real t) const { return l_ / w_ * (phase_integral(w_ * t + d_) - i0_); }

  /// Embedding point of body b (0, 1, 2) at time t.
  Eigen::Matrix<Real, 3, 1> position(int b, Real t) const {
    const Real th = theta(t);
    const Real ph = phi(t) + Real(2) * std::numbers::pi_v<Real> * Real(b) / Real(3);
    return {std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th)};
  }

 private:
  /// integral_0^u dx / (a + b sin x) for a > |b|.
  static Real inverse_sine_integral(Real a, Real b, Real u) {
    using std::atan;
    using std::floor;
    using std::sqrt;
    using std::tan;
    const Real two_pi = Real(2) * std::numbers::pi_v<Real>;
    const Real k = sqrt(a * a - b * b);
    const Real periods = floor((u + std::numbers::pi_v<Real>) / two_pi);
    const Real r = u - periods * two_pi;  // in [-pi, pi)
    const Real part = Real(2) / k * (atan((a * tan(r / Real(2)) + b) / k) - atan(b / k));
    return periods * two_pi / k + part;
  }
  /// integral_0^u dx / (1 - psi^2) with psi = A + B sin x.
  Real phase_integral(Real u) const {
    return (inverse_sine_integral(Real(1) - a_, -b_, u) +
            inverse_sine_integral(Real(1) + a_, b_, u)) /
           Real(2);
  }

  Real l_{}, energy_{}, w_{}, a_{}, b_{}, d_{}, i0_{};
};

}  // namespace sesi::scenes::paper
