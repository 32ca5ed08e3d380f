#pragma once
/// @file reference/embedding.hpp
/// Reference methods in the embedding of S^n and H^n (issue #4): positions x_b on the quadric
/// <x,x> = s R^2 (s = +1: the sphere |x| = R; s = -1: the hyperboloid <x,x>_L = -R^2 with the
/// Minkowski product of hyperbolic.hpp) and velocities v_b tangent to it (<x,v> = 0).
/// The same System as the chart steppers supplies the forces: System::ambient_gradient fills
/// ws.G from ws.X with dV/dx (partial derivatives; their normal part does not matter).
///
/// Equations of motion (Lagrangian L = sum m/2 <v,v> - V with the constraint):
///   m x'' = -eta dV/dx + lambda x,   eta = I (S^n) or diag(1, .., 1, -1) (H^n),
/// so the acceleration of body b is a_b = -eta G_b / m_b up to a multiple of x_b.
///
/// Two methods:
///  (a) RATTLE (H. C. Andersen, J. Comput. Phys. 52 (1983) 24; B. Leimkuhler, R. D. Skeel,
///      J. Comput. Phys. 112 (1994) 117; Hairer, Lubich, Wanner, Geometric Numerical
///      Integration, 2nd ed. (GNI), Sec. VII.1.4): symplectic on the constrained cotangent
///      bundle, order 2, one force evaluation per step. The constraint is
///      quadratic, so its multiplier is the small root of a quadratic, solved in closed form.
///  (b) Geodesic splitting: the exact geodesic flow of the kinetic energy (great circles,
///      hyperbolas) and the exact flow of the potential (a kick by the tangential force), each
///      symplectic on T*M; the symmetric base step, composed with the coefficient tables of the
///      chart steppers (coefficients.hpp), has the table's order. Same construction as the
///      geodesic integrators of B. Leimkuhler, C. Matthews, Proc. R. Soc. A 472 (2016) 20160138
///      (there with a stochastic part).
/// RATTLE is a symmetric second-order base step too, so it composes with the same tables.

#include <array>
#include <cmath>
#include <cstddef>
#include <type_traits>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "sesi/coefficients.hpp"
#include "sesi/config.hpp"
#include "sesi/processed.hpp"
#include "sesi/spaces/hyperbolic.hpp"
#include "sesi/spaces/sphere.hpp"
#include "sesi/special_functions.hpp"
#include "sesi/state.hpp"
#include "sesi/stepper.hpp"
#include "sesi/system.hpp"

namespace sesi::reference {

/// The quadric a chart embeds in: its sign s (<x,x> = s R^2), metric eta, radius.
template <class Chart>
struct Quadric;  // S^n and H^n only

template <int N, class Scalar_>
struct Quadric<Sphere<N, Scalar_>> {
  using Scalar = Scalar_;
  static constexpr int sign = 1;
  /// Euclidean product.
  template <class A, class B>
  static Scalar dot(const Eigen::MatrixBase<A>& u, const Eigen::MatrixBase<B>& v) {
    return u.dot(v);
  }
  /// eta g (identity).
  template <class G>
  static void raise(Eigen::MatrixBase<G>&) {}
};

template <int N, class Scalar_>
struct Quadric<Hyperbolic<N, Scalar_>> {
  using Scalar = Scalar_;
  static constexpr int sign = -1;
  /// Minkowski product, time-like coordinate last.
  template <class A, class B>
  static Scalar dot(const Eigen::MatrixBase<A>& u, const Eigen::MatrixBase<B>& v) {
    return minkowski(u, v);
  }
  /// eta g: flip the time-like component.
  template <class G>
  static void raise(Eigen::MatrixBase<G>& g) {
    const Eigen::Index t = g.size() - 1;
    g[t] = -g[t];
  }
};

/// Charts that embed in a quadric (S^n, H^n of any dimension and Scalar).
template <class Chart>
concept QuadricChart = requires {
  Quadric<Chart>::sign;
};

/// The state of N bodies in the embedding: column b holds body b's position and velocity.
template <QuadricChart Chart>
struct EmbeddedState {
  using Scalar = typename Chart::Scalar;
  using Matrix = Eigen::Matrix<Scalar, Chart::ambient_dimension, Eigen::Dynamic>;

  Matrix x;  ///< positions on the quadric, ambient_dim x bodies
  Matrix v;  ///< velocities, tangent: <x_b, v_b> = 0

  EmbeddedState() = default;
  EmbeddedState(int ambient, int bodies)
      : x(Matrix::Zero(ambient, bodies)), v(Matrix::Zero(ambient, bodies)) {}

  int bodies() const { return static_cast<int>(x.cols()); }
};

/// The embedding state of a chart state: x_b = embed(q_b), v_b = J(q_b) dq_b/dt.
template <class Sys>
EmbeddedState<typename Sys::Chart> to_embedded(const Sys& sys,
                                               const State<typename Sys::Chart>& s) {
  using Chart = typename Sys::Chart;
  EmbeddedState<Chart> e(sys.ambient_dim(), s.bodies());
  typename Chart::Point q(sys.dim()), p(sys.dim());
  typename Chart::Ambient x(sys.ambient_dim()), v(sys.ambient_dim());
  for (int b = 0; b < s.bodies(); ++b) {
    q = s.q.col(b);
    p = s.p.col(b);
    sys.chart().embed(q, x);
    sys.chart().velocity(q, p, sys.mass(b), v);
    e.x.col(b) = x;
    e.v.col(b) = v;
  }
  return e;
}

namespace detail {
/// chart.chart(x, q), kept out of line: inlined next to a local Ambient, GCC 12 reports a false
/// -Warray-bounds in Hyperbolic::chart (x.head(dim_) on a fixed-size vector, read as if dim_
/// could exceed the size).
template <class Chart>
[[gnu::noinline]] void chart_coordinates(const Chart& chart, const typename Chart::Ambient& x,
                                         typename Chart::Point& q) {
  chart.chart(x, q);
}
}  // namespace detail

/// The chart state of an embedding state: q_b = chart(x_b) (angles in their principal ranges),
/// p_b = m_b J^T eta v_b.
template <class Sys>
State<typename Sys::Chart> to_chart(const Sys& sys, const EmbeddedState<typename Sys::Chart>& e) {
  using Chart = typename Sys::Chart;
  State<Chart> s(sys.dim(), e.bodies());
  typename Chart::Point q(sys.dim()), p(sys.dim());
  typename Chart::Ambient x(sys.ambient_dim()), v(sys.ambient_dim());
  for (int b = 0; b < e.bodies(); ++b) {
    x = e.x.col(b);
    v = e.v.col(b);
    detail::chart_coordinates(sys.chart(), x, q);
    sys.chart().momentum(q, v, sys.mass(b), p);
    s.q.col(b) = q;
    s.p.col(b) = p;
  }
  return s;
}

/// Total energy of an embedding state: sum m/2 <v,v> plus the potential (evaluated through the
/// chart, since System exposes the potential of a chart state only).
template <class Sys>
typename Sys::Scalar energy(const Sys& sys, const EmbeddedState<typename Sys::Chart>& e) {
  using Q = Quadric<typename Sys::Chart>;
  using Scalar = typename Sys::Scalar;
  Scalar k(0);
  for (int b = 0; b < e.bodies(); ++b)
    k += sys.mass(b) * Q::dot(e.v.col(b), e.v.col(b)) / Scalar(2);
  return k + sys.potential_energy(to_chart(sys, e));
}

namespace detail {

/// Shared parts of the embedding steppers: the force cache and the projections.
template <QuadricChart Chart>
class EmbeddingBase {
 public:
  using Scalar = typename Chart::Scalar;
  using state_type = EmbeddedState<Chart>;
  using deriv_type = EmbeddedState<Chart>;
  using value_type = Scalar;
  using time_type = Scalar;
  using order_type = unsigned short;
  using Matrix = typename state_type::Matrix;
  using Q = Quadric<Chart>;

  /// Force evaluations since construction.
  std::size_t evaluations() const { return evaluations_; }

 protected:
  /// acc_.col(b) = -eta G_b / m_b at positions X (one force evaluation); skipped when X is
  /// where the cache was filled (first-same-as-last across stages and steps).
  template <class Sys>
  void accelerations(const Sys& sys, const Matrix& X) {
    if (cached_ && cache_x_.cols() == X.cols() && cache_x_ == X) return;
    if (ws_.X.cols() != X.cols()) ws_ = sys.make_workspace();
    ++evaluations_;
    ws_.X = X;
    sys.ambient_gradient(ws_);
    acc_.resize(X.rows(), X.cols());
    for (int b = 0; b < X.cols(); ++b) {
      auto a = acc_.col(b);
      a = -ws_.G.col(b) / sys.mass(b);
      Q::raise(a);
    }
    cache_x_ = X;
    cached_ = true;
  }
  /// Put every column of X back on the quadric and every column of V back in its tangent
  /// space, correcting round-off only (the exact flows keep both invariants).
  static void retract(const Chart& chart, Matrix& X, Matrix& V) {
    using std::sqrt;
    const Scalar r = chart.radius();
    for (int b = 0; b < X.cols(); ++b) {
      auto x = X.col(b);
      auto v = V.col(b);
      const Scalar xx = Q::dot(x, x);
      x *= r / sqrt(Scalar(Q::sign) * xx);
      v -= (Q::dot(x, v) / (Scalar(Q::sign) * r * r)) * x;
    }
  }

  Workspace<Chart> ws_;
  Matrix acc_, cache_x_;
  bool cached_ = false;
  std::size_t evaluations_ = 0;
};

}  // namespace detail

/// RATTLE on S^n or H^n, composed with a coefficient table (Strang: plain RATTLE, order 2).
/// One step of length h from (x, v), per body (GNI Sec. VII.1.4 with mass matrix m eta):
///   v' = v + h/2 (a(x) + mu x),         x1 = x + h v',   <x1, x1> = s R^2
///   v1 = v' + h/2 (a(x1) + nu x1),      <x1, v1> = 0.
/// With d = h v + h^2/2 a and x1 = x + d + c x (c = h^2 mu / 2), the position constraint is
///   <x,x> c^2 + 2 (<x,x> + <x,d>) c + (<x,x> - s R^2 + 2 <x,d> + <d,d>) = 0,
/// whose root with c -> 0 as h -> 0 is taken in the cancellation-free form
///   c = -C / (B + sgn(B) sqrt(B^2 - A C)).
/// (Keeping <x,x> - s R^2 in C removes the round-off drift of the constraint.) The velocity
/// constraint is linear: nu from <x1, v1> = 0.
template <class Table, QuadricChart Chart>
class RattleComposition : public detail::EmbeddingBase<Chart> {
  using Base = detail::EmbeddingBase<Chart>;
  using Q = typename Base::Q;

 public:
  using typename Base::Matrix;
  using typename Base::order_type;
  using typename Base::Scalar;
  using typename Base::state_type;
  using typename Base::time_type;
  using table = Table;

  static constexpr order_type order_value = Table::order;
  static constexpr order_type order() { return Table::order; }

  RattleComposition() : w_(Table::template weights<Scalar>()) {
    if constexpr (Chart::ambient_dimension != Eigen::Dynamic) d_.setZero();  // copies stay defined
  }

  template <class Sys>
  void do_step(Sys&& system, state_type& s, time_type /*t*/, time_type dt) {
    using Raw = std::remove_cvref_t<Sys>;
    const auto& sys = sesi::detail::unwrap<Raw>::get(system);
    for (std::size_t k = 0; k < Table::stages; ++k) stage(sys, s, w_[k] * dt);
  }

 private:
  template <class Sys>
  void stage(const Sys& sys, state_type& s, Scalar h) {
    using std::sqrt;
    const Scalar r2 = sys.chart().radius() * sys.chart().radius();
    const Scalar target = Scalar(Q::sign) * r2;
    this->accelerations(sys, s.x);
    for (int b = 0; b < s.bodies(); ++b) {
      auto x = s.x.col(b);
      auto v = s.v.col(b);
      d_ = h * v + (h * h / Scalar(2)) * this->acc_.col(b);
      const Scalar xx = Q::dot(x, x), xd = Q::dot(x, d_);
      const Scalar A = xx, B = xx + xd, C = (xx - target) + Scalar(2) * xd + Q::dot(d_, d_);
      const Scalar disc = B * B - A * C;
      SESI_CHECK(disc >= Scalar(0),
                 "RATTLE: no position on the sphere within reach (step too large)");
      const Scalar root = sqrt(disc > Scalar(0) ? disc : Scalar(0));
      const Scalar c = -C / (B + (B < Scalar(0) ? -root : root));
      // v' = (x1 - x)/h = (d + c x)/h, then x1 = x + d + c x.
      v = (d_ + c * x) / h;
      x += d_ + c * x;
    }
    this->accelerations(sys, s.x);
    for (int b = 0; b < s.bodies(); ++b) {
      auto x = s.x.col(b);
      auto v = s.v.col(b);
      v += (h / Scalar(2)) * this->acc_.col(b);
      v -= (Q::dot(x, v) / Q::dot(x, x)) * x;  // nu: the velocity constraint <x1, v1> = 0
    }
  }

  std::array<Scalar, Table::stages> w_;
  typename Chart::Ambient d_;
};

/// Geodesic splitting on S^n or H^n: the symmetric base step drift(h/2) kick(h) drift(h/2)
/// (Form = drift_kick_drift) or kick(h/2) drift(h) kick(h/2) (kick_drift_kick), composed with
/// a coefficient table; adjacent half flows of the same kind are fused, so a step of s stages
/// costs s force evaluations (kick-drift-kick reuses the last step's force).
///  drift(h): the geodesic of each body, w = sqrt(<v,v>)/R, th = w h,
///    S^n: x <- cos(th) x + h sinc(th) v,   v <- cos(th) v - h w^2 sinc(th) x
///    H^n: x <- cosh(th) x + h sinhc(th) v, v <- cosh(th) v + h w^2 sinhc(th) x
///    (sinc, sinhc of special_functions.hpp: exact and finite as w -> 0);
///  kick(h): v <- v + h P_x(a), a = -eta dV/dx / m, P_x u = u - (<u,x>/<x,x>) x the projection
///    on the tangent space (Minkowski on H^n).
/// Each step ends with a round-off retraction (x rescaled to <x,x> = s R^2, v made tangent).
/// With Table = coefficients::Runtime the weights are given at run time (as sesi::Composition:
/// one engine for every table, stepping bit for bit as the fixed table's; the program's
/// geodesic methods).
template <class Table, QuadricChart Chart, Splitting Form = Splitting::drift_kick_drift>
class GeodesicComposition : public detail::EmbeddingBase<Chart> {
  using Base = detail::EmbeddingBase<Chart>;
  using Q = typename Base::Q;
  static constexpr bool runtime_table = std::is_same_v<Table, coefficients::Runtime>;

 public:
  using typename Base::Matrix;
  using typename Base::order_type;
  using typename Base::Scalar;
  using typename Base::state_type;
  using typename Base::time_type;
  using table = Table;
  using weights_type =
      std::conditional_t<runtime_table, std::vector<Scalar>, std::array<Scalar, Table::stages>>;

  /// The table's order (0 for a runtime table: ask order()).
  static constexpr order_type order_value = Table::order;
  constexpr order_type order() const {
    if constexpr (runtime_table) {
      return order_;
    } else {
      return Table::order;
    }
  }

  GeodesicComposition() requires(!runtime_table) : w_(Table::template weights<Scalar>()) { clear(); }
  /// A runtime table: palindromic weights summing to 1, of the given order.
  GeodesicComposition(std::vector<Scalar> weights, order_type order) requires runtime_table
      : w_(std::move(weights)), order_(order) {
    SESI_CHECK(!w_.empty(), "a composition needs at least one stage");
    clear();
  }
  /// A runtime-table composition with the weights and order of a fixed table T.
  template <class T>
  static GeodesicComposition of() requires runtime_table {
    const auto w = T::template weights<Scalar>();
    return GeodesicComposition(std::vector<Scalar>(w.begin(), w.end()), T::order);
  }
  std::size_t stages() const { return w_.size(); }
  const weights_type& weights() const { return w_; }

  template <class Sys>
  void do_step(Sys&& system, state_type& s, time_type /*t*/, time_type dt) {
    using Raw = std::remove_cvref_t<Sys>;
    const auto& sys = sesi::detail::unwrap<Raw>::get(system);
    const std::size_t n = w_.size();
    Scalar pending = w_[0] * dt / Scalar(2);  // half flow carried over to the next stage
    for (std::size_t k = 0; k < n; ++k) {
      const Scalar h = w_[k] * dt;
      if constexpr (Form == Splitting::drift_kick_drift) {
        drift(sys.chart(), s, pending);
        kick(sys, s, h);
      } else {
        kick(sys, s, pending);
        drift(sys.chart(), s, h);
      }
      pending = h / Scalar(2) + (k + 1 < n ? w_[k + 1] * dt / Scalar(2) : Scalar(0));
    }
    // The round-off retraction goes before the last kick in the kick-drift-kick form, so that
    // the force of that kick is the one at the returned positions (reused by the next step).
    if constexpr (Form == Splitting::drift_kick_drift) {
      drift(sys.chart(), s, pending);
      this->retract(sys.chart(), s.x, s.v);
    } else {
      this->retract(sys.chart(), s.x, s.v);
      kick(sys, s, pending);
    }
  }

 private:
  void clear() {
    if constexpr (Chart::ambient_dimension != Eigen::Dynamic) {  // copies stay defined
      x_.setZero();
      a_.setZero();
    }
  }
  void drift(const Chart& chart, state_type& s, Scalar h) {
    using std::cos;
    using std::cosh;
    using std::sqrt;
    const Scalar r = chart.radius();
    for (int b = 0; b < s.bodies(); ++b) {
      auto x = s.x.col(b);
      auto v = s.v.col(b);
      const Scalar vv = Q::dot(v, v);
      const Scalar w2 = (vv > Scalar(0) ? vv : Scalar(0)) / (r * r);
      const Scalar th = sqrt(w2) * h;
      Scalar c, sc;  // cos(th) and sin(th)/th, or their hyperbolic versions
      if constexpr (Q::sign > 0) {
        c = cos(th);
        sc = special::sinc(th);
      } else {
        c = cosh(th);
        sc = special::sinhc(th);
      }
      const Scalar to_x = h * sc, to_v = Scalar(-Q::sign) * h * w2 * sc;
      x_ = x;
      x = c * x + to_x * v;
      v = c * v + to_v * x_;
    }
  }
  template <class Sys>
  void kick(const Sys& sys, state_type& s, Scalar h) {
    this->accelerations(sys, s.x);
    for (int b = 0; b < s.bodies(); ++b) {
      auto x = s.x.col(b);
      a_ = this->acc_.col(b);
      a_ -= (Q::dot(a_, x) / Q::dot(x, x)) * x;
      s.v.col(b) += h * a_;
    }
  }

  weights_type w_;
  order_type order_ = Table::order;
  typename Chart::Ambient x_, a_;
};

/// The named methods.
template <class Chart>
using Rattle = RattleComposition<coefficients::Strang, Chart>;
template <class Chart>
using Geodesic2 = GeodesicComposition<coefficients::Strang, Chart>;
template <class Chart>
using Geodesic4 = GeodesicComposition<coefficients::Yoshida4, Chart>;
template <class Chart>
using Geodesic6 = GeodesicComposition<coefficients::Yoshida6, Chart>;

/// Processed methods over the geodesic splitting (issue #15): the processed tables of
/// coefficients.hpp (Blanes 2001, Blanes-Casas-Murua 2006) with the geodesic base step in place
/// of the chart's. The construction (sesi::Processed, processed.hpp) needs of its base step only
/// that it be symmetric and of second order, which the geodesic splitting is (HLW V.3.3); the
/// state stepped is the kernel's variables, read through post_process.
template <class Table, class Chart>
using GeodesicProcessed = sesi::Processed<Table, Chart, Splitting::drift_kick_drift, GeodesicComposition>;

}  // namespace sesi::reference
