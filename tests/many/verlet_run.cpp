// A 1000-body Lennard-Jones run through a Verlet list against the all-pairs run (issue #11): a
// separate binary, labelled long, so that the sanitizer job leaves it out.
#include <vector>

#include <doctest/doctest.h>

#include <sesi/neighbours.hpp>
#include <sesi/stepper.hpp>

#include "common.hpp"

using namespace manytest;


TEST_CASE("a 1000-body run through a Verlet list matches the all-pairs run") {
  // Issue #11: 1000 bodies, 100 steps. Forces through the list equal the all-pairs rows to the
  // bit (tests/many/neighbours.cpp: the same pair terms summed in the same order), so the two
  // runs agree exactly, across the list's rebuilds.
  const int n = 1000;
  const sesi::Sphere<2, double> chart(radius_for(2, n));
  const auto s0 = lattice_state(chart, n, 1.0, 15);
  const sesi::LennardJones<double> lj{1.0, 1.0, 2.5};
  using Sys = sesi::System<sesi::Sphere<2, double>, sesi::LennardJones<double>>;
  Sys sys(chart, std::vector<double>(n, 1.0), lj);
  // A list updated at the points of every step, as the kick-drift-kick run's own list is (one
  // force evaluation per step, at the step's end points): its rebuilds are the run's.
  sesi::VerletList<sesi::Sphere<2, double>> shadow;
  const auto run = [&](Sys::PairSearch search) {
    sys.set_pair_search(search);
    auto s = s0;
    sesi::Composition<sesi::coefficients::Strang, sesi::Sphere<2, double>, sesi::Splitting::kick_drift_kick> stepper;
    if (search == Sys::PairSearch::automatic) shadow.update(chart, points_of(chart, s), lj.range(chart));
    for (int k = 0; k < 100; ++k) {
      stepper.do_step(sys, s, 0.0, 0.002);
      if (search == Sys::PairSearch::automatic) shadow.update(chart, points_of(chart, s), lj.range(chart));
    }
    return s;
  };
  const auto a = run(Sys::PairSearch::automatic);
  const auto b = run(Sys::PairSearch::all_pairs);
  CHECK(a.q.allFinite());
  CHECK((a.q.array() == b.q.array()).all());
  CHECK((a.p.array() == b.p.array()).all());
  // The first build, then at least one rebuild (a body moved more than half the skin).
  CHECK(shadow.builds() >= 2);
  MESSAGE("list builds over the run: " << shadow.builds());
}
