// Results do not depend on the number of threads (issue #11): every loop over bodies writes only
// its own body's entries and every sum is formed in a fixed order (include/sesi/parallel.hpp),
// so 1, 2 and 3 threads step the same many-body scenes to the same bits. Without OpenMP the
// loops are serial and the test holds trivially (it says so).
#include <vector>

#include <doctest/doctest.h>

#include <sesi/recharting.hpp>
#include <sesi/stepper.hpp>

#include "common.hpp"

namespace {

using namespace manytest;

/// What one run leaves: the state, and the diagnostics of it computed on the same threads.
template <class Sys>
struct Outcome {
  sesi::State<typename Sys::Chart> state;
  double energy;
  Eigen::MatrixXd gradient;
};

/// `steps` steps of Yoshida's fourth-order composition, in the program's re-charting
/// kick-drift-kick form, then the energy and the potential gradient, all on `threads` threads.
template <class Sys>
Outcome<Sys> run(const Sys& sys, sesi::State<typename Sys::Chart> s, int threads, int steps) {
  sesi::parallel::set_threads(threads);
  sesi::RechartingComposition<sesi::coefficients::Yoshida4, typename Sys::Chart> stepper;
  for (int k = 0; k < steps; ++k) stepper.do_step(sys, s, 0.0, 0.002);
  auto w = sys.make_workspace();
  typename sesi::State<typename Sys::Chart>::Matrix g;
  sys.potential_gradient(s, w, g);
  Outcome<Sys> out{s, sys.energy(s), g};
  sesi::parallel::set_threads(0);
  return out;
}

template <class Sys>
void check_thread_counts(const Sys& sys, const sesi::State<typename Sys::Chart>& s0) {
  REQUIRE(sys.bodies() >= 3 * sesi::parallel::min_parallel_bodies);  // work for three threads (threads_for)
  const auto one = run(sys, s0, 1, 20);
  CHECK(one.state.q.allFinite());
  for (int threads : {2, 3}) {
    // Stepped, and its energy and forces computed, on `threads` threads; each compared with
    // the same on one thread.
    const auto many = run(sys, s0, threads, 20);
    CHECK((many.state.q.array() == one.state.q.array()).all());
    CHECK((many.state.p.array() == one.state.p.array()).all());
    CHECK(many.state.frames == one.state.frames);
    CHECK(many.energy == one.energy);
    CHECK((many.gradient.array() == one.gradient.array()).all());
  }
  if (!sesi::parallel::available()) MESSAGE("built without OpenMP: every count ran on one thread");
}

}  // namespace

TEST_CASE("1, 2 and 3 threads give the same bits") {
  const int n = 800;
  SUBCASE("S^2: Lennard-Jones and cotangent gravity") {
    const sesi::Sphere<2, double> chart(radius_for(2, n));
    sesi::System sys(chart, std::vector<double>(n, 1.0), sesi::LennardJones<double>{1.0, 1.0, 2.5},
                     sesi::CotangentGravity<double>{1e-3});
    check_thread_counts(sys, lattice_state(chart, n, 1.0, 21));
  }
  SUBCASE("H^2 five radii from the origin: Lennard-Jones, harmonic pairs") {
    const sesi::Hyperbolic<2, double> chart(8.0);
    sesi::System sys(chart, std::vector<double>(n, 1.0), sesi::LennardJones<double>{1e-6, 0.05, 0.75},
                     sesi::HarmonicPair<double>{1e-4, 1.0});
    check_thread_counts(sys, random_state(chart, n, 12.0, 40.0, 0.1, 22));
  }
}

namespace {

/// Free motion (no potential: every kick subtracts zero) of `steps` kick-drift-kick Strang
/// steps, which the engine flows in blocks of bodies on threads (stepper.hpp, flows_in_blocks),
/// against the same flows body by body through the chart's scalar cached path (level_flow with
/// its own sine and cosine): the same bits, on 1 and 3 threads.
template <class Chart>
void check_blocked_flows(const Chart& chart, const sesi::State<Chart>& s0, int steps, double dt) {
  static_assert(sesi::detail::blocked_flows<Chart>);
  const int n = static_cast<int>(s0.q.cols()), top = chart.dim() - 1;
  std::vector<double> masses(static_cast<std::size_t>(n));
  for (int b = 0; b < n; ++b) masses[static_cast<std::size_t>(b)] = 1.0 + 0.01 * (b % 7);
  const sesi::System sys(chart, masses);
  sesi::State<Chart> by_body = s0;
  for (int b = 0; b < n; ++b) {
    typename Chart::Point q = s0.q.col(b), p = s0.p.col(b);
    typename Chart::TrigType t;
    chart.refresh(q, t);
    const double m = masses[static_cast<std::size_t>(b)];
    for (int k = 0; k < steps; ++k) {
      if (top == 0) {
        chart.level_flow(0, q, p, m, dt, t);
        continue;
      }
      for (int i = 0; i < top; ++i) chart.level_flow(i, q, p, m, dt / 2, t);
      chart.level_flow(top, q, p, m, dt, t);
      for (int i = top - 1; i >= 0; --i) chart.level_flow(i, q, p, m, dt / 2, t);
    }
    by_body.q.col(b) = q;
    by_body.p.col(b) = p;
  }
  for (const int threads : {1, 3}) {
    sesi::parallel::set_threads(threads);
    sesi::Composition<sesi::coefficients::Strang, Chart, sesi::Splitting::kick_drift_kick> stepper;
    sesi::State<Chart> s = s0;
    for (int k = 0; k < steps; ++k) stepper.do_step(sys, s, 0.0, dt);
    sesi::parallel::set_threads(0);
    INFO(threads, " threads");
    CHECK((s.q.array() == by_body.q.array()).all());
    CHECK((s.p.array() == by_body.p.array()).all());
  }
}

}  // namespace

TEST_CASE("the K-flows in blocks of bodies give the per-body flows' bits (S^2, S^3, H^2, H^3)") {
  const int n = 3 * sesi::parallel::min_parallel_bodies + 5;  // chunks on threads, a part block
  check_blocked_flows(sesi::Sphere<2, double>(3.0), random_state(sesi::Sphere<2, double>(3.0), n, 0, 0, 1.0, 31), 30, 0.01);
  check_blocked_flows(sesi::Sphere<3, double>(3.0), random_state(sesi::Sphere<3, double>(3.0), n, 0, 0, 1.0, 32), 30, 0.01);
  check_blocked_flows(sesi::Hyperbolic<2, double>(2.0),
                      random_state(sesi::Hyperbolic<2, double>(2.0), n, 3.0, 20.0, 0.5, 33), 30, 0.01);
  check_blocked_flows(sesi::Hyperbolic<3, double>(2.0),
                      random_state(sesi::Hyperbolic<3, double>(2.0), n, 3.0, 20.0, 0.5, 34), 30, 0.01);
}
