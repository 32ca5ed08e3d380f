// The kick-drift-kick form keeps its last gradient for the next step's first kick, and after a
// re-charting it brings that gradient up to date only where a re-charted body enters
// (System::patch_gradient, issue #27): the changed bodies' rows and their partners'. The claim
// is exact: a run that patches equals, bit for bit, a run that evaluates every gradient afresh
// (reset() before every step), through re-chartings on S^2 and H^2, with 1 and 2 threads. And
// the diagnostics may use the stepper's Verlet lists (Workspace::share_lists) without a bit of
// difference, and System::neighbour_lists gives every pair closer than a reach.
#include <atomic>
#include <cstring>
#include <memory>
#include <vector>

#include <doctest/doctest.h>

#include <sesi/recharting.hpp>
#include <sesi/stepper.hpp>

#include "common.hpp"

namespace {

using namespace manytest;

template <class State>
bool same_bits(const State& a, const State& b) {
  if (a.q.size() != b.q.size() || a.frames.size() != b.frames.size()) return false;
  for (std::size_t k = 0; k < a.frames.size(); ++k) {
    if (std::memcmp(a.frames[k].data(), b.frames[k].data(), sizeof(double) * a.frames[k].size()) != 0) return false;
  }
  return std::memcmp(a.q.data(), b.q.data(), sizeof(double) * a.q.size()) == 0 &&
         std::memcmp(a.p.data(), b.p.data(), sizeof(double) * a.p.size()) == 0;
}

/// steps kick-drift-kick steps with re-charting: patched (as the engine does by itself) against
/// fresh gradients (reset() forgets the kept gradient and the trig caches before every step).
/// Returns the re-chartings of the patched run after its first step (which re-charts the bodies
/// near the chart's singular set at once: too many to patch).
template <class Sys>
long compare_runs(const Sys& sys, const sesi::State<typename Sys::Chart>& start, int steps, double dt) {
  using Chart = typename Sys::Chart;
  using Engine = sesi::RechartingComposition<sesi::coefficients::Strang, Chart>;
  Engine patched(sesi::RechartPolicy<double>{}), fresh(sesi::RechartPolicy<double>{});
  sesi::State<Chart> a = start, b = start;
  long after_first = 0;
  for (int k = 0; k < steps; ++k) {
    patched.do_step(std::cref(sys), a, 0.0, dt);
    fresh.reset();
    fresh.do_step(std::cref(sys), b, 0.0, dt);
    if (k == 0) after_first = patched.recharts();
    INFO("step " << k << ", threads " << sesi::parallel::threads());
    REQUIRE(same_bits(a, b));
  }
  REQUIRE(a.q.allFinite());  // a scene that stays a scene
  REQUIRE(a.p.allFinite());
  return patched.recharts() - after_first;
}

/// A zero external potential that counts the calls of its gradient: one per body in a force
/// evaluation, one per row a patch recomputes.
struct CountingZero {
  std::shared_ptr<std::atomic<long>> calls = std::make_shared<std::atomic<long>>(0);
  template <class Space>
  double value(const Space&, const typename Space::Ambient&, double) const {
    return 0.0;
  }
  template <class Space>
  void gradient(const Space&, const typename Space::Ambient&, double, typename Space::Ambient& g) const {
    g.setZero();
    calls->fetch_add(1, std::memory_order_relaxed);
  }
};

}  // namespace

TEST_CASE("a turn costs no force evaluation: the kept gradient is patched") {
  // A turn keeps a body's q and changes its frame (recharting.hpp). Until issue #27 the engine
  // asked only whether q changed, so a step after a turn evaluated every body afresh: 1.9
  // evaluations a step at 10^5 Lennard-Jones bodies on S^2, where some body turns at most steps.
  const int n = 600;
  const sesi::Sphere<2, double> chart(radius_for(2, n));
  const CountingZero counter;
  sesi::System sys(chart, std::vector<double>(n, 1.0), sesi::LennardJones<double>{1.0, 1.0, 2.5}, counter);
  sesi::RechartingComposition<sesi::coefficients::Strang, sesi::Sphere<2, double>> engine(sesi::RechartPolicy<double>{});
  sesi::State<sesi::Sphere<2, double>> s = lattice_state(chart, n, 2.0, 31);
  engine.do_step(std::cref(sys), s, 0.0, 0.005);  // (re-charts the bodies near the singular set at once)
  const long recharts = engine.recharts(), calls = counter.calls->load();
  const int steps = 400;
  long turning_steps = 0;  // steps after which some body was re-charted
  for (int k = 0; k < steps; ++k) {
    const long before = engine.recharts();
    engine.do_step(std::cref(sys), s, 0.0, 0.005);
    if (engine.recharts() > before) ++turning_steps;
  }
  const long turned = engine.recharts() - recharts;
  const long extra = counter.calls->load() - calls - static_cast<long>(steps) * n;
  MESSAGE(turned << " re-chartings after " << turning_steps << " of " << steps
                 << " steps; rows recomputed beyond one evaluation a step: " << extra);
  REQUIRE(turning_steps >= 3);
  // One evaluation a step, and per re-charted body its row and its partners' (about 12 within
  // cutoff + skin at density 1/2; 32 bounds them), where an evaluation after every step with a
  // re-charting would add n rows per such step.
  CHECK(extra >= 0);
  CHECK(extra <= 32 * turned);
  CHECK(extra < turning_steps * n);
}

TEST_CASE("a patched gradient equals a fresh one to the bit through re-chartings") {
  const int n = 600;
  SUBCASE("S^2, Lennard-Jones") {
    const sesi::Sphere<2, double> chart(radius_for(2, n));
    sesi::System sys(chart, std::vector<double>(n, 1.0), sesi::LennardJones<double>{1.0, 1.0, 2.5});
    for (const int threads : {1, 2}) {
      sesi::parallel::set_threads(threads);
      // Speeds ~2 carry about 20 bodies a unit of time over the re-charting line |sin q_1| = 1/2
      // (a band of length 2 x 2 pi R sin 30 deg, density 1/2): some 20 over 400 steps of 0.005.
      const long recharts = compare_runs(sys, lattice_state(chart, n, 2.0, 31), 400, 0.005);
      MESSAGE("S^2, " << threads << " threads: " << recharts << " re-chartings after the first step, a few a step, patched");
      CHECK(recharts >= 3);
    }
  }
  SUBCASE("H^2: Lennard-Jones") {
    // The scene of tests/many/threads.cpp at the origin and five times as fast (faster, its
    // random overlaps blow up within 300 steps): some 15 re-chartings in 600 steps.
    const sesi::Hyperbolic<2, double> chart(8.0);
    sesi::System sys(chart, std::vector<double>(n, 1.0), sesi::LennardJones<double>{1e-6, 0.05, 0.75});
    for (const int threads : {1, 2}) {
      sesi::parallel::set_threads(threads);
      const long recharts = compare_runs(sys, random_state(chart, n, 12.0, 0.0, 0.5, 32), 600, 0.005);
      MESSAGE("H^2, " << threads << " threads: " << recharts << " re-chartings after the first step, a few a step, patched");
      CHECK(recharts >= 3);
    }
  }
  sesi::parallel::set_threads(0);
}

TEST_CASE("patch_gradient recomputes the rows of moved bodies and of their partners") {
  // A sharper check than a re-charting (whose world points agree to round-off): three moved
  // bodies change their own rows and their partners' (old and new) in every bit, and the patch
  // must give what a fresh kick gives.
  const int n = 600;
  const sesi::Sphere<2, double> chart(radius_for(2, n));
  sesi::System sys(chart, std::vector<double>(n, 1.0), sesi::LennardJones<double>{1.0, 1.0, 2.5});
  sesi::State<sesi::Sphere<2, double>> s = lattice_state(chart, n, 1.0, 34);
  sesi::State<sesi::Sphere<2, double>>::Matrix kept, fresh;
  auto w = sys.make_workspace();
  sys.refresh(s, w);
  sys.kick_cached(s, 0.0, w, kept);
  // Two small moves, and body 300 moved 4 sigma (beyond cutoff + skin): its old partners lose it.
  const std::vector<int> moved{5, 300, 599};
  s.q(1, 5) += 0.1 / chart.radius();
  s.q(1, 300) += 4.0 / chart.radius();
  s.q(1, 599) += 0.1 / chart.radius();
  REQUIRE(sys.patch_gradient(s, w, moved, kept));
  auto w2 = sys.make_workspace();
  sys.refresh(s, w2);
  sys.kick_cached(s, 0.0, w2, fresh);
  CHECK(std::memcmp(kept.data(), fresh.data(), sizeof(double) * kept.size()) == 0);
  // Too many changed bodies (more than a sixteenth) are left to a fresh evaluation.
  std::vector<int> many(n / 16 + 1);
  for (int k = 0; k < static_cast<int>(many.size()); ++k) many[static_cast<std::size_t>(k)] = k;
  CHECK_FALSE(sys.patch_gradient(s, w, many, kept));
}

TEST_CASE("diagnostics on the stepper's lists, and the pairs closer than a reach") {
  const int n = 600;
  const sesi::Sphere<2, double> chart(radius_for(2, n));
  sesi::System sys(chart, std::vector<double>(n, 1.0), sesi::LennardJones<double>{1.0, 1.0, 2.5});
  sesi::State<sesi::Sphere<2, double>> s = lattice_state(chart, n, 1.0, 33);
  sesi::Composition<sesi::coefficients::Strang, sesi::Sphere<2, double>, sesi::Splitting::kick_drift_kick> engine;
  for (int k = 0; k < 30; ++k) engine.do_step(std::cref(sys), s, 0.0, 0.005);
  auto own = sys.make_workspace();
  auto shared = sys.make_workspace();
  shared.share_lists(&engine.workspace());
  const double e_own = sys.potential_energy(s, own), e_shared = sys.potential_energy(s, shared);
  CHECK(std::memcmp(&e_own, &e_shared, sizeof(double)) == 0);
  CHECK(shared.verlet.empty());  // it built none of its own

  // Every pair closer than 1.7 (brute force over the chord, monotone in the distance) is listed.
  const sesi::NeighbourLists* lists = sys.neighbour_lists(shared, 1.7);
  REQUIRE(lists != nullptr);
  CHECK(sys.neighbour_lists(shared, 2.6) == nullptr);  // beyond the only term's range
  const Eigen::MatrixXd X = points_of(chart, s);
  const double chord = chart.chord_of_distance(1.7);
  long close = 0, listed = 0;
  for (int i = 0; i < n; ++i) {
    for (int j = i + 1; j < n; ++j) {
      if ((X.col(i) - X.col(j)).norm() >= chord) continue;
      ++close;
      const int* first = lists->index.data() + lists->begin(i);
      const int* last = lists->index.data() + lists->end(i);
      listed += std::binary_search(first, last, j) ? 1 : 0;
    }
  }
  CHECK(close > n);  // about 2 pi 1.7^2 / 2 / 2 = 4.5 pairs a body at density 1/2
  CHECK(listed == close);
}
