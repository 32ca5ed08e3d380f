#pragma once
/// @file odeint.hpp
/// Interoperation with Boost.Odeint (optional target sesi::odeint; the core never includes Boost).
///
/// sesi::odeint::stepper<Method> is a sesi stepper with odeint's stepper_category tag, so that
/// boost::numeric::odeint::integrate_const / integrate_n_steps / integrate_times drive it with an
/// observer. The system may be passed by value, as std::ref or as boost::ref.

#include <type_traits>
#include <utility>

#include <boost/numeric/odeint/stepper/stepper_categories.hpp>
#include <boost/ref.hpp>

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

}  // namespace sesi::odeint
