// Tao's explicit method for non-separable Hamiltonians (reference/tao.hpp): orders 2 and 4 at a
// fixed binding omega, the doubled phase space, the work per step, bounded energy.
#include <cmath>

#include <doctest/doctest.h>
#include <sesi/reference/tao.hpp>

#include "common.hpp"

namespace {
namespace R = sesi::reference;
using reftest::measured_order;
namespace paper = reftest::paper;
}  // namespace

TEST_CASE("Tao's method converges at orders 2 and 4 for a fixed omega") {
  // For a fixed omega the method is a splitting of the augmented Hamiltonian, exact on the
  // diagonal, so it has the order of its composition; the asymptotic regime needs h omega
  // small (omega = 20, the default: h omega = 0.2 for order 2 (N = 100 steps over T = 1 or 3
  // is h omega = 0.2 or 0.6), 0.15 to 0.2 for order 4).
  const double omega = 20;
  SUBCASE("the seed's scene to t = 1") {
    const auto sys = paper::make_system<double>();
    const auto x0 = paper::initial_state<double>();
    const double o2 = measured_order<R::Tao2<paper::Chart<double>>>(sys, x0, 1, 100, omega);
    const double o4 = measured_order<R::Tao4<paper::Chart<double>>>(sys, x0, 1, 100, omega);
    MESSAGE("paper: tao2 ", o2, ", tao4 ", o4);
    CHECK(std::abs(o2 - 2) < 0.3);
    CHECK(std::abs(o4 - 4) < 0.3);
  }
  SUBCASE("S^3, three soft springs, to t = 3") {
    const auto sys = reftest::sphere3_system<double>();
    const auto x0 = reftest::sphere3_initial<double>();
    using C = sesi::Sphere<3, double>;
    const double o2 = measured_order<R::Tao2<C>>(sys, x0, 3, 100, omega);
    const double o4 = measured_order<R::Tao4<C>>(sys, x0, 3, 400, omega);
    MESSAGE("S3: tao2 ", o2, ", tao4 ", o4);
    CHECK(std::abs(o2 - 2) < 0.3);
    CHECK(std::abs(o4 - 4) < 0.3);
  }
  SUBCASE("H^2, three soft springs, to t = 3") {
    const auto sys = reftest::hyperbolic_system<double>();
    const auto x0 = reftest::hyperbolic_initial<double>();
    using C = sesi::Hyperbolic<2, double>;
    const double o2 = measured_order<R::Tao2<C>>(sys, x0, 3, 100, omega);
    const double o4 = measured_order<R::Tao4<C>>(sys, x0, 3, 400, omega);
    MESSAGE("H2: tao2 ", o2, ", tao4 ", o4);
    CHECK(std::abs(o2 - 2) < 0.3);
    CHECK(std::abs(o4 - 4) < 0.3);
  }
}

TEST_CASE("Tao's doubled phase space: copies start on the diagonal and stay close") {
  const auto sys = paper::make_system<double>();
  auto x = paper::initial_state<double>();
  R::Tao2<paper::Chart<double>> st;
  CHECK(st.omega() == 20.0);
  // After one step from the diagonal the copies differ by the local error of the augmented
  // system, O(h^3): halving h divides the gap by 2^3.
  auto gap_after_one_step = [&](double h) {
    auto s = paper::initial_state<double>();
    R::Tao2<paper::Chart<double>> one;
    one.do_step(sys, s, 0.0, h);
    return std::max((one.shadow_q() - s.q).cwiseAbs().maxCoeff(),
                    (one.shadow_p() - s.p).cwiseAbs().maxCoeff());
  };
  const double slope = std::log2(gap_after_one_step(0.01) / gap_after_one_step(0.005));
  MESSAGE("copy gap after one step falls as h^", slope);
  CHECK(std::abs(slope - 3) < 0.3);
  st.do_step(sys, x, 0.0, 0.1);
  // A state handed in that is not the last output restarts the copies on the diagonal: the
  // step then equals a fresh stepper's step from that state.
  x.p(0, 0) += 0.01;
  auto y = x;
  R::Tao2<paper::Chart<double>> fresh;
  st.do_step(sys, x, 0.1, 0.1);
  fresh.do_step(sys, y, 0.1, 0.1);
  CHECK(x.q == y.q);
  CHECK(x.p == y.p);
  // While the state is the last output, the copies carry over (the result differs from a
  // restart).
  auto restarted = x;
  st.do_step(sys, x, 0.2, 0.1);
  st.reset();
  st.do_step(sys, restarted, 0.2, 0.1);
  CHECK(x.q != restarted.q);
}

TEST_CASE("Tao's method costs 3 s + 1 field evaluations per step of s stages") {
  const auto sys = paper::make_system<double>();
  auto a = paper::initial_state<double>(), b = a;
  R::Tao2<paper::Chart<double>> t2;
  R::Tao4<paper::Chart<double>> t4;
  for (int k = 0; k < 10; ++k) {
    t2.do_step(sys, a, k * 0.1, 0.1);
    t4.do_step(sys, b, k * 0.1, 0.1);
  }
  CHECK(t2.evaluations() == 10 * 4);
  CHECK(t4.evaluations() == 10 * 10);
}

TEST_CASE("Tao's method keeps the energy bounded on the seed's scene over T = 800") {
  const auto sys = paper::make_system<double>();
  const auto x0 = paper::initial_state<double>();
  auto energy = [&](const auto& x) { return sys.energy(x); };
  for (double omega : {1.0, 20.0}) {
    const auto t2 =
        reftest::energy_halves<R::Tao2<paper::Chart<double>>>(sys, x0, 0.1, 800, energy, omega);
    const auto t4 =
        reftest::energy_halves<R::Tao4<paper::Chart<double>>>(sys, x0, 0.1, 800, energy, omega);
    MESSAGE("omega ", omega, ": tao2 ", t2.first, " / ", t2.second, "; tao4 ", t4.first, " / ",
            t4.second);
    CHECK(t2.second <= 1.5 * t2.first);
    CHECK(t4.second <= 1.5 * t4.first);
  }
}

TEST_CASE("suggested_omega reads Tao's h << omega^{-1/l} as h = omega^{-1/l} / 10") {
  using T2 = R::Tao2<paper::Chart<double>>;
  using T4 = R::Tao4<paper::Chart<double>>;
  CHECK(T2::suggested_omega(0.1) == doctest::Approx(1.0));
  CHECK(T2::suggested_omega(0.01) == doctest::Approx(100.0));
  CHECK(T4::suggested_omega(0.01) == doctest::Approx(1e4));
}
