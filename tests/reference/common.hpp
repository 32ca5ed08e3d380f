// Shared problems and measurements of the reference-method tests.
#pragma once

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include <sesi/scenes/paper.hpp>
#include <sesi/sesi.hpp>

namespace reftest {

namespace paper = sesi::scenes::paper;

/// A smooth pair term: a spring k d^2 / 2 with a Gaussian core a exp(-d^2 / 2 s^2). Both are
/// smooth functions of d^2, so the force has no kink at collisions (a spring on d - d0 has one:
/// the direction of the distance gradient flips there), and every method sees its nominal order.
template <class Scalar, class Kind>
struct SoftSpring {
  using distance_kind = Kind;
  Scalar k, a, s;
  template <class Space>
  Scalar value(const Space&, Scalar d, Scalar, Scalar) const {
    using std::exp;
    return k / 2 * d * d + a * exp(-d * d / (2 * s * s));
  }
  template <class Space>
  Scalar derivative(const Space&, Scalar d, Scalar, Scalar) const {
    using std::exp;
    return k * d - a * d / (s * s) * exp(-d * d / (2 * s * s));
  }
};

/// Three bodies on H^2 with soft springs on the geodesic distance, in geodesic polar coordinates
/// away from the chart origin.
template <class Scalar = double>
auto hyperbolic_system() {
  using Chart = sesi::Hyperbolic<2, Scalar>;
  return sesi::System(
      Chart(Scalar(1)), std::vector<Scalar>{Scalar(1), Scalar(2), Scalar(1.5)},
      SoftSpring<Scalar, sesi::geodesic_distance>{Scalar(0.5), Scalar(0.3), Scalar(0.5)});
}
template <class Scalar = double>
sesi::State<sesi::Hyperbolic<2, Scalar>> hyperbolic_initial() {
  sesi::State<sesi::Hyperbolic<2, Scalar>> x(2, 3);
  x.q << Scalar(1.5), Scalar(1.8), Scalar(1.6), Scalar(0.0), Scalar(0.5), Scalar(1.0);
  x.p << Scalar(0.05), Scalar(-0.1), Scalar(0.0), Scalar(0.6), Scalar(-0.5), Scalar(0.4);
  return x;
}

/// Three bodies on S^3 (radius 1.5) with soft springs on the chord, away from the chart's poles.
template <class Scalar = double>
auto sphere3_system() {
  using Chart = sesi::Sphere<3, Scalar>;
  return sesi::System(
      Chart(Scalar(1.5)), std::vector<Scalar>{Scalar(1), Scalar(0.5), Scalar(2)},
      SoftSpring<Scalar, sesi::chord_distance>{Scalar(1), Scalar(0.5), Scalar(0.5)});
}
template <class Scalar = double>
sesi::State<sesi::Sphere<3, Scalar>> sphere3_initial() {
  sesi::State<sesi::Sphere<3, Scalar>> x(3, 3);
  x.q << Scalar(1.2), Scalar(1.6), Scalar(1.4), Scalar(1.3), Scalar(1.6), Scalar(1.9), Scalar(0.3),
      Scalar(1.0), Scalar(0.2);
  x.p << Scalar(0.1), Scalar(-0.2), Scalar(0.1), Scalar(0.2), Scalar(0.1), Scalar(-0.3),
      Scalar(0.3), Scalar(-0.1), Scalar(0.2);
  return x;
}

/// x after `steps` steps of `dt` with a fresh Stepper.
template <class Stepper, class Sys, class StateT, class... Args>
StateT run(const Sys& sys, StateT x, double t_end, long steps, Args... args) {
  using Scalar = typename Sys::Scalar;
  Stepper stepper(args...);
  const Scalar dt = Scalar(t_end) / Scalar(steps);
  for (long k = 0; k < steps; ++k) stepper.do_step(sys, x, Scalar(k) * dt, dt);
  return x;
}

/// Distance between two states (chart: q and p; embedding: x and v), max norm.
template <class StateT>
double distance(const StateT& a, const StateT& b) {
  if constexpr (requires { a.q; }) {
    return double(std::max((a.q - b.q).template lpNorm<Eigen::Infinity>(),
                           (a.p - b.p).template lpNorm<Eigen::Infinity>()));
  } else {
    return double(std::max((a.x - b.x).template lpNorm<Eigen::Infinity>(),
                           (a.v - b.v).template lpNorm<Eigen::Infinity>()));
  }
}

/// Measured order from runs with N, 2N, 4N steps: the differences of neighbouring runs fall by
/// 2^order (the seed's convergence test, Suppl. Fig.).
template <class Stepper, class Sys, class StateT, class... Args>
double measured_order(const Sys& sys, const StateT& x0, double t_end, long steps, Args... args) {
  const auto a = run<Stepper>(sys, x0, t_end, steps, args...);
  const auto b = run<Stepper>(sys, x0, t_end, 2 * steps, args...);
  const auto c = run<Stepper>(sys, x0, t_end, 4 * steps, args...);
  return std::log2(distance(a, b) / distance(b, c));
}

/// Maximum |E - E0| over the first and the second half of a run.
struct EnergyHalves {
  double first = 0, second = 0;
};
template <class Stepper, class Sys, class StateT, class EnergyFn, class... Args>
EnergyHalves energy_halves(const Sys& sys, StateT x, double dt, double t_end, EnergyFn energy,
                           Args... args) {
  using Scalar = typename Sys::Scalar;
  Stepper stepper(args...);
  const double e0 = double(energy(x));
  const long steps = std::lround(t_end / dt);
  EnergyHalves h;
  for (long k = 0; k < steps; ++k) {
    stepper.do_step(sys, x, Scalar(k) * Scalar(dt), Scalar(dt));
    double& slot = k < steps / 2 ? h.first : h.second;
    slot = std::max(slot, std::abs(double(energy(x)) - e0));
  }
  return h;
}

}  // namespace reftest
