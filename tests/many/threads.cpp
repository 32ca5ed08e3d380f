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

/// q and p after `steps` steps of Yoshida's fourth-order composition, in the program's
/// re-charting kick-drift-kick form, on `threads` threads.
template <class Sys>
sesi::State<typename Sys::Chart> run(const Sys& sys, sesi::State<typename Sys::Chart> s, int threads, int steps) {
  sesi::parallel::set_threads(threads);
  sesi::RechartingComposition<sesi::coefficients::Yoshida4, typename Sys::Chart> stepper;
  for (int k = 0; k < steps; ++k) stepper.do_step(sys, s, 0.0, 0.002);
  sesi::parallel::set_threads(0);
  return s;
}

template <class Sys>
void check_thread_counts(const Sys& sys, const sesi::State<typename Sys::Chart>& s0) {
  REQUIRE(sys.bodies() >= sesi::parallel::min_parallel_bodies);
  const auto one = run(sys, s0, 1, 20);
  CHECK(one.q.allFinite());
  for (int threads : {2, 3}) {
    const auto many = run(sys, s0, threads, 20);
    CHECK((many.q.array() == one.q.array()).all());
    CHECK((many.p.array() == one.p.array()).all());
    CHECK(many.frames == one.frames);
    CHECK(sys.energy(many) == sys.energy(one));
  }
  if (!sesi::parallel::available()) MESSAGE("built without OpenMP: every count ran on one thread");
}

}  // namespace

TEST_CASE("1, 2 and 3 threads give the same bits") {
  const int n = 400;
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
