#pragma once
/// @file odeint.hpp
/// Interoperation with Boost.Odeint (optional target sesi::odeint; the core never includes Boost).
///
/// sesi::odeint::stepper<Method> is a sesi stepper with odeint's stepper_category tag, so that
/// boost::numeric::odeint::integrate_const / integrate_n_steps / integrate_times drive it with an
/// observer. The system may be passed by value, as std::ref or as boost::ref.
///
/// sesi::odeint::chart_ode (second part of this file, issue #4) is the Hamiltonian ODE of a
/// System in chart coordinates (reference/hamiltonian.hpp) on a flat std::vector<Scalar>
/// (q column-major, then p), which odeint's default range_algebra handles without any operator
/// added to another library's namespace. The drivers that run odeint's reference steppers on it
/// (integrate_dopri5, ...) are in sesi/reference/odeint.hpp, so that including this header
/// does not compile odeint's steppers.

#include <cstddef>
#include <type_traits>
#include <utility>
#include <vector>

#include <boost/numeric/odeint/stepper/stepper_categories.hpp>
#include <boost/ref.hpp>

#include "sesi/reference/hamiltonian.hpp"
#include "sesi/state.hpp"
#include "sesi/stepper.hpp"

namespace sesi::odeint {

template <class Method>
class stepper : public Method {
 public:
  using stepper_category = boost::numeric::odeint::stepper_tag;
  using typename Method::state_type;
  using typename Method::time_type;
  using Method::Method;

  template <class Sys>
  void do_step(Sys&& system, state_type& x, time_type t, time_type dt) {
    Method::do_step(boost::unwrap_ref(system), x, t, dt);
  }
};

/// The named methods as odeint steppers.
template <class Chart>
using strang = stepper<Strang<Chart>>;
template <class Chart>
using yoshida4 = stepper<Yoshida4<Chart>>;
template <class Chart>
using suzuki4 = stepper<Suzuki4<Chart>>;
template <class Chart>
using mclachlan4 = stepper<McLachlan4<Chart>>;
template <class Chart>
using yoshida6 = stepper<Yoshida6<Chart>>;
template <class Chart>
using kahan_li6 = stepper<KahanLi6<Chart>>;
template <class Chart>
using mclachlan8 = stepper<McLachlan8<Chart>>;
template <class Chart>
using kahan_li8 = stepper<KahanLi8<Chart>>;

// ---- the chart ODE for odeint's steppers (issue #4) ---------------------------------------

/// The Hamiltonian ODE of sys in chart coordinates on a flat std::vector<Scalar>, as an odeint
/// system: ode(y, dydt, t). Counts its calls (force evaluations). Pass it to odeint as
/// std::ref(ode): odeint copies systems, and the count and scratch space live here.
template <class Sys>
class chart_ode {
 public:
  using Chart = typename Sys::Chart;
  using Scalar = typename Sys::Scalar;
  using state_type = std::vector<Scalar>;
  using StateType = State<Chart>;

  explicit chart_ode(const Sys& sys)
      : field_(sys), x_(sys.dim(), sys.bodies()), dx_(sys.dim(), sys.bodies()) {}

  void operator()(const state_type& y, state_type& dydt, Scalar /*t*/) {
    reference::from_flat(y, x_);
    field_(x_, dx_);
    reference::to_flat(dx_, dydt);
  }

  /// Calls since construction.
  std::size_t evaluations() const { return field_.evaluations(); }
  const Sys& system() const { return field_.system(); }

  /// The flat vector of a state, and back (the state must have sys.bodies() bodies).
  state_type flat(const StateType& s) const {
    state_type y;
    reference::to_flat(s, y);
    return y;
  }
  void unflat(const state_type& y, StateType& s) const {
    s.q.resize(x_.q.rows(), x_.q.cols());
    s.p.resize(x_.p.rows(), x_.p.cols());
    reference::from_flat(y, s);
  }

 private:
  reference::HamiltonianField<Sys> field_;
  StateType x_, dx_;
};

}  // namespace sesi::odeint
