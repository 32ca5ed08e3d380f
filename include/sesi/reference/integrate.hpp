#pragma once
/// @file reference/integrate.hpp
/// A fixed-step driver with sampling, for every stepper with do_step(sys, x, t, dt): the chart
/// steppers, the reference steppers (implicit, Tao, embedding) and odeint's runge_kutta4.
///
/// Unlike odeint's integrate_times, which shortens a step to land on each observation time (and,
/// with times accumulated in floating point, can insert steps of round-off length), this driver
/// never changes the step: time k is t0 + k dt exactly, and each requested time is observed at
/// the nearest grid point, so sampling does not perturb the trajectory.

#include <cmath>
#include <cstddef>
#include <span>

namespace sesi::reference {

/// An observer that does nothing.
struct NoObserver {
  template <class StateT, class Scalar>
  void operator()(const StateT&, Scalar) const {}
};

/// Advance x from t0 to t1 with steps dt (the last one shorter if t1 - t0 is not a whole
/// number of steps), calling observer(x, t) at the grid point nearest to each of `times`
/// (sorted ascending; at most one call per grid point).
/// @return the number of steps taken.
template <class Stepper, class Sys, class StateT, class Scalar, class Observer = NoObserver>
std::size_t integrate_fixed(Stepper& stepper, const Sys& sys, StateT& x, Scalar t0, Scalar t1,
                            Scalar dt, std::span<const Scalar> times = {},
                            Observer&& observer = Observer{}) {
  using std::ceil;
  using std::fabs;
  using std::lround;
  const Scalar span = t1 - t0;
  if (!(span > Scalar(0)) || !(dt > Scalar(0))) {
    if (!times.empty()) observer(x, t0);
    return 0;
  }
  // A whole number of steps when t1 - t0 is one up to round-off, else one more, shorter step.
  long n = lround(span / dt);
  const bool whole = n >= 1 && fabs(Scalar(n) * dt - span) <= Scalar(1e-6) * dt;
  if (!whole) n = static_cast<long>(ceil(span / dt));
  auto grid = [&](long k) { return k == n ? t1 : t0 + Scalar(k) * dt; };
  std::size_t j = 0;
  auto sample = [&](long k) {
    const Scalar tk = grid(k);
    const Scalar upper = k == n ? Scalar(0) : (tk + grid(k + 1)) / Scalar(2);
    bool hit = false;
    while (j < times.size() && (k == n || times[j] < upper)) {
      hit = true;
      ++j;
    }
    if (hit) observer(x, tk);
  };
  sample(0);
  for (long k = 0; k < n; ++k) {
    // Every step is exactly dt (steppers that reuse the last step's data compare it), except a
    // shorter last one when t1 - t0 is not a whole number of steps.
    stepper.do_step(sys, x, grid(k), (whole || k + 1 < n) ? dt : t1 - grid(k));
    sample(k + 1);
  }
  return static_cast<std::size_t>(n);
}

}  // namespace sesi::reference
