#pragma once
/// @file reference/odeint.hpp
/// Non-symplectic references through Boost.Odeint (optional target sesi::odeint; issue #4):
/// Dormand-Prince 5(4), Runge-Kutta-Fehlberg 7(8), Bulirsch-Stoer and classical RK4 on the
/// chart ODE (sesi::odeint::chart_ode of sesi/odeint.hpp), over [t0, t1] from and to
/// State<Chart>, counting force evaluations (right-hand-side calls) and calling an observer at
/// given sample times.

#include <algorithm>
#include <cstddef>
#include <functional>
#include <span>
#include <vector>

#include <boost/numeric/odeint/integrate/integrate_adaptive.hpp>
#include <boost/numeric/odeint/integrate/integrate_times.hpp>
#include <boost/numeric/odeint/stepper/bulirsch_stoer.hpp>
#include <boost/numeric/odeint/stepper/bulirsch_stoer_dense_out.hpp>
#include <boost/numeric/odeint/stepper/controlled_runge_kutta.hpp>
#include <boost/numeric/odeint/stepper/dense_output_runge_kutta.hpp>
#include <boost/numeric/odeint/stepper/generation.hpp>
#include <boost/numeric/odeint/stepper/runge_kutta4.hpp>
#include <boost/numeric/odeint/stepper/runge_kutta_dopri5.hpp>
#include <boost/numeric/odeint/stepper/runge_kutta_fehlberg78.hpp>

#include "sesi/odeint.hpp"
#include "sesi/reference/integrate.hpp"
#include "sesi/state.hpp"

namespace sesi::odeint {

/// Error tolerances and first step of the adaptive integrators (odeint's meaning: the local
/// error of each component is kept below absolute + relative * |x| (dopri5, fehlberg78; see
/// odeint's default_error_checker), resp. the Bulirsch-Stoer analogue).
template <class Scalar>
struct tolerances {
  Scalar absolute = Scalar(1e-10);
  Scalar relative = Scalar(1e-10);
  Scalar initial_step = Scalar(1e-2);
};

/// What a reference run returns: the final state (at t1), the steps odeint took and the force
/// evaluations (calls of the right-hand side) it made.
template <class Chart>
struct result {
  State<Chart> state;
  std::size_t steps = 0;
  std::size_t evaluations = 0;
};

namespace detail {

/// Observation times for integrate_times: t0, the requested times inside (t0, t1), t1; and for
/// each whether the caller asked for it.
template <class Scalar>
struct time_plan {
  std::vector<Scalar> times;
  std::vector<char> wanted;
  time_plan(Scalar t0, Scalar t1, std::span<const Scalar> requested) {
    auto asked = [&](Scalar t) {
      return std::find(requested.begin(), requested.end(), t) != requested.end();
    };
    times.push_back(t0);
    wanted.push_back(asked(t0));
    for (Scalar t : requested) {
      if (t > t0 && t < t1) {
        times.push_back(t);
        wanted.push_back(1);
      }
    }
    times.push_back(t1);
    wanted.push_back(asked(t1));
  }
};

/// odeint observer on the flat vector, calling observer(State, t) at the wanted times only.
template <class Sys, class Observer>
struct flat_observer {
  chart_ode<Sys>* ode;
  const time_plan<typename Sys::Scalar>* plan;
  Observer* observer;
  State<typename Sys::Chart>* buffer;
  std::size_t next = 0;
  void operator()(const std::vector<typename Sys::Scalar>& y, typename Sys::Scalar t) {
    if (next < plan->wanted.size() && plan->wanted[next]) {
      ode->unflat(y, *buffer);
      (*observer)(static_cast<const State<typename Sys::Chart>&>(*buffer), t);
    }
    ++next;
  }
};

/// Run an adaptive odeint stepper: integrate_adaptive without sampling, else integrate_times
/// with the sampling stepper (dense output where odeint has one).
template <class Sys, class Adaptive, class Sampling, class Observer>
result<typename Sys::Chart> run_adaptive(const Sys& sys, const State<typename Sys::Chart>& x0,
                                         typename Sys::Scalar t0, typename Sys::Scalar t1,
                                         typename Sys::Scalar dt, Adaptive adaptive,
                                         Sampling sampling,
                                         std::span<const typename Sys::Scalar> times,
                                         Observer& observer) {
  namespace ode = boost::numeric::odeint;
  chart_ode<Sys> f(sys);
  auto y = f.flat(x0);
  result<typename Sys::Chart> r;
  if (times.empty()) {
    r.steps = ode::integrate_adaptive(adaptive, std::ref(f), y, t0, t1, dt);
  } else {
    const time_plan<typename Sys::Scalar> plan(t0, t1, times);
    State<typename Sys::Chart> buffer;
    flat_observer<Sys, Observer> obs{&f, &plan, &observer, &buffer};
    r.steps = ode::integrate_times(sampling, std::ref(f), y, plan.times.begin(), plan.times.end(),
                                   dt, std::ref(obs));
  }
  f.unflat(y, r.state);
  r.evaluations = f.evaluations();
  return r;
}

}  // namespace detail

/// Dormand-Prince 5(4) (J. R. Dormand, P. J. Prince, J. Comput. Appl. Math. 6 (1980) 19; the
/// seed's "RK45"), step size controlled by tol; sampling at `times` uses its dense output
/// (order-4 interpolation), so the observer does not change the steps.
/// @param times sorted observation times; those in [t0, t1] are passed to observer(State, t).
template <class Sys, class Observer = reference::NoObserver>
result<typename Sys::Chart> integrate_dopri5(const Sys& sys, const State<typename Sys::Chart>& x0,
                                             typename Sys::Scalar t0, typename Sys::Scalar t1,
                                             tolerances<typename Sys::Scalar> tol = {},
                                             std::span<const typename Sys::Scalar> times = {},
                                             Observer&& observer = Observer{}) {
  namespace ode = boost::numeric::odeint;
  using Scalar = typename Sys::Scalar;
  using stepper = ode::runge_kutta_dopri5<std::vector<Scalar>, Scalar>;
  return detail::run_adaptive(sys, x0, t0, t1, tol.initial_step,
                              ode::make_controlled(tol.absolute, tol.relative, stepper()),
                              ode::make_dense_output(tol.absolute, tol.relative, stepper()), times,
                              observer);
}

/// Runge-Kutta-Fehlberg 7(8) (E. Fehlberg, NASA TR R-287 (1968)), step size controlled by tol.
/// odeint has no dense output for it: sampling shortens the steps that straddle a sample time.
template <class Sys, class Observer = reference::NoObserver>
result<typename Sys::Chart> integrate_fehlberg78(const Sys& sys,
                                                 const State<typename Sys::Chart>& x0,
                                                 typename Sys::Scalar t0, typename Sys::Scalar t1,
                                                 tolerances<typename Sys::Scalar> tol = {},
                                                 std::span<const typename Sys::Scalar> times = {},
                                                 Observer&& observer = Observer{}) {
  namespace ode = boost::numeric::odeint;
  using Scalar = typename Sys::Scalar;
  using stepper = ode::runge_kutta_fehlberg78<std::vector<Scalar>, Scalar>;
  auto controlled = ode::make_controlled(tol.absolute, tol.relative, stepper());
  return detail::run_adaptive(sys, x0, t0, t1, tol.initial_step, controlled, controlled, times,
                              observer);
}

/// Bulirsch-Stoer extrapolation (odeint's bulirsch_stoer; Hairer, Norsett, Wanner, Solving
/// ODEs I, Sec. II.9), step size and order controlled by tol; sampling uses
/// bulirsch_stoer_dense_out.
template <class Sys, class Observer = reference::NoObserver>
result<typename Sys::Chart> integrate_bulirsch_stoer(
    const Sys& sys, const State<typename Sys::Chart>& x0, typename Sys::Scalar t0,
    typename Sys::Scalar t1, tolerances<typename Sys::Scalar> tol = {},
    std::span<const typename Sys::Scalar> times = {}, Observer&& observer = Observer{}) {
  namespace ode = boost::numeric::odeint;
  using Scalar = typename Sys::Scalar;
  using state = std::vector<Scalar>;
  return detail::run_adaptive(
      sys, x0, t0, t1, tol.initial_step,
      ode::bulirsch_stoer<state, Scalar>(tol.absolute, tol.relative),
      ode::bulirsch_stoer_dense_out<state, Scalar>(tol.absolute, tol.relative), times, observer);
}

/// The classical fourth-order Runge-Kutta method with fixed step dt (the last step shorter if
/// t1 - t0 is not a whole number of steps), sampled at the grid points nearest to `times`
/// (reference::integrate_fixed: sampling never changes the step).
template <class Sys, class Observer = reference::NoObserver>
result<typename Sys::Chart> integrate_rk4(const Sys& sys, const State<typename Sys::Chart>& x0,
                                          typename Sys::Scalar t0, typename Sys::Scalar t1,
                                          typename Sys::Scalar dt,
                                          std::span<const typename Sys::Scalar> times = {},
                                          Observer&& observer = Observer{}) {
  namespace ode = boost::numeric::odeint;
  using Scalar = typename Sys::Scalar;
  using state = std::vector<Scalar>;
  chart_ode<Sys> f(sys);
  struct rk4_on_flat {
    ode::runge_kutta4<state, Scalar> rk;
    chart_ode<Sys>* f;
    void do_step(const Sys&, state& y, Scalar t, Scalar h) { rk.do_step(std::ref(*f), y, t, h); }
  } stepper{{}, &f};
  State<typename Sys::Chart> buffer;
  auto obs = [&](const state& y, Scalar t) {
    f.unflat(y, buffer);
    observer(static_cast<const State<typename Sys::Chart>&>(buffer), t);
  };
  auto y = f.flat(x0);
  result<typename Sys::Chart> r;
  r.steps = reference::integrate_fixed(stepper, sys, y, t0, t1, dt, times, obs);
  f.unflat(y, r.state);
  r.evaluations = f.evaluations();
  return r;
}

}  // namespace sesi::odeint
