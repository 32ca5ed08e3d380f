// Implicit references (reference/implicit.hpp): the Gauss-Legendre tableaus, the orders of the
// implicit midpoint rule and Gauss 4, bounded energy, the fixed-point iteration's work, and the
// seed's comparison on its own scene.
#include <cmath>
#include <limits>

#include <doctest/doctest.h>
#include <sesi/reference/implicit.hpp>

#include "common.hpp"

namespace {

namespace R = sesi::reference;
using reftest::measured_order;
namespace paper = reftest::paper;

template <class Scalar, std::size_t S>
void check_tableau() {
  const R::GaussTableau<Scalar, S> t;
  const Scalar eps = std::numeric_limits<Scalar>::epsilon();
  Scalar sum_b(0);
  for (std::size_t i = 0; i < S; ++i) {
    sum_b += t.b[i];
    Scalar row(0);
    for (std::size_t j = 0; j < S; ++j) {
      row += t.a[i][j];
      // Symplecticity of a Runge-Kutta method: b_i a_ij + b_j a_ji = b_i b_j (GNI Sec. VI.4).
      CHECK(std::abs(double(t.b[i] * t.a[i][j] + t.b[j] * t.a[j][i] - t.b[i] * t.b[j])) <=
            8 * double(eps));
    }
    CHECK(std::abs(double(row - t.c[i])) <= 8 * double(eps));  // c_i = sum_j a_ij
    // Extrapolation weights integrate the Lagrange basis over [1, 1 + c_i]: sum_j e_ij = c_i.
    Scalar erow(0);
    for (std::size_t j = 0; j < S; ++j) erow += t.e[i][j];
    CHECK(std::abs(double(erow - t.c[i])) <= 8 * double(eps));
  }
  CHECK(std::abs(double(sum_b - 1)) <= 8 * double(eps));
}

}  // namespace

TEST_CASE_TEMPLATE("Gauss-Legendre tableaus are consistent and symplectic in every Scalar", Scalar,
                   float, double, long double) {
  check_tableau<Scalar, 1>();
  check_tableau<Scalar, 2>();
  check_tableau<Scalar, 3>();
  // The published order-4 values (Hairer, Norsett, Wanner I, Sec. II.7): a_12 = 1/4 - sqrt3/6.
  const R::GaussTableau<Scalar, 2> t;
  CHECK(double(t.a[0][1]) == doctest::Approx(0.25 - std::sqrt(3.0) / 6).epsilon(1e-6));
  CHECK(double(t.a[1][0]) == doctest::Approx(0.25 + std::sqrt(3.0) / 6).epsilon(1e-6));
}

TEST_CASE("implicit midpoint and Gauss 4 converge at orders 2 and 4") {
  SUBCASE("the seed's scene to t = 10 (the seed's convergence test)") {
    const auto sys = paper::make_system<double>();
    const auto x0 = paper::initial_state<double>();
    const double mid = measured_order<R::ImplicitMidpoint<paper::Chart<double>>>(sys, x0, 10, 100);
    const double g4 = measured_order<R::Gauss4<paper::Chart<double>>>(sys, x0, 10, 50);
    MESSAGE("paper: midpoint ", mid, ", gauss4 ", g4);
    CHECK(std::abs(mid - 2) < 0.3);
    CHECK(std::abs(g4 - 4) < 0.3);
  }
  SUBCASE("H^2, three springs, to t = 3") {
    const auto sys = reftest::hyperbolic_system<double>();
    const auto x0 = reftest::hyperbolic_initial<double>();
    using C = sesi::Hyperbolic<2, double>;
    const double mid = measured_order<R::ImplicitMidpoint<C>>(sys, x0, 3, 100);
    const double g4 = measured_order<R::Gauss4<C>>(sys, x0, 3, 100);
    MESSAGE("H2: midpoint ", mid, ", gauss4 ", g4);
    CHECK(std::abs(mid - 2) < 0.3);
    CHECK(std::abs(g4 - 4) < 0.3);
  }
  SUBCASE("S^3, three springs, to t = 3") {
    const auto sys = reftest::sphere3_system<double>();
    const auto x0 = reftest::sphere3_initial<double>();
    using C = sesi::Sphere<3, double>;
    const double mid = measured_order<R::ImplicitMidpoint<C>>(sys, x0, 3, 50);
    const double g4 = measured_order<R::Gauss4<C>>(sys, x0, 3, 50);
    MESSAGE("S3: midpoint ", mid, ", gauss4 ", g4);
    CHECK(std::abs(mid - 2) < 0.3);
    CHECK(std::abs(g4 - 4) < 0.3);
  }
}

TEST_CASE("implicit midpoint and Gauss 4 keep the energy bounded over T = 800") {
  const auto sys = paper::make_system<double>();
  const auto x0 = paper::initial_state<double>();
  auto energy = [&](const auto& x) { return sys.energy(x); };
  const auto mid =
      reftest::energy_halves<R::ImplicitMidpoint<paper::Chart<double>>>(sys, x0, 0.1, 800, energy);
  const auto g4 =
      reftest::energy_halves<R::Gauss4<paper::Chart<double>>>(sys, x0, 0.1, 800, energy);
  MESSAGE("midpoint: ", mid.first, " / ", mid.second, "; gauss4: ", g4.first, " / ", g4.second);
  CHECK(mid.second <= 1.5 * mid.first);
  CHECK(g4.second <= 1.5 * g4.first);
  // (Chaotic orbits in a chart are not used here: their energy error peaks where a body passes
  // near a chart pole, so the maxima of two halves differ by the closest approaches, not drift.)
}

namespace {
/// Spectral radius of the Jacobian of the Hamiltonian field at x: the Jacobian by central
/// differences, the radius by Gelfand's formula rho = lim |J^k v|^{1/k} (generic v), which
/// spares this test Eigen's eigenvalue module (10 s of compile time).
template <class Sys>
double field_spectral_radius(const Sys& sys, const sesi::State<typename Sys::Chart>& x) {
  R::HamiltonianField<Sys> f(sys);
  std::vector<double> y0;
  R::to_flat(x, y0);
  const int n = static_cast<int>(y0.size());
  Eigen::MatrixXd jac(n, n);
  auto plus = x, minus = x, fp = x, fm = x;
  std::vector<double> yp, ym, gp, gm;
  for (int k = 0; k < n; ++k) {
    const double d = 1e-6 * std::max(1.0, std::abs(y0[size_t(k)]));
    yp = y0;
    ym = y0;
    yp[size_t(k)] += d;
    ym[size_t(k)] -= d;
    R::from_flat(yp, plus);
    R::from_flat(ym, minus);
    f(plus, fp);
    f(minus, fm);
    R::to_flat(fp, gp);
    R::to_flat(fm, gm);
    for (int i = 0; i < n; ++i) jac(i, k) = (gp[size_t(i)] - gm[size_t(i)]) / (2 * d);
  }
  Eigen::VectorXd v = Eigen::VectorXd::LinSpaced(n, 1.0, 2.0);
  double log_growth = 0;
  const int powers = 4000;
  for (int k = 0; k < powers; ++k) {
    v = jac * v;
    const double norm = v.norm();
    log_growth += std::log(norm);
    v /= norm;
  }
  return std::exp(log_growth / powers);
}
}  // namespace

TEST_CASE("the fixed-point iteration converges at the rate h rho(A) rho(f')") {
  // A sweep multiplies the error by the iteration matrix h A (x) f', of spectral radius
  // rho = h rho(A) rho(f'). From a relative starting error below 1, reaching the round-off unit
  // eps takes log(eps) / log(rho) sweeps, plus one to measure the last increment and two for
  // the zig-zag-proof stagnation test: a bound on the average (single steps may need a few
  // more: the iteration matrix is far from normal, its powers grow transiently).
  const auto sys = paper::make_system<double>();
  const double h = 0.1;
  auto x = paper::initial_state<double>();
  // rho(f') along the orbit: the largest over one radial period, sampled every step.
  double rho_f = 0;
  {
    sesi::KahanLi8<paper::Chart<double>> st;
    for (int k = 0; k < 32; ++k) {
      rho_f = std::max(rho_f, field_spectral_radius(sys, x));
      st.do_step(sys, x, k * h, h);
    }
  }
  const double eps = std::numeric_limits<double>::epsilon();
  auto bound = [&](double rho_a) { return std::log(eps) / std::log(h * rho_a * rho_f) + 3; };
  // rho(A): 1/2 for the midpoint rule; |(3 +- i sqrt3)/12| = 1/sqrt(12) for Gauss 4.
  const double rho_mid = 0.5, rho_g4 = 1 / std::sqrt(12.0);
  MESSAGE("rho(f') = ", rho_f, "; average sweeps bound: midpoint ", bound(rho_mid), ", gauss4 ",
          bound(rho_g4));

  R::ImplicitMidpoint<paper::Chart<double>> mid;
  R::Gauss4<paper::Chart<double>> g4;
  auto a = paper::initial_state<double>(), b = a;
  for (int k = 0; k < 8000; ++k) {
    mid.do_step(sys, a, k * h, h);
    g4.do_step(sys, b, k * h, h);
  }
  const auto& sm = mid.statistics();
  const auto& sg = g4.statistics();
  MESSAGE("midpoint: ", double(sm.iterations) / 8000, " sweeps/step (max ", sm.max_iterations,
          "); gauss4: ", double(sg.iterations) / 8000, " (max ", sg.max_iterations, ")");
  CHECK(sm.steps == 8000);
  CHECK(sm.unconverged == 0);
  CHECK(sg.unconverged == 0);
  CHECK(double(sm.iterations) / 8000 <= bound(rho_mid));
  CHECK(double(sg.iterations) / 8000 <= bound(rho_g4));
  // Evaluations: s per sweep, plus one for the explicit guess of the first step.
  CHECK(sm.evaluations == sm.iterations + 1);
  CHECK(sg.evaluations == 2 * sg.iterations + 1);
}

TEST_CASE("the seed's comparison: implicit midpoint at tau = 0.1 is in SESI 2's accuracy class") {
  // Both are symplectic of order 2: over T = 800 the energy error stays bounded (second half no
  // larger than 1.5 times the first) and, relative to E, below (h w)^2 with w the radial
  // frequency of the exact solution: the O(h^2) modified Hamiltonian with a constant of one.
  const auto sys = paper::make_system<double>();
  const auto x0 = paper::initial_state<double>();
  const paper::Exact exact;
  const double e = double(exact.energy()), w = double(exact.frequency()), h = 0.1;
  auto energy = [&](const auto& x) { return sys.energy(x); };
  const auto mid =
      reftest::energy_halves<R::ImplicitMidpoint<paper::Chart<double>>>(sys, x0, h, 800, energy);
  const auto sesi2 =
      reftest::energy_halves<sesi::Strang<paper::Chart<double>>>(sys, x0, h, 800, energy);
  MESSAGE("max |dE|: midpoint ", std::max(mid.first, mid.second), ", sesi2 ",
          std::max(sesi2.first, sesi2.second), ", bound ", h * w * h * w * e);
  for (const auto& r : {mid, sesi2}) {
    CHECK(r.second <= 1.5 * r.first);
    CHECK(std::max(r.first, r.second) <= h * w * h * w * e);
  }
}
