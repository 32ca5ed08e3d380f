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
