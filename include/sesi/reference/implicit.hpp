#pragma once
/// @file reference/implicit.hpp
/// Implicit symplectic references on the chart ODE (reference/hamiltonian.hpp): the s-stage
/// Gauss-Legendre collocation methods, of order 2s. s = 1 is the implicit midpoint rule, the
/// seed's comparator (seed paper, Suppl. "Simulation details"; for the midpoint rule its four
/// half-step equations are y_{n+1} = y_n + h f((y_n + y_{n+1})/2)); s = 2 is the order-4 method.
/// Gauss methods are symplectic and symmetric (Hairer, Lubich, Wanner, Geometric Numerical
/// Integration, 2nd ed. (GNI), Secs. VI.4 and V.2).
///
/// Implementation in the manner of Hairer's GNI codes (GNI Sec. VIII.6):
///  - stage increments Z_i = Y_i - y_n solve Z_i = h sum_j a_ij f(y_n + Z_j);
///  - starting guess from the previous step's collocation polynomial, extrapolated to the new
///    stage times (GNI Sec. VIII.6.1): Z_i^0 = h sum_j e_ij F_j, e_ij = int_1^{1+c_i} l_j;
///  - fixed-point iteration (GNI Sec. VIII.6.2), stopped when the increment is below one unit
///    of round-off of every component, or stops decreasing (round-off reached), the criterion of
///    E. Hairer, R. I. McLachlan, A. Razakarivony, "Achieving Brouwer's law with implicit
///    Runge-Kutta methods", BIT 48 (2008) 231, made robust to the zig-zag of the increments
///    (see do_step);
///  - y_{n+1} = y_n + h sum_j b_j F_j with the last evaluated F_j (no extra evaluation).
///
/// Why fixed-point rather than Newton: on the non-stiff problems these references serve, the
/// iteration contracts by about h L / 2 per sweep from an O(h^{s+1}) guess. On the seed's scene
/// at h = 0.1 it needs 16 sweeps per step for the midpoint rule (16 evaluations), 12 for
/// Gauss 4 (24 evaluations). A simplified Newton iteration needs the Jacobian of the 2 n N
/// dimensional field first: 2 n N = 12 evaluations by differences there (no analytic Hessian of
/// a user potential is available), a factorisation of a (2 n N s)^2 matrix, and then still
/// a few iterations, so it would not be faster at these sizes; it pays only for stiff
/// problems, which these references do not target.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <limits>
#include <type_traits>

#include <Eigen/Core>

#include "sesi/chart.hpp"
#include "sesi/config.hpp"
#include "sesi/reference/hamiltonian.hpp"
#include "sesi/state.hpp"
#include "sesi/stepper.hpp"

namespace sesi::reference {

/// The s-stage Gauss-Legendre collocation tableau, computed in Scalar from its nodes: the roots
/// of the shifted Legendre polynomial P_s(2c - 1) (GNI Sec. II.1.3; Hairer, Norsett, Wanner,
/// Solving ODEs I, Sec. II.7):
///   s = 1: c = 1/2;  s = 2: c = 1/2 -+ sqrt(3)/6;
///   s = 3: c = 1/2 - sqrt(15)/10, 1/2, 1/2 + sqrt(15)/10.
/// Then a_ij = int_0^{c_i} l_j, b_j = int_0^1 l_j (collocation, GNI Sec. II.1.3) and the
/// extrapolation weights e_ij = int_1^{1+c_i} l_j, l_j the Lagrange basis on the nodes.
template <class Scalar, std::size_t S>
struct GaussTableau {
  static_assert(S >= 1 && S <= 3, "Gauss-Legendre tableaus are provided for 1 to 3 stages");
  std::array<Scalar, S> c{}, b{};
  std::array<std::array<Scalar, S>, S> a{}, e{};

  GaussTableau() {
    using std::sqrt;
    const Scalar half = Scalar(1) / Scalar(2);
    if constexpr (S == 1) {
      c = {half};
    } else if constexpr (S == 2) {
      const Scalar d = sqrt(Scalar(3)) / Scalar(6);
      c = {half - d, half + d};
    } else {
      const Scalar d = sqrt(Scalar(15)) / Scalar(10);
      c = {half - d, half, half + d};
    }
    for (std::size_t j = 0; j < S; ++j) {
      const auto l = lagrange(j);
      b[j] = integral(l, Scalar(0), Scalar(1));
      for (std::size_t i = 0; i < S; ++i) {
        a[i][j] = integral(l, Scalar(0), c[i]);
        e[i][j] = integral(l, Scalar(1), Scalar(1) + c[i]);
      }
    }
  }

 private:
  /// Coefficients (ascending powers) of l_j(t) = prod_{k != j} (t - c_k) / (c_j - c_k).
  std::array<Scalar, S> lagrange(std::size_t j) const {
    std::array<Scalar, S> poly{};
    poly[0] = Scalar(1);
    std::size_t degree = 0;
    for (std::size_t k = 0; k < S; ++k) {
      if (k == j) continue;
      const Scalar inv = Scalar(1) / (c[j] - c[k]);
      // poly *= (t - c_k) * inv
      for (std::size_t m = degree + 2; m-- > 0;) {  // m = degree + 1 .. 0
        const Scalar lower = m > 0 ? poly[m - 1] : Scalar(0);
        poly[m] = (lower - c[k] * poly[m]) * inv;
      }
      ++degree;
    }
    return poly;
  }
  static Scalar integral(const std::array<Scalar, S>& poly, Scalar from, Scalar to) {
    Scalar sum(0), pf(from), pt(to);
    for (std::size_t m = 0; m < S; ++m) {
      sum += poly[m] * (pt - pf) / Scalar(m + 1);
      pf *= from;
      pt *= to;
    }
    return sum;
  }
};

/// Work counters of an implicit stepper.
struct IterationStatistics {
  std::size_t steps = 0;           ///< do_step calls
  std::size_t iterations = 0;      ///< fixed-point sweeps (each is `stages` force evaluations)
  std::size_t evaluations = 0;     ///< force evaluations (calls of the Hamiltonian field)
  std::size_t max_iterations = 0;  ///< the most sweeps one step needed
  std::size_t unconverged = 0;     ///< steps that hit the iteration cap before converging
};

/// The s-stage Gauss-Legendre method (order 2s) on State<Chart>, with the odeint Stepper
/// interface of the chart steppers (order(), do_step(sys, x, t, dt); the system may be passed
/// as std::ref). Keeps the last step's stage derivatives for the starting guess of the next.
template <HierarchicalChart Chart, std::size_t Stages>
class Gauss {
 public:
  using Scalar = typename Chart::Scalar;
  using state_type = State<Chart>;
  using deriv_type = State<Chart>;
  using value_type = Scalar;
  using time_type = Scalar;
  using order_type = unsigned short;

  static constexpr order_type order_value = static_cast<order_type>(2 * Stages);
  static constexpr order_type order() { return order_value; }
  static constexpr std::size_t stages() { return Stages; }

  /// @param max_iterations cap on fixed-point sweeps per step (steps hitting it are counted in
  ///        statistics().unconverged).
  explicit Gauss(std::size_t max_iterations = 100) : max_iterations_(max_iterations) {}

  const GaussTableau<Scalar, Stages>& tableau() const { return tab_; }
  const IterationStatistics& statistics() const { return stats_; }
  void reset_statistics() { stats_ = {}; }
  /// Forget the previous step (the next step starts from an explicit guess).
  void reset() { have_history_ = false; }

  /// Advance x from t to t + dt in place.
  template <class Sys>
  void do_step(Sys&& system, state_type& x, time_type /*t*/, time_type dt) {
    using Raw = std::remove_cvref_t<Sys>;
    const auto& sys = sesi::detail::unwrap<Raw>::get(system);
    auto f = [&](const state_type& y, state_type& dydt) { field_.evaluate(sys, y, dydt); };
    const std::size_t evals_before = field_.evaluations();
    y0_ = x;
    resize_like(x);

    // Starting guess: the previous collocation polynomial if x is where it ended and the step
    // is the same; otherwise Z_i = c_i h f(y_n) (one evaluation: one sweep from Z = 0).
    const bool continued = have_history_ && dt == last_dt_ && same(x, last_out_);
    if (continued) {
      for (std::size_t i = 0; i < Stages; ++i) combine(tab_.e[i], dt, z_[i]);
    } else {
      f(y0_, f_[0]);
      for (std::size_t i = 0; i < Stages; ++i) {
        z_[i].q = (tab_.c[i] * dt) * f_[0].q;
        z_[i].p = (tab_.c[i] * dt) * f_[0].p;
      }
    }

    const Scalar eps = std::numeric_limits<Scalar>::epsilon();
    const Scalar inf = std::numeric_limits<Scalar>::infinity();
    Scalar back1 = inf, back2 = inf;  // the increments one and two sweeps ago
    std::size_t sweeps = 0;
    bool converged = false;
    while (sweeps < max_iterations_) {
      for (std::size_t i = 0; i < Stages; ++i) {
        stage_.q = y0_.q + z_[i].q;
        stage_.p = y0_.p + z_[i].p;
        f(stage_, f_[i]);
      }
      ++sweeps;
      Scalar delta(0);
      for (std::size_t i = 0; i < Stages; ++i) {
        combine(tab_.a[i], dt, znew_);
        delta = std::max(delta, increment(znew_.q, z_[i].q, y0_.q));
        delta = std::max(delta, increment(znew_.p, z_[i].p, y0_.p));
        z_[i].q = znew_.q;
        z_[i].p = znew_.p;
      }
      // Converged: the increment no longer moves any y_n + Z_i by an ulp, or it stopped
      // decreasing (round-off dominates; Hairer-McLachlan-Razakarivony 2008). The iteration
      // matrix h A (x) J f' has complex eigenvalues for a Hamiltonian field, so the increments
      // fall in a zig-zag (measured: 3e-4, 2.5e-4, 3e-6, 2.6e-6, ...); comparing with the
      // increment two sweeps back keeps a zig-zag pair from stopping the iteration early.
      if (delta <= eps || delta >= back2) {
        converged = true;
        break;
      }
      back2 = back1;
      back1 = delta;
    }

    // y_{n+1} = y_n + h sum_j b_j F_j, F_j from the last sweep.
    combine(tab_.b, dt, znew_);
    x.q = y0_.q + znew_.q;
    x.p = y0_.p + znew_.p;

    have_history_ = true;
    last_dt_ = dt;
    last_out_ = x;
    ++stats_.steps;
    stats_.iterations += sweeps;
    stats_.evaluations += field_.evaluations() - evals_before;
    stats_.max_iterations = std::max(stats_.max_iterations, sweeps);
    if (!converged) ++stats_.unconverged;
  }

 private:
  void resize_like(const state_type& x) {
    auto shape = [&](state_type& s) {
      s.q.resize(x.q.rows(), x.q.cols());
      s.p.resize(x.p.rows(), x.p.cols());
    };
    shape(stage_);
    shape(znew_);
    for (auto& z : z_) shape(z);
  }
  static bool same(const state_type& a, const state_type& b) {
    return a.q.rows() == b.q.rows() && a.q.cols() == b.q.cols() && a.q == b.q && a.p == b.p;
  }
  /// out = h sum_j w_j F_j.
  void combine(const std::array<Scalar, Stages>& w, Scalar h, state_type& out) const {
    out.q = (w[0] * h) * f_[0].q;
    out.p = (w[0] * h) * f_[0].p;
    for (std::size_t j = 1; j < Stages; ++j) {
      out.q += (w[j] * h) * f_[j].q;
      out.p += (w[j] * h) * f_[j].p;
    }
  }
  /// max_k |znew_k - z_k| / (|y_k| + |znew_k|): the increment in units of the components.
  template <class M>
  static Scalar increment(const M& znew, const M& z, const M& y) {
    const Scalar tiny = std::numeric_limits<Scalar>::min();
    return ((znew - z).array().abs() / (y.array().abs() + znew.array().abs() + tiny)).maxCoeff();
  }

  GaussTableau<Scalar, Stages> tab_;
  ChartField<Chart> field_;
  std::size_t max_iterations_;
  IterationStatistics stats_;
  state_type y0_, stage_, znew_, last_out_;
  std::array<state_type, Stages> z_, f_;
  bool have_history_ = false;
  Scalar last_dt_{};
};

/// The implicit midpoint rule (order 2, the seed's comparator), Gauss 4 and Gauss 6.
template <class Chart>
using ImplicitMidpoint = Gauss<Chart, 1>;
template <class Chart>
using Gauss4 = Gauss<Chart, 2>;
template <class Chart>
using Gauss6 = Gauss<Chart, 3>;

}  // namespace sesi::reference
