// The Langevin thermostat (include/sesi/thermostat.hpp, BAOAB) and its counter-based normals
// (include/sesi/random.hpp); issue #25, docs/thermostats.md.
//
//  - gamma = 0 is the engine's kick-drift-kick Strang step bit for bit (S^2, H^2);
//  - the normals are a pure function of their key; a run is a pure function of (seed, state,
//    step counter): the same seed gives the same trajectory, a resumed run the same bits, one
//    thread and two the same bits;
//  - one body in a well samples the exact Boltzmann marginal of its distance to the well's
//    centre (S^2: chord well, H^2: central harmonic well) and the kinetic energy's chi-squared
//    law, by Kolmogorov-Smirnov tests at the 1 % level for the number of samples.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include <doctest/doctest.h>

#include "common.hpp"

#include <sesi/random.hpp>
#include <sesi/special_functions.hpp>
#include <sesi/thermostat.hpp>

namespace {

using namespace coretest;
using S2 = sesi::Sphere<2, double>;
using H2 = sesi::Hyperbolic<2, double>;

// ---- gamma = 0 ------------------------------------------------------------------------------

// BAOAB with no friction is B A A B with the two top-level half flows fused (as the engine fuses
// them), i.e. the kick-drift-kick Strang step: the same operations in the same order, so the
// states must agree to the bit. (The drift-kick-drift Sesi2 is a different step.)
template <class Chart>
void check_zero_friction() {
  const auto sys = make_scene<Chart>();
  auto a = initial_state(sys);
  auto b = a;
  sesi::Composition<sesi::coefficients::Strang, Chart, sesi::Splitting::kick_drift_kick> nve;
  sesi::LangevinBAOAB<Chart> langevin(1.0, 0.0, 12345);
  const double dt = 0.01;
  for (int k = 0; k < 500; ++k) {
    nve.do_step(sys, a, k * dt, dt);
    langevin.do_step(sys, b, k * dt, dt);
  }
  CHECK(langevin.step() == 500);
  CHECK(a.q == b.q);
  CHECK(a.p == b.p);
  CHECK(a.q.array().isFinite().all());
}

TEST_CASE("langevin: gamma = 0 is the kick-drift-kick Strang step bit for bit (S^2, H^2)") {
  check_zero_friction<S2>();
  check_zero_friction<H2>();
}

// ---- determinism ----------------------------------------------------------------------------

TEST_CASE("random: the normals are a pure function of the key") {
  using sesi::random::normal;
  using sesi::random::normal_pair;
  const std::uint64_t s = sesi::random::stream::langevin;
  // Forwards, then backwards in another order of the key's words: the same numbers.
  std::vector<double> forward, backward;
  for (std::uint64_t step = 0; step < 4; ++step)
    for (std::uint64_t body = 0; body < 3; ++body)
      for (std::uint64_t c = 0; c < 5; ++c) forward.push_back(normal(99, s, step, body, c));
  backward.resize(forward.size());
  for (std::uint64_t c = 5; c-- > 0;)
    for (std::uint64_t body = 3; body-- > 0;)
      for (std::uint64_t step = 4; step-- > 0;) backward[(step * 3 + body) * 5 + c] = normal(99, s, step, body, c);
  CHECK(forward == backward);
  const auto z = normal_pair(99, s, 2, 1, 1);
  CHECK(z[0] == normal(99, s, 2, 1, 2));
  CHECK(z[1] == normal(99, s, 2, 1, 3));
  // Every word of the key matters.
  const double x = normal(99, s, 2, 1, 2);
  CHECK(x != normal(98, s, 2, 1, 2));
  CHECK(x != normal(99, sesi::random::stream::perturbation, 2, 1, 2));
  CHECK(x != normal(99, s, 3, 1, 2));
  CHECK(x != normal(99, s, 2, 0, 2));
  CHECK(x != normal(99, s, 2, 1, 0));
  CHECK(z[0] != z[1]);
}

TEST_CASE("langevin: same seed, same trajectory; a resumed run gives the same bits") {
  const auto sys = make_scene<S2>();
  const auto x0 = initial_state(sys);
  const double dt = 0.01;
  const auto run_from = [&](sesi::State<S2> x, std::uint64_t seed, std::uint64_t first, int steps) {
    sesi::LangevinBAOAB<S2> stepper(0.5, 2.0, seed, first);
    for (int k = 0; k < steps; ++k) stepper.do_step(sys, x, (double(first) + k) * dt, dt);
    return x;
  };
  const auto a = run_from(x0, 7, 0, 300);
  const auto b = run_from(x0, 7, 0, 300);
  CHECK(a.q == b.q);
  CHECK(a.p == b.p);
  // Resume: a fresh stepper at step 150 from the state after 150 steps.
  const auto c = run_from(run_from(x0, 7, 0, 150), 7, 150, 150);
  CHECK(a.q == c.q);
  CHECK(a.p == c.p);
  // Another seed, another trajectory.
  const auto d = run_from(x0, 8, 0, 300);
  CHECK(coretest::distance(a, d) > 1e-3);
}

TEST_CASE("langevin: the same bits on one thread and on two (600 bodies: the threaded loops)") {
  // 600 bodies >= 2 parallel::min_parallel_bodies, so two threads split the bodies into chunks.
  const S2 chart(1.0);
  S2::Ambient centre(3);
  centre << 0.6, 0.0, 0.8;
  const sesi::System sys(chart, std::vector<double>(600, 1.0), Trap<S2>{2.0, centre});
  sesi::State<S2> x0(2, 600);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int b = 0; b < 600; ++b) x0.set_body(b, {1.0 + 1.1 * u(rng), 6.28 * u(rng)}, {u(rng) - 0.5, u(rng) - 0.5});
  const auto run_on = [&](int threads) {
    sesi::parallel::set_threads(threads);
#if defined(_OPENMP)
    CHECK(sesi::parallel::chunks_for(600) == (threads == 1 ? 1 : 8));  // the loops do split
#endif
    auto x = x0;
    sesi::LangevinBAOAB<S2> stepper(1.0, 3.0, 5);
    for (int k = 0; k < 20; ++k) stepper.do_step(sys, x, k * 0.01, 0.01);
    sesi::parallel::set_threads(0);
    return x;
  };
  const auto one = run_on(1), two = run_on(2);
  CHECK(one.q == two.q);
  CHECK(one.p == two.p);
}

// ---- the canonical distribution ---------------------------------------------------------------

/// The Kolmogorov-Smirnov statistic sup |F_N - F| of the sample against the CDF F.
double ks_statistic(std::vector<double> x, const std::function<double(double)>& cdf) {
  std::sort(x.begin(), x.end());
  const double n = static_cast<double>(x.size());
  double d = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    const double f = cdf(x[i]);
    d = std::max({d, (static_cast<double>(i) + 1) / n - f, f - static_cast<double>(i) / n});
  }
  return d;
}
/// The 1 % critical value of the KS statistic for N samples (asymptotic: 1.628 / sqrt(N)).
double ks_critical(std::size_t n) { return 1.63 / std::sqrt(static_cast<double>(n)); }

/// The CDF of a density on [0, b] by the cumulative trapezoidal rule on m intervals, read by
/// linear interpolation (the density here is smooth: the error is O((b/m)^2), below 1e-9).
struct QuadratureCdf {
  double b;
  std::vector<double> c;
  QuadratureCdf(const std::function<double(double)>& density, double b_, int m) : b(b_), c(static_cast<std::size_t>(m) + 1) {
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

/// V = k/2 d(x, c)^2 about a centre c of H^n (radius 1): gradient k d grad d, as
/// Hyperbolic::distance_gradient writes grad d (its d / sinh d by special::sinhc, smooth at d = 0).
struct HyperbolicWell {
  using Ambient = H2::Ambient;
  double k;
  Ambient c;
  double value(const H2& space, const Ambient& x, double m) const {
    const double d = space.distance(x, c);
    return m * k / 2 * d * d;
  }
  void gradient(const H2& space, const Ambient& x, double m, Ambient& g) const {
    const double d = space.distance(x, c);
    const double ab = x.head<2>().dot(c.head<2>()) - x[2] * c[2];  // <x, c>_L = -cosh d
    g = -(c + ab * x);
    g[2] = -g[2];
    g *= m * k / sesi::special::sinhc(d);
  }
};

struct Samples {
  std::vector<double> distance, two_k;  // distance to the centre, 2 K / kT
};

/// One body of unit mass started at rest at the well's centre, thermalised for `burn` steps, then
/// sampled every `stride` steps.
template <class Sys>
Samples sample(const Sys& sys, const typename Sys::Chart::Point& q0, const typename Sys::Chart::Ambient& centre,
               double kT, double gamma, double dt, int burn, int stride, int n, std::uint64_t seed) {
  using Chart = typename Sys::Chart;
  sesi::State<Chart> x(2, 1);
  x.q.col(0) = q0;
  sesi::LangevinBAOAB<Chart> stepper(kT, gamma, seed);
  long k = 0;
  for (; k < burn; ++k) stepper.do_step(sys, x, k * dt, dt);
  Samples s;
  typename Chart::Point q(2);
  typename Chart::Ambient y(3);
  for (int j = 0; j < n; ++j) {
    for (int i = 0; i < stride; ++i, ++k) stepper.do_step(sys, x, k * dt, dt);
    q = x.q.col(0);
    sys.chart().embed(q, y);
    s.distance.push_back(sys.chart().distance(y, centre));
    s.two_k.push_back(2 * sys.kinetic_energy(x) / kT);
  }
  return s;
}

// The runs: kT = 1, m = 1, well stiffness k = 40 (frequency omega = sqrt(40) = 6.3, spread of the
// distance ~ 1/sqrt(40) = 0.16, far from the charts' singular points: the S^2 centre is 1 rad
// from the pole, the H^2 centre at radius 1.5), friction gamma = 10 (damped oscillation, decay
// rate gamma/2 = 5), dt = 0.005, N = 10000 samples every 200 steps (1 time unit: correlation
// e^-5 < 1 %, so the samples are close to independent and the KS law applies), after 2000 steps
// (10 time units) from rest at the centre.
// The bias: BAOAB's configurational error is O(h^2); for this well it is of relative size
// (omega h)^2 = 1e-3 (exact for a harmonic well with one exact A flow; the hierarchical A sweep
// adds an error of that order), so the CDF moves by about 1e-3 times max x f(x) < 1e-3, and the
// kinetic law by the same order: both well below the KS resolution 1.63 / sqrt(N) = 0.0163.
constexpr double well_kT = 1, well_k = 40, well_gamma = 10, well_dt = 0.005;
constexpr int well_burn = 2000, well_stride = 200, well_samples = 10000;

void check_ks(const char* what, const std::vector<double>& x, const std::function<double(double)>& cdf) {
  const double d = ks_statistic(x, cdf), crit = ks_critical(x.size());
  MESSAGE(std::string(what), ": KS statistic ", d, " against the 1 % critical value ", crit, " (N = ", x.size(), ")");
  CHECK(d < crit);
}

/// 2K / kT of one body on a 2-dimensional space: chi-squared with 2 degrees of freedom.
double chi2_2_cdf(double x) { return x <= 0 ? 0 : -std::expm1(-x / 2); }

TEST_CASE("langevin: one body in a chord well on S^2 samples sin(a) exp(-V/kT) and chi-squared(2)") {
  const S2 chart(1.0);
  S2::Point qc(2);
  qc << 1.0, 0.3;
  S2::Ambient centre(3);
  chart.embed(qc, centre);
  // V = k/2 |x - c|^2 = k (1 - cos a) at angle a from the centre (R = 1).
  const sesi::System sys(chart, std::vector<double>{1.0}, Trap<S2>{well_k, centre});
  const Samples s = sample(sys, qc, centre, well_kT, well_gamma, well_dt, well_burn, well_stride, well_samples, 2025);
  const double bk = well_k / well_kT;
  const auto density = [&](double a) { return std::sin(a) * std::exp(-bk * (1 - std::cos(a))); };
  const QuadratureCdf cdf(density, std::numbers::pi, 200000);
  // The quadrature against the closed form (1 - e^{-bk (1 - cos a)}) / (1 - e^{-2 bk}).
  const auto exact = [&](double a) { return -std::expm1(-bk * (1 - std::cos(a))) / -std::expm1(-2 * bk); };
  for (double a = 0; a < 1.5; a += 0.01) REQUIRE(std::abs(cdf(a) - exact(a)) < 1e-8);
  check_ks("S^2 angle to the centre", s.distance, [&](double a) { return cdf(a); });
  check_ks("S^2 2K/kT", s.two_k, chi2_2_cdf);
}

TEST_CASE("langevin: one body in a central harmonic well on H^2 samples sinh(r) exp(-V/kT) and chi-squared(2)") {
  const H2 chart(1.0);
  H2::Point qc(2);
  qc << 1.5, 0.4;
  H2::Ambient centre(3);
  chart.embed(qc, centre);
  const sesi::System sys(chart, std::vector<double>{1.0}, HyperbolicWell{well_k, centre});
  const Samples s = sample(sys, qc, centre, well_kT, well_gamma, well_dt, well_burn, well_stride, well_samples, 2025);
  const double bk = well_k / well_kT;
  // Density sinh(r) exp(-k r^2 / 2kT) on [0, 3] (beyond 3 it is below e^-170).
  const QuadratureCdf cdf([&](double r) { return std::sinh(r) * std::exp(-bk * r * r / 2); }, 3.0, 300000);
  check_ks("H^2 distance to the centre", s.distance, [&](double r) { return cdf(r); });
  check_ks("H^2 2K/kT", s.two_k, chi2_2_cdf);
}

}  // namespace
