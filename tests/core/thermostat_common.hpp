// Shared measurements of the thermostat tests (tests/core/thermostat*.cpp): the Kolmogorov-Smirnov
// statistic and its critical value, CDFs by quadrature and in closed form, wells on S^n and H^n,
// and a sampler of one body's distance to a well's centre and kinetic energy.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <numbers>
#include <string>
#include <vector>

#include <doctest/doctest.h>

#include "common.hpp"

#include <sesi/special_functions.hpp>
#include <sesi/thermostat.hpp>

namespace thermotest {

/// The Kolmogorov-Smirnov statistic sup |F_N - F| of the sample against the CDF F.
inline double ks_statistic(std::vector<double> x, const std::function<double(double)>& cdf) {
  std::sort(x.begin(), x.end());
  const double n = static_cast<double>(x.size());
  double d = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    const double f = cdf(x[i]);
    d = std::max({d, (static_cast<double>(i) + 1) / n - f, f - static_cast<double>(i) / n});
  }
  return d;
}
/// The 1 % critical value of the KS statistic for N samples (asymptotic Kolmogorov law:
/// P(sqrt(N) D > 1.628) = 0.01; 1.63 rounds it up).
inline double ks_critical(std::size_t n) { return 1.63 / std::sqrt(static_cast<double>(n)); }

inline void check_ks(const std::string& what, const std::vector<double>& x, const std::function<double(double)>& cdf) {
  const double d = ks_statistic(x, cdf), crit = ks_critical(x.size());
  MESSAGE(what, ": KS statistic ", d, " against the 1 % critical value ", crit, " (N = ", x.size(), ")");
  CHECK(d < crit);
}

/// The CDF of a density on [0, b] by the cumulative trapezoidal rule on m intervals, read by
/// linear interpolation (the densities here are smooth: the error is O((b/m)^2), below 1e-9).
struct QuadratureCdf {
  double b;
  std::vector<double> c;
  QuadratureCdf(const std::function<double(double)>& density, double b_, int m)
      : b(b_), c(static_cast<std::size_t>(m) + 1) {
    const double h = b / m;
    c[0] = 0;
    for (int i = 1; i <= m; ++i)
      c[static_cast<std::size_t>(i)] = c[static_cast<std::size_t>(i) - 1] + h / 2 * (density((i - 1) * h) + density(i * h));
    for (double& v : c) v /= c.back();
  }
  double operator()(double x) const {
    if (x <= 0) return 0;
    if (x >= b) return 1;
    const double u = x / b * static_cast<double>(c.size() - 1);
    const auto i = static_cast<std::size_t>(u);
    const double w = u - static_cast<double>(i);
    return i + 1 < c.size() ? (1 - w) * c[i] + w * c[i + 1] : 1.0;
  }
};

/// The chi-squared CDF with n = 1, 2 or 3 degrees of freedom (2K/kT of one body in n dimensions:
/// K/kT ~ Gamma(n/2)), in closed form: erf(sqrt(x/2)); 1 - e^{-x/2}; erf(sqrt(x/2)) - sqrt(2x/pi) e^{-x/2}.
inline double chi2_cdf(int n, double x) {
  if (x <= 0) return 0;
  switch (n) {
    case 1:
      return std::erf(std::sqrt(x / 2));
    case 2:
      return -std::expm1(-x / 2);
    default:
      return std::erf(std::sqrt(x / 2)) - std::sqrt(2 * x / std::numbers::pi) * std::exp(-x / 2);
  }
}

/// V = k/2 d(x, c)^2 about a centre c of H^n (radius 1): gradient k d grad d, as
/// Hyperbolic::distance_gradient writes grad d (its d / sinh d by special::sinhc, smooth at d = 0).
template <class Chart>
struct HyperbolicWell {
  using Ambient = typename Chart::Ambient;
  double k;
  Ambient c;
  double value(const Chart& space, const Ambient& x, double m) const {
    const double d = space.distance(x, c);
    return m * k / 2 * d * d;
  }
  void gradient(const Chart& space, const Ambient& x, double m, Ambient& g) const {
    const double d = space.distance(x, c);
    const int n = static_cast<int>(x.size()) - 1;
    const double ab = x.head(n).dot(c.head(n)) - x[n] * c[n];  // <x, c>_L = -cosh d
    g = -(c + ab * x);
    g[n] = -g[n];
    g *= m * k / sesi::special::sinhc(d);
  }
};

struct Samples {
  std::vector<double> distance, two_k;  // distance to the centre, 2 K / kT
};

/// One body of unit mass started at rest at the well's centre, thermalised for `burn` steps, then
/// sampled every `stride` steps, with the given stepper (a thermostatted engine).
template <class Sys, class Stepper>
Samples sample(const Sys& sys, Stepper& stepper, const typename Sys::Chart::Point& q0,
               const typename Sys::Chart::Ambient& centre, double kT, double dt, int burn, int stride, int n) {
  using Chart = typename Sys::Chart;
  const int dim = static_cast<int>(q0.size());
  sesi::State<Chart> x(dim, 1);
  x.q.col(0) = q0;
  long k = 0;
  for (; k < burn; ++k) stepper.do_step(sys, x, static_cast<double>(k) * dt, dt);
  Samples s;
  typename Chart::Point q(dim);
  typename Chart::Ambient y(dim + 1);
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < stride; ++i, ++k) stepper.do_step(sys, x, static_cast<double>(k) * dt, dt);
    q = x.q.col(0);
    sys.chart().embed(q, y);
    s.distance.push_back(sys.chart().distance(y, centre));
    s.two_k.push_back(2 * sys.kinetic_energy(x) / kT);
  }
  return s;
}

/// The canonical marginal of the distance a to a well's centre on S^n (chord well V = k/2 |x - c|^2
/// = k (1 - cos a), R = 1): density sin^{n-1}(a) exp(-k (1 - cos a) / kT) on [0, pi].
inline QuadratureCdf sphere_well_cdf(int n, double bk) {
  return QuadratureCdf([=](double a) { return std::pow(std::sin(a), n - 1) * std::exp(-bk * (1 - std::cos(a))); },
                       std::numbers::pi, 200000);
}
/// On H^n (central well V = k/2 d^2): density sinh^{n-1}(r) exp(-k r^2 / 2kT) on [0, 3] (beyond 3
/// it is below e^-170 for the wells here, k/kT >= 40).
inline QuadratureCdf hyperbolic_well_cdf(int n, double bk) {
  return QuadratureCdf([=](double r) { return std::pow(std::sinh(r), n - 1) * std::exp(-bk * r * r / 2); }, 3.0,
                       300000);
}

}  // namespace thermotest
