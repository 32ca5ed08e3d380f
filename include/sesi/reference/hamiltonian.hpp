#pragma once
/// @file reference/hamiltonian.hpp
/// The first-order Hamiltonian ODE in chart coordinates, shared by every reference method
/// (issue #4): the same System and State as the chart steppers, no Boost.
///
///   dq/dt =  dH/dp,   dH/dp_i = dK_i/dp_i                      (the chart's kinetic_dp)
///   dp/dt = -dH/dq,   dH/dq_k = sum_{i>k} dK_i/dq_k + dV/dq_k  (kinetic_dq, and
///                                                               System::potential_gradient)
///
/// with H = sum_b sum_i K_i(q_b, p_b; m_b) + V (seed paper, Discussion; system.hpp). One call of
/// the field is one force evaluation (one potential gradient): the unit in which the reference
/// methods count their work.

#include <algorithm>
#include <cstddef>
#include <type_traits>

#include <Eigen/Core>

#include "sesi/chart.hpp"
#include "sesi/state.hpp"
#include "sesi/system.hpp"

namespace sesi::reference {

/// Evaluation of the Hamiltonian vector field for the systems of one chart type: owns the
/// scratch space (sized on first use: later evaluations allocate nothing) and counts
/// evaluations; the system is passed to each call, so that steppers templated on the chart
/// alone (like the chart steppers) can own one.
template <HierarchicalChart Chart>
class ChartField {
 public:
  using Scalar = typename Chart::Scalar;
  using StateType = State<Chart>;
  using Matrix = typename StateType::Matrix;

  ChartField() {
    // Fixed-size members start defined, so that copying a fresh stepper copies no garbage.
    if constexpr (Chart::dimension != Eigen::Dynamic) {
      q_.setZero();
      p_.setZero();
    }
  }

  /// dxdt = (dH/dp, -dH/dq) at x; dxdt is resized to x's shape if needed.
  template <class Sys>
  void evaluate(const Sys& sys, const StateType& x, StateType& dxdt) {
    static_assert(std::is_same_v<typename Sys::Chart, Chart>, "system and field charts differ");
    ++evaluations_;
    const Chart& chart = sys.chart();
    const int n = sys.dim();
    if (q_.size() != n) {
      q_.resize(n);
      p_.resize(n);
    }
    sys.potential_gradient(x, ws_, grad_);  // sizes ws_ and grad_ on first use
    dxdt.q.resize(n, x.bodies());
    dxdt.p.resize(n, x.bodies());
    for (int b = 0; b < x.bodies(); ++b) {
      q_ = x.q.col(b);
      p_ = x.p.col(b);
      const Scalar m = sys.mass(b);
      for (int i = 0; i < n; ++i) dxdt.q(i, b) = chart.kinetic_dp(i, q_, p_[i], m);
      // K_i depends on q_k only for k < i (chart.hpp), so dH/dq_k sums the levels above k.
      for (int k = 0; k < n; ++k) {
        Scalar dh = grad_(k, b);
        for (int i = k + 1; i < n; ++i) dh += chart.kinetic_dq(i, k, q_, p_[i], m);
        dxdt.p(k, b) = -dh;
      }
    }
  }

  /// Force evaluations since construction or the last reset.
  std::size_t evaluations() const { return evaluations_; }
  void reset_evaluations() { evaluations_ = 0; }

 private:
  Workspace<Chart> ws_;
  Matrix grad_;  // dV/dq, dim x bodies
  typename Chart::Point q_, p_;
  std::size_t evaluations_ = 0;
};

/// The Hamiltonian vector field of one System: a ChartField bound to the system, which must
/// outlive it. field(x, dxdt) is one force evaluation.
template <class Sys>
class HamiltonianField : public ChartField<typename Sys::Chart> {
 public:
  using System = Sys;
  using Chart = typename Sys::Chart;
  using StateType = State<Chart>;

  explicit HamiltonianField(const Sys& sys) : sys_(&sys) {}

  const Sys& system() const { return *sys_; }
  void operator()(const StateType& x, StateType& dxdt) { this->evaluate(*sys_, x, dxdt); }

 private:
  const Sys* sys_;
};

/// Length of the flat layout of a state: q (column-major, dim x bodies), then p.
template <class Chart>
std::size_t flat_size(const State<Chart>& s) {
  return static_cast<std::size_t>(2 * s.q.size());
}

/// Copy s into a flat vector y (std::vector or Eigen vector), resized: q column-major, then p.
template <class Chart, class Vec>
void to_flat(const State<Chart>& s, Vec& y) {
  const auto n = static_cast<std::size_t>(s.q.size());
  y.resize(static_cast<decltype(y.size())>(2 * n));
  std::copy(s.q.data(), s.q.data() + n, y.data());
  std::copy(s.p.data(), s.p.data() + n, y.data() + n);
}

/// Copy a flat vector back into s, which must already have its shape (dim x bodies).
template <class Chart, class Vec>
void from_flat(const Vec& y, State<Chart>& s) {
  const auto n = static_cast<std::size_t>(s.q.size());
  SESI_CHECK(static_cast<std::size_t>(y.size()) == 2 * n, "flat vector does not match the state");
  std::copy(y.data(), y.data() + n, s.q.data());
  std::copy(y.data() + n, y.data() + 2 * n, s.p.data());
}

}  // namespace sesi::reference
