#pragma once
/// @file reference/tao.hpp
/// Tao's explicit symplectic method for non-separable Hamiltonians (M. Tao, "Explicit symplectic
/// approximation of nonseparable Hamiltonians: algorithm and long time performance",
/// Phys. Rev. E 94, 043303 (2016)), on the chart ODE of reference/hamiltonian.hpp.
///
/// Phase space is doubled to (q, p, x, y) with the augmented Hamiltonian
///   Hbar = H_A + H_B + omega H_C,  H_A = H(q, y),  H_B = H(x, p),
///   H_C = (|q - x|^2 + |p - y|^2) / 2.
/// Each part has an exact, explicit flow:
///   phi_A(d): p -= d dH/dq(q, y), x += d dH/dp(q, y)   (q, y fixed: one field evaluation)
///   phi_B(d): q += d dH/dp(x, p), y -= d dH/dq(x, p)   (x, p fixed: one field evaluation)
///   phi_C(d): (q - x, p - y) rotated by the angle 2 omega d, (q + x, p + y) fixed.
/// The order-2 step is Tao's symmetric Strang composition
///   phi_A(h/2) phi_B(h/2) phi_C(h) phi_B(h/2) phi_A(h/2),
/// and higher even orders compose it with the same tables as the chart steppers
/// (coefficients.hpp; Tao's order-4 method is Yoshida's triple jump, Yoshida4). Adjacent phi_A
/// half flows of two stages are fused (q and y do not move under phi_A, so its flows add
/// exactly), so a step of s stages costs 3 s + 1 field evaluations. The output is the (q, p)
/// copy, as in Tao's paper; (x, y) persist between steps.
///
/// The binding omega. For a fixed omega the method is a consistent splitting of Hbar, whose
/// flow from the diagonal (x = q, y = p) is the original flow, so its order l holds for every
/// omega; omega sets the error constant and the long-time behaviour. Tao asks for
/// h << omega^{-1/l} (his error bound for integrable systems is O(T h^l omega)) and for omega
/// large enough that the binding keeps the two copies together. Measured with this code
/// (max energy error over T = 800):
///  - the seed's scene (integrable), h = 0.1: 2e-3..4e-3 (order 2) and 6e-4..9e-3 (order 4)
///    for every omega from 0.5 to 100 (omega = 20: 3.7e-3 and 8.1e-3; SESI 2: 1.2e-3);
///  - three soft springs on S^3 (tests/reference/common.hpp, not integrable), h = 0.01:
///    omega <= 1 lets the copies drift apart to O(1); omega = 5 and 100 stay bound (energy
///    errors 2e-3 and 2e-4 at order 2); at h = 0.1 no omega worked, and some runs blew up when
///    a body passed within 1e-3 of a chart pole (traced for omega = 20, h = 0.01), where the
///    explicit A and B maps see the singular field, unlike the chart steppers' exact flows;
///  - the order tests reach the asymptotic order for h omega <= 0.2..0.6 (omega = 20).
/// The default omega = 20, ten times the seed scene's radial frequency (2.02), binds well
/// there and is in the asymptotic regime for h <= 0.01..0.03; it is a compromise, not a rule:
/// pass omega explicitly, e.g. suggested_omega(h), which reads Tao's h << omega^{-1/l} as
/// h = omega^{-1/l} / 10 (omega = 1 at h = 0.1, 100 at h = 0.01 for l = 2), and keep it fixed
/// when comparing steps.

#include <array>
#include <cmath>
#include <cstddef>
#include <type_traits>

#include <Eigen/Core>

#include "sesi/chart.hpp"
#include "sesi/coefficients.hpp"
#include "sesi/reference/hamiltonian.hpp"
#include "sesi/state.hpp"
#include "sesi/stepper.hpp"

namespace sesi::reference {

/// Tao's method composed with a coefficient table (Strang: order 2; Yoshida4: order 4; ...).
/// Stepper interface of the chart steppers: order(), do_step(sys, x, t, dt).
template <class Table, HierarchicalChart Chart>
class Tao {
 public:
  using Scalar = typename Chart::Scalar;
  using state_type = State<Chart>;
  using deriv_type = State<Chart>;
  using value_type = Scalar;
  using time_type = Scalar;
  using order_type = unsigned short;
  using table = Table;
  using Matrix = typename state_type::Matrix;

  static constexpr order_type order_value = Table::order;
  static constexpr order_type order() { return Table::order; }

  /// @param omega the binding constant of H_C (see the file comment for the default).
  explicit Tao(Scalar omega = Scalar(20)) : omega_(omega), w_(Table::template weights<Scalar>()) {}

  Scalar omega() const { return omega_; }
  /// omega with h = omega^{-1/l} / c, Tao's condition h << omega^{-1/l} with a margin c.
  static Scalar suggested_omega(Scalar h, Scalar c = Scalar(10)) {
    using std::pow;
    return pow(c * h, -Scalar(Table::order));
  }
  /// The second copy (x, y) of the extended phase space.
  const Matrix& shadow_q() const { return x_; }
  const Matrix& shadow_p() const { return y_; }
  /// Field evaluations since construction.
  std::size_t evaluations() const { return field_.evaluations(); }
  /// Restart the extended phase space from the next state (x = q, y = p).
  void reset() { seeded_ = false; }

  /// Advance s from t to t + dt in place.
  template <class Sys>
  void do_step(Sys&& system, state_type& s, time_type /*t*/, time_type dt) {
    using Raw = std::remove_cvref_t<Sys>;
    const auto& sys = sesi::detail::unwrap<Raw>::get(system);
    // The copies start on the diagonal x = q, y = p (Tao, Sec. 2), and again whenever the caller
    // hands in a state that is not what the last step returned.
    if (!seeded_ || !(last_q_ == s.q && last_p_ == s.p)) {
      x_ = s.q;
      y_ = s.p;
      seeded_ = true;
    }
    const std::size_t n = Table::stages;
    Scalar pending = w_[0] * dt / Scalar(2);  // phi_A carried over to fuse with the next stage
    for (std::size_t k = 0; k < n; ++k) {
      const Scalar h = w_[k] * dt;
      flow_a(sys, s, pending);
      flow_b(sys, s, h / Scalar(2));
      flow_c(s, h);
      flow_b(sys, s, h / Scalar(2));
      pending = h / Scalar(2) + (k + 1 < n ? w_[k + 1] * dt / Scalar(2) : Scalar(0));
    }
    flow_a(sys, s, pending);
    last_q_ = s.q;
    last_p_ = s.p;
  }

 private:
  /// phi_A(d): the field at (q, y) drives p and x.
  template <class Sys>
  void flow_a(const Sys& sys, state_type& s, Scalar d) {
    mixed_.q = s.q;
    mixed_.p = y_;
    field_.evaluate(sys, mixed_, f_);
    s.p += d * f_.p;
    x_ += d * f_.q;
  }
  /// phi_B(d): the field at (x, p) drives q and y.
  template <class Sys>
  void flow_b(const Sys& sys, state_type& s, Scalar d) {
    mixed_.q = x_;
    mixed_.p = s.p;
    field_.evaluate(sys, mixed_, f_);
    s.q += d * f_.q;
    y_ += d * f_.p;
  }
  /// phi_C(d): exact flow of omega H_C, a rotation of the differences by 2 omega d.
  void flow_c(state_type& s, Scalar d) {
    using std::cos;
    using std::sin;
    const Scalar c = cos(Scalar(2) * omega_ * d), sn = sin(Scalar(2) * omega_ * d);
    dq_ = s.q - x_;
    dp_ = s.p - y_;
    sq_ = s.q + x_;
    sp_ = s.p + y_;
    rq_ = c * dq_ + sn * dp_;
    rp_ = c * dp_ - sn * dq_;
    s.q = (sq_ + rq_) / Scalar(2);
    s.p = (sp_ + rp_) / Scalar(2);
    x_ = (sq_ - rq_) / Scalar(2);
    y_ = (sp_ - rp_) / Scalar(2);
  }

  Scalar omega_;
  std::array<Scalar, Table::stages> w_;
  ChartField<Chart> field_;
  Matrix x_, y_, last_q_, last_p_;
  Matrix dq_, dp_, sq_, sp_, rq_, rp_;
  state_type mixed_, f_;
  bool seeded_ = false;
};

/// Tao's order-2 method and its triple-jump order-4 composition.
template <class Chart>
using Tao2 = Tao<coefficients::Strang, Chart>;
template <class Chart>
using Tao4 = Tao<coefficients::Yoshida4, Chart>;

}  // namespace sesi::reference
