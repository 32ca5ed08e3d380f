// Energy conservation of order 2 on quotients (issue #26): a Lennard-Jones liquid of 1000 bodies
// (density 0.5, T = 1, cutoff 2.5) on compact hyperbolic surfaces of genus 2 and 3 (Sausset &
// Tarjus, J. Phys. A 40, 12873 (2007)) and on an E^2 periodic box, stepped by sesi2 with the
// bodies brought back into the domain (sesi::wrap) after every step, at two steps h and h/2 over
// the same time (10^4 steps at h/2). Labelled long: about ten seconds per space.
#include <cmath>
#include <vector>

#include <doctest/doctest.h>

#include <sesi/recharting.hpp>
#include <sesi/stepper.hpp>

#include "common.hpp"
#include "topology_scenes.hpp"

namespace {

using namespace topotest;
using LJ = sesi::LennardJones<double>;
template <class Chart>
using LJSystem = sesi::System<Chart, LJ>;

struct Run {
  double max_error;  // max |E(t) - E(0)| over the samples
  long wraps;        // bodies brought back into the domain
};

/// steps steps of h, with a wrap after each (margin: a quarter of the cutoff, as the program's),
/// the energy sampled every `every` steps.
template <class Stepper, class Chart>
Run run(const LJSystem<Chart>& sys, sesi::State<Chart> s, double h, int steps, int every) {
  Stepper stepper;
  auto images = sys.chart().topology().identity_images(s.bodies());
  const double margin = 0.25 * std::get<0>(sys.terms()).cutoff;
  auto w = sys.make_workspace();
  const double e0 = sys.energy(s, w);
  Run out{0.0, 0};
  for (int k = 1; k <= steps; ++k) {
    stepper.do_step(sys, s, 0.0, h);
    out.wraps += sesi::wrap(sys, s, images, margin);
    if (k % every == 0) out.max_error = std::max(out.max_error, std::abs(sys.energy(s, w) - e0));
  }
  CHECK(s.q.allFinite());
  return out;
}

/// The measured order log2(err(h) / err(h/2)) of the max energy error over the same time T = 25.
///
/// The bound: for a symmetric second-order method E(t) - E(0) = h^2 (H2(z(t)) - H2(z(0))) + O(h^4),
/// H2 the modified energy's leading term (Hairer, Lubich & Wanner, GNI, IX.8), here with
/// (h omega)^2 ~ 1e-2 (omega^2 = W''(1) = 456 at a collision) the O(h^4) part is under 1 %. The two
/// runs are different chaotic trajectories of the same liquid, so the two maxima are two samples
/// of the maximum of h^2 (H2(z(t)) - H2(z(0))) over T, a sum over 1000 bodies, nearly Gaussian, with
/// K ~ T / tau ~ 250 independent values in T (tau ~ 0.1, a collision time at density 0.5 and
/// T = 1). The maximum of K Gaussians is sigma (a_K + G / a_K), a_K = sqrt(2 ln K) = 3.3, G Gumbel
/// (sd 1.28): relative sd 1.28 / a_K^2 = 0.12, so log2 of a ratio of two has sd 0.24 and lies
/// within 3 sd, 0.72, of 2; 0.75 is asserted. (The force's jump at the cutoff adds an error
/// ~h^2 per crossing, a random walk of ~sqrt(10^5) crossings of 0.016 h^2 each, about 5 h^2
/// against ~80 h^2 from H2 (sqrt(1000) bodies x ~2.5 h^2 each): also h^2, and small.)
template <class Stepper, class Chart>
void check_order(const LJSystem<Chart>& sys, const sesi::State<Chart>& s0) {
  const double h = 0.005;
  const Run coarse = run<Stepper>(sys, s0, h, 5000, 10);
  const Run fine = run<Stepper>(sys, s0, h / 2, 10000, 20);
  const double order = std::log2(coarse.max_error / fine.max_error);
  MESSAGE("max |E - E0|: " << coarse.max_error << " at h, " << fine.max_error << " at h/2; order " << order
                           << "; wraps " << coarse.wraps << ", " << fine.wraps);
  // Not a bound: the runs must see bodies cross sides (at speed ~1 over T = 25, a good part of
  // the bodies within 25 of a side do).
  CHECK(coarse.wraps > sys.bodies() / 10);
  CHECK(fine.wraps > sys.bodies() / 10);
  CHECK(std::abs(order - 2.0) < 0.75);
}

}  // namespace

TEST_CASE("energy conservation of order 2 for a Lennard-Jones liquid on quotients") {
  const int n = 1000;
  const LJ lj{1.0, 1.0, 2.5};
  SUBCASE("genus 2") {
    const Surface chart = surface(2, surface_radius(2, n, 0.5));
    REQUIRE(lj.cutoff <= chart.topology().max_cutoff());
    const LJSystem<Surface> sys(chart, std::vector<double>(n, 1.0), lj);
    check_order<sesi::RechartingComposition<sesi::coefficients::Strang, Surface>>(
        sys, state_from(chart, spaced_points(chart, n, 1.0, 81), 1.0, 82));
  }
  SUBCASE("genus 3") {
    const Surface chart = surface(3, surface_radius(3, n, 0.5));
    REQUIRE(lj.cutoff <= chart.topology().max_cutoff());
    const LJSystem<Surface> sys(chart, std::vector<double>(n, 1.0), lj);
    check_order<sesi::RechartingComposition<sesi::coefficients::Strang, Surface>>(
        sys, state_from(chart, spaced_points(chart, n, 1.0, 83), 1.0, 84));
  }
  SUBCASE("E^2 box") {
    const double L = std::sqrt(n / 0.5);
    const Box2 chart = box2(L, L);
    const LJSystem<Box2> sys(chart, std::vector<double>(n, 1.0), lj);
    check_order<sesi::Composition<sesi::coefficients::Strang, Box2>>(
        sys, state_from(chart, spaced_points(chart, n, 1.0, 85), 1.0, 86));
  }
}
