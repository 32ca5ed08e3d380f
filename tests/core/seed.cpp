// The seed's scene (sesi::scenes::paper; shared/paper-scene.md): three bodies on S^2 with the
// chord well, against its exact solution (issue #2).
#include <algorithm>
#include <cmath>

#include <doctest/doctest.h>

#include <sesi/diagnostics.hpp>
#include <sesi/scenes/paper.hpp>

#include "common.hpp"

namespace {

namespace paper = sesi::scenes::paper;

struct Run {
  double first = 0, second = 0;  ///< max |E - E0| over the first and second halves
  double position_error = 0;     ///< |x_1(T) - x_1,exact(T)|
};

template <class Stepper>
Run run(double tau, double t_end) {
  const auto sys = paper::make_system();
  auto x = paper::initial_state();
  const paper::Exact exact;
  auto w = sys.make_workspace();
  const double e0 = sys.energy(x, w);
  const long steps = std::lround(t_end / tau);
  Stepper stepper;
  Run r;
  for (long k = 0; k < steps; ++k) {
    stepper.do_step(sys, x, double(k) * tau, tau);
    double& slot = k < steps / 2 ? r.first : r.second;
    slot = std::max(slot, std::abs(sys.energy(x, w) - e0));
  }
  const auto X = sesi::embedding_points(sys, x);
  r.position_error = (X.col(0) - exact.position(0, t_end).cast<double>()).norm();
  return r;
}

}  // namespace

TEST_CASE("seed: the scene's energy is the exact solution's, E = 0.183243903882068") {
  const auto sys = paper::make_system();
  const paper::Exact exact;
  // Both are sums of a handful of O(1) terms: a few eps.
  CHECK(std::abs(sys.energy(paper::initial_state()) - double(exact.energy())) <= 8 * 2.2e-16);
  CHECK(std::abs(double(exact.energy()) - 0.183243903882068) <= 1e-15);
}

TEST_CASE("seed: SESI 4 at tau = 0.01 ends within 1e-5 of the exact body-1 position at T = 800") {
  // The figure. Its order: the phase error of a 4th-order method grows like C T tau^4,
  // so tau = 0.02 must miss by 2^4 = 16 times more (order within 0.3: 2^3.7 .. 2^4.3).
  const auto fine = run<sesi::Yoshida4<paper::Chart<>>>(0.01, 800.0);
  const auto coarse = run<sesi::Yoshida4<paper::Chart<>>>(0.02, 800.0);
  MESSAGE("SESI 4 T = 800: position error tau 0.01: ", fine.position_error,
          ", tau 0.02: ", coarse.position_error, ", max energy error ", fine.second);
  CHECK(fine.position_error < 1e-5);
  CHECK(std::abs(std::log2(coarse.position_error / fine.position_error) - 4.0) <= 0.3);
}

TEST_CASE("seed: SESI 2 and SESI 4 at tau = 0.1 keep the energy error bounded to T = 800") {
  // Bounded: the second half's maximum is within 1.5 times the first's (no drift); and of the
  // method's order: halving tau divides the maximum by 2^p, p within 0.3.
  const auto s2 = run<sesi::Strang<paper::Chart<>>>(0.1, 800.0);
  const auto s2h = run<sesi::Strang<paper::Chart<>>>(0.05, 800.0);
  const auto s4 = run<sesi::Yoshida4<paper::Chart<>>>(0.1, 800.0);
  const auto s4h = run<sesi::Yoshida4<paper::Chart<>>>(0.05, 800.0);
  MESSAGE("SESI 2 tau 0.1: max energy error ", std::max(s2.first, s2.second),
          " (halves ", s2.first, ", ", s2.second, "), position error ", s2.position_error);
  MESSAGE("SESI 4 tau 0.1: max energy error ", std::max(s4.first, s4.second),
          " (halves ", s4.first, ", ", s4.second, "), position error ", s4.position_error);
  CHECK(s2.second <= 1.5 * s2.first);
  CHECK(s4.second <= 1.5 * s4.first);
  const double p2 = std::log2(std::max(s2.first, s2.second) / std::max(s2h.first, s2h.second));
  const double p4 = std::log2(std::max(s4.first, s4.second) / std::max(s4h.first, s4h.second));
  MESSAGE("energy error orders: SESI 2 ", p2, ", SESI 4 ", p4);
  CHECK(std::abs(p2 - 2.0) <= 0.3);
  CHECK(std::abs(p4 - 4.0) <= 0.3);
}
