// A 1000-body Lennard-Jones run through a Verlet list against the all-pairs run (issue #11): a
// separate binary, labelled long, so that the sanitizer job leaves it out.
#include <algorithm>
#include <vector>

#include <doctest/doctest.h>

#include <sesi/stepper.hpp>

#include "common.hpp"

using namespace manytest;


TEST_CASE("a 1000-body run through a Verlet list matches the all-pairs run") {
  // Issue #11: 1000 bodies, 100 steps, agreement to 1e-10. Forces through the list equal the
  // all-pairs rows to the bit (above), so the two runs are expected to agree exactly; the run
  // is long enough that bodies move beyond half the skin, so the list is rebuilt on the way.
  const int n = 1000;
  const sesi::Sphere<2, double> chart(radius_for(2, n));
  const auto s0 = lattice_state(chart, n, 1.0, 15);
  using Sys = sesi::System<sesi::Sphere<2, double>, sesi::LennardJones<double>>;
  Sys sys(chart, std::vector<double>(n, 1.0), sesi::LennardJones<double>{1.0, 1.0, 2.5});
  const auto run = [&](Sys::PairSearch search) {
    sys.set_pair_search(search);
    auto s = s0;
    sesi::Composition<sesi::coefficients::Strang, sesi::Sphere<2, double>, sesi::Splitting::kick_drift_kick> stepper;
    for (int k = 0; k < 100; ++k) stepper.do_step(sys, s, 0.0, 0.002);
    return s;
  };
  const auto a = run(Sys::PairSearch::automatic);
  const auto b = run(Sys::PairSearch::all_pairs);
  const double diff = std::max((a.q - b.q).cwiseAbs().maxCoeff(), (a.p - b.p).cwiseAbs().maxCoeff());
  CHECK(diff <= 1e-10);
  MESSAGE("largest difference, list against all pairs: " << diff);
  // Some body moved more than half the skin (0.15): the list must have been rebuilt.
  const Eigen::MatrixXd X0 = points_of(chart, s0), X1 = points_of(chart, a);
  CHECK((X1 - X0).colwise().norm().maxCoeff() > 0.12 * 2.5 / 2);
}
