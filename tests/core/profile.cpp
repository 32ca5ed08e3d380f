// The step profile (include/sesi/profile.hpp, issue #27): what it charges where. The checks are
// on the accounting's structure (calls, loops, chunks, phases that add up to the window), and on
// lower bounds that sleep_for guarantees (it sleeps at least as long as asked, on steady_clock);
// never on how fast anything runs.
#include <chrono>
#include <cmath>
#include <limits>
#include <thread>

#include <doctest/doctest.h>

#include <sesi/parallel.hpp>
#include <sesi/profile.hpp>

namespace {

using sesi::profile::Phase;
using sesi::profile::Scope;

int at(Phase p) { return static_cast<int>(p); }

void sleep_ms(int ms) { std::this_thread::sleep_for(std::chrono::milliseconds(ms)); }

/// Sum of the phases' exclusive walls: the window's wall up to the rounding of each phase's
/// seconds (one rounding per phase_count values, and as many in the sum: 2 phase_count eps).
void check_adds_up(const sesi::profile::Report& r) {
  double sum = 0.0;
  for (const auto& p : r.phases) sum += p.wall;
  CHECK(std::abs(sum - r.wall) <= 2 * sesi::profile::phase_count * std::numeric_limits<double>::epsilon() * r.wall);
}

}  // namespace

TEST_CASE("off by default: a Scope and a loop record nothing") {
  CHECK_FALSE(sesi::profile::enabled());
  {
    const Scope s(Phase::force);
    sesi::parallel::for_chunks(10, 1, [](int, int, int) {});
  }
  sesi::profile::start(1);
  const auto r = sesi::profile::stop();
  CHECK_FALSE(sesi::profile::enabled());
  CHECK(r.phases[at(Phase::force)].calls == 0);  // start() resets whatever came before
  CHECK(r.phases[at(Phase::force)].loops == 0);
}

TEST_CASE("nested phases: the inner phase's time is its own, and the phases add up to the window") {
  sesi::profile::start(1);
  {
    const Scope force(Phase::force);
    sleep_ms(5);
    {
      const Scope neighbours(Phase::neighbours);
      sleep_ms(20);
    }
  }
  {
    const Scope drift(Phase::drift);
    sleep_ms(5);
  }
  const auto r = sesi::profile::stop();
  CHECK(r.phases[at(Phase::force)].calls == 1);
  CHECK(r.phases[at(Phase::neighbours)].calls == 1);
  CHECK(r.phases[at(Phase::drift)].calls == 1);
  CHECK(r.phases[at(Phase::neighbours)].wall >= 0.020);  // sleep_for sleeps at least that long
  CHECK(r.phases[at(Phase::force)].wall >= 0.005);
  CHECK(r.phases[at(Phase::drift)].wall >= 0.005);
  CHECK(r.wall >= 0.030);
  // No loops: everything is serial, and the serial fraction is 1 (to the rounding of a quotient).
  CHECK(r.phases[at(Phase::force)].serial == r.phases[at(Phase::force)].wall);
  CHECK(std::abs(r.serial_fraction() - 1.0) <= 2 * sesi::profile::phase_count * std::numeric_limits<double>::epsilon());
  check_adds_up(r);
}

TEST_CASE("parallel loops: wall on the calling thread, busy time per thread, in the phase open at the loop") {
  sesi::parallel::set_threads(2);
  const int threads = sesi::parallel::threads();  // 1 without OpenMP
  sesi::profile::start(threads);
  {
    const Scope force(Phase::force);
    sesi::parallel::for_chunks(1000, 8, [](int, int, int) {
      // A Scope and a loop inside a chunk are the chunk's: not recorded apart.
      const Scope ignored(Phase::thermostat);
      sesi::parallel::for_chunks(100, 4, [](int, int, int) {});
      sleep_ms(2);
    });
    {
      const Scope neighbours(Phase::neighbours);
      // One chunk over enough bodies to share among threads: a region even so (shared_loop).
      sesi::parallel::for_chunks(2 * sesi::parallel::min_parallel_bodies, 1, [](int, int, int) { sleep_ms(1); });
    }
    {
      const Scope drift(Phase::drift);
      // Too few bodies to share (one thread at any count): serial.
      sesi::parallel::for_chunks(sesi::parallel::min_parallel_bodies, 1, [](int, int, int) { sleep_ms(1); });
    }
    sleep_ms(3);  // serial work of the force phase
  }
  const auto r = sesi::profile::stop();
  sesi::parallel::set_threads(0);
  REQUIRE(r.threads == threads);
  const auto& force = r.phases[at(Phase::force)];
  const auto& neighbours = r.phases[at(Phase::neighbours)];
  CHECK(force.loops == 1);
  CHECK(neighbours.loops == 1);
  CHECK(r.phases[at(Phase::thermostat)].calls == 0);
  long long chunks = 0;
  double busy = 0.0;
  for (int t = 0; t < threads; ++t) {
    chunks += force.chunks[t];
    busy += force.busy[t];
  }
  CHECK(chunks == 8);  // the outer loop's chunks only, on whichever threads ran them
  CHECK(busy >= 8 * 0.002);
  CHECK(neighbours.chunks[0] == 1);  // a one-chunk loop runs on the calling thread
  CHECK(neighbours.busy[0] >= 0.001);
  // The loop's wall lies inside the phase's own wall; the rest is serial (>= the 3 ms sleep).
  CHECK(force.loop_wall <= force.wall);
  // serial is formed in integer nanoseconds: the doubles differ by their roundings (3 eps wall).
  CHECK(std::abs(force.serial - (force.wall - force.loop_wall)) <= 3 * std::numeric_limits<double>::epsilon() * force.wall);
  CHECK(force.serial >= 0.003);
  CHECK(neighbours.loop_wall >= 0.001);
  const auto& drift = r.phases[at(Phase::drift)];
  CHECK(drift.loops == 0);
  CHECK(drift.serial == drift.wall);
  CHECK(drift.serial >= 0.001);
  check_adds_up(r);
}

TEST_CASE("a thread other than the one that started records nothing") {
  sesi::profile::start(1);
  std::thread other([] {
    const Scope s(Phase::drift);
    sesi::parallel::for_chunks(10, 1, [](int, int, int) {});
  });
  other.join();
  const auto r = sesi::profile::stop();
  CHECK(r.phases[at(Phase::drift)].calls == 0);
  CHECK(r.phases[at(Phase::other)].loops == 0);
}
