// Langevin BAOAB (include/sesi/thermostat.hpp) samples the canonical distribution: one body in a
// well samples the exact Boltzmann marginal of its distance to the well's centre (S^2, S^3: chord
// well, density sin^{n-1}(a) exp(-V/kT); H^2, H^3: central harmonic well, sinh^{n-1}(r) exp(-V/kT))
// and the kinetic energy's law (2K/kT chi-squared with n degrees of freedom, K/kT ~ Gamma(n/2)),
// by Kolmogorov-Smirnov tests at the 1 % level for the number of samples; issue #25.
#include <cmath>
#include <cstdint>
#include <string>

#include <doctest/doctest.h>

#include "thermostat_common.hpp"

namespace {

using namespace coretest;
using namespace thermotest;

// The runs: kT = 1, m = 1, well stiffness k = 40 (frequency omega = sqrt(40) = 6.3, spread of the
// distance ~ sqrt(n/40) <= 0.27, far from the charts' singular points: the sphere centres are
// >= 1 rad from a pole, the hyperbolic ones at radius 1.5), friction gamma = 10 (damped
// oscillation, decay rate gamma/2 = 5), dt = 0.005, N = 10000 samples every 200 steps (1 time unit:
// correlation e^-5 < 1 %, so the samples are close to independent and the KS law applies), after
// 2000 steps (10 time units) from rest at the centre.
// The bias: BAOAB's configurational error is O(h^2); for this well it is of relative size
// (omega h)^2 = 1e-3 (exact for a harmonic well with one exact A flow; the hierarchical A sweep
// adds an error of that order; thermostat_bias.cpp measures it), so the CDF moves by about 1e-3
// times max x f(x) < 1e-3, and the kinetic law by the same order: both well below the KS
// resolution 1.63 / sqrt(N) = 0.0163.
constexpr double well_kT = 1, well_k = 40, well_gamma = 10, well_dt = 0.005;
constexpr int well_burn = 2000, well_stride = 200, well_samples = 10000;

template <class Chart, class Term>
void check_well(const std::string& name, const Chart& chart, const typename Chart::Point& qc, Term term,
                const QuadratureCdf& cdf) {
  const int n = static_cast<int>(qc.size());
  typename Chart::Ambient centre(n + 1);
  chart.embed(qc, centre);
  term.c = centre;
  const sesi::System sys(chart, std::vector<double>{1.0}, term);
  sesi::LangevinBAOAB<Chart> stepper(well_kT, well_gamma, 2025);
  const Samples s = sample(sys, stepper, qc, centre, well_kT, well_dt, well_burn, well_stride, well_samples);
  check_ks(name + " distance to the centre", s.distance, [&](double a) { return cdf(a); });
  check_ks(name + " 2K/kT", s.two_k, [&](double x) { return chi2_cdf(n, x); });
}

TEST_CASE("langevin: one body in a chord well on S^2 samples sin(a) exp(-V/kT) and chi-squared(2)") {
  using S2 = sesi::Sphere<2, double>;
  const double bk = well_k / well_kT;
  const QuadratureCdf cdf = sphere_well_cdf(2, bk);
  // The quadrature against the closed form (1 - e^{-bk (1 - cos a)}) / (1 - e^{-2 bk}).
  const auto exact = [&](double a) { return -std::expm1(-bk * (1 - std::cos(a))) / -std::expm1(-2 * bk); };
  for (double a = 0; a < 1.5; a += 0.01) REQUIRE(std::abs(cdf(a) - exact(a)) < 1e-8);
  S2::Point qc(2);
  qc << 1.0, 0.3;
  // V = k/2 |x - c|^2 = k (1 - cos a) at angle a from the centre (R = 1).
  check_well("S^2", S2(1.0), qc, Trap<S2>{well_k, S2::Ambient()}, cdf);
}

TEST_CASE("langevin: one body in a chord well on S^3 samples sin^2(a) exp(-V/kT) and chi-squared(3)") {
  using S3 = sesi::Sphere<3, double>;
  S3::Point qc(3);
  qc << 1.4, 1.3, 0.3;  // >= 1.3 rad from the chart's singular set
  check_well("S^3", S3(1.0), qc, Trap<S3>{well_k, S3::Ambient()}, sphere_well_cdf(3, well_k / well_kT));
}

TEST_CASE("langevin: one body in a central harmonic well on H^2 samples sinh(r) exp(-V/kT) and chi-squared(2)") {
  using H2 = sesi::Hyperbolic<2, double>;
  H2::Point qc(2);
  qc << 1.5, 0.4;
  check_well("H^2", H2(1.0), qc, HyperbolicWell<H2>{well_k, H2::Ambient()}, hyperbolic_well_cdf(2, well_k / well_kT));
}

TEST_CASE("langevin: one body in a central harmonic well on H^3 samples sinh^2(r) exp(-V/kT) and chi-squared(3)") {
  using H3 = sesi::Hyperbolic<3, double>;
  H3::Point qc(3);
  qc << 1.5, 1.2, 0.4;
  check_well("H^3", H3(1.0), qc, HyperbolicWell<H3>{well_k, H3::Ambient()}, hyperbolic_well_cdf(3, well_k / well_kT));
}

}  // namespace
