#pragma once
/// @file runtime_composition.hpp
/// sesi::Composition with its coefficient table chosen at run time.
///
/// The library's engine (include/sesi/stepper.hpp, drift-kick-drift form) takes the table as a
/// template argument, so a program offering every table would compile the engine once per
/// (space, dimension, table). This is the same algorithm, step for step and operation for
/// operation (tests/program/test_runtime_composition.cpp checks that the two agree bit for
/// bit), with the weights in a vector: one engine per (space, dimension) serves all tables.
/// A candidate for the library (as sesi::Composition over a runtime table).

#include <cstddef>
#include <string_view>
#include <vector>

#include <sesi/chart.hpp>
#include <sesi/state.hpp>
#include <sesi/system.hpp>

namespace sesi::program {

template <sesi::HierarchicalChart Chart>
class RuntimeComposition {
 public:
  using Scalar = typename Chart::Scalar;
  using state_type = sesi::State<Chart>;

  /// The weights of a library coefficient table (include/sesi/coefficients.hpp).
  template <class Table>
  static RuntimeComposition of() {
    const auto w = Table::template weights<Scalar>();
    return RuntimeComposition(std::vector<Scalar>(w.begin(), w.end()));
  }

  explicit RuntimeComposition(std::vector<Scalar> weights) : w_(std::move(weights)) {}

  const std::vector<Scalar>& weights() const { return w_; }

  /// Advance x from t to t + dt in place (as sesi::Composition::do_step).
  template <class Sys>
  void do_step(const Sys& sys, state_type& x, Scalar /*t*/, Scalar dt) {
    // The trig caches left by the last step are valid if q is what that step produced.
    if (!(last_q_.cols() == x.q.cols() && last_q_.rows() == x.q.rows() && last_q_ == x.q)) {
      sys.refresh(x, ws_);
    }
    step_dkd(sys, x, dt);
    last_q_ = x.q;
  }

 private:
  void flow(const Chart& chart, int b, int i, Scalar m, Scalar h, bool own_trig = true) {
    if constexpr (sesi::HasTrigCache<Chart>) {
      chart.level_flow(i, ws_.q, ws_.p, m, h, ws_.trig[static_cast<std::size_t>(b)], own_trig);
    } else {
      sesi::level_flow(chart, i, ws_.q, ws_.p, m, h);
    }
  }
  template <class Sys, class F>
  void each_body(const Sys& sys, state_type& x, F&& f) {
    for (int b = 0; b < sys.bodies(); ++b) {
      ws_.q = x.q.col(b);
      ws_.p = x.p.col(b);
      f(b, sys.mass(b));
      x.q.col(b) = ws_.q;
      x.p.col(b) = ws_.p;
    }
  }
  /// Level 0 for time h0, levels 1..last for time h, on every body.
  template <class Sys>
  void forward(const Sys& sys, state_type& x, Scalar h0, Scalar h, int last) {
    each_body(sys, x, [&](int b, Scalar m) {
      if (h0 != Scalar(0)) flow(sys.chart(), b, 0, m, h0);
      for (int i = 1; i <= last; ++i) flow(sys.chart(), b, i, m, h);
    });
  }
  /// Levels from..1 for time h, then level 0 for time h0; the top level's own sine is left
  /// stale (nothing reads it before the next forward pass flows it again).
  template <class Sys>
  void backward(const Sys& sys, state_type& x, Scalar h, Scalar h0, int from) {
    each_body(sys, x, [&](int b, Scalar m) {
      for (int i = from; i >= 1; --i) flow(sys.chart(), b, i, m, h, i != from);
      if (h0 != Scalar(0)) flow(sys.chart(), b, 0, m, h0, from != 0);
    });
  }
  /// The seed's base step composed over the weights, level-0 half flows of neighbouring stages
  /// fused into one.
  template <class Sys>
  void step_dkd(const Sys& sys, state_type& x, Scalar dt) {
    const int top = sys.dim() - 1;
    const std::size_t s = w_.size();
    Scalar pending = w_[0] * dt / Scalar(2);
    for (std::size_t k = 0; k < s; ++k) {
      const Scalar half = w_[k] * dt / Scalar(2);
      forward(sys, x, pending, half, top);
      sys.kick_cached(x, w_[k] * dt, ws_);
      pending = half + (k + 1 < s ? w_[k + 1] * dt / Scalar(2) : Scalar(0));
      backward(sys, x, half, k + 1 < s ? Scalar(0) : pending, top);
    }
  }

  std::vector<Scalar> w_;
  sesi::Workspace<Chart> ws_;
  typename state_type::Matrix last_q_;
};

}  // namespace sesi::program
