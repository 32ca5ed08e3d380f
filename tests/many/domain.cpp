// A domain of one simulation across processes (System::set_domain, issue #27; the program's
// src/domain runs one per MPI rank): two domains in one process, each stepped by its own thread,
// each holding the bodies of its half of S^2 and a halo of the bodies within reach, refreshed from
// the other domain after every drift (System::drifted) and after every step, with every sum over
// bodies taken over both domains' own bodies in body order (System::sum_rows). The claim is the
// program's: the domains step their own bodies to the bits of the whole system, re-chartings and
// all, and their energy is the whole system's to the bit.
#include <barrier>
#include <cstring>
#include <functional>
#include <thread>
#include <vector>

#include <doctest/doctest.h>

#include <sesi/recharting.hpp>
#include <sesi/stepper.hpp>

#include "common.hpp"

namespace {

using namespace manytest;
using Chart = sesi::Sphere<2, double>;
using State = sesi::State<Chart>;
using Sys = sesi::System<Chart, sesi::LennardJones<double>>;
using Engine = sesi::RechartingComposition<sesi::coefficients::Strang, Chart>;

bool same_body(const State& a, int i, const State& b, int j) {
  const auto same = [](const auto& u, const auto& v) {
    return std::memcmp(u.data(), v.data(), sizeof(double) * static_cast<std::size_t>(u.size())) == 0;
  };
  const Eigen::Vector2d qa = a.q.col(i), qb = b.q.col(j), pa = a.p.col(i), pb = b.p.col(j);
  return same(qa, qb) && same(pa, pb) && a.frames.size() == static_cast<std::size_t>(a.bodies()) &&
         b.frames.size() == static_cast<std::size_t>(b.bodies()) &&
         same(a.frames[static_cast<std::size_t>(i)], b.frames[static_cast<std::size_t>(j)]);
}

/// The whole system's bodies as the two domains share them: each body's latest state (q, p,
/// frame) written by its owner, read by the domain whose halo holds it, between barriers.
struct Shared {
  explicit Shared(int n) : q(2, n), p(2, n), frames(static_cast<std::size_t>(n)), rows(static_cast<std::size_t>(n)) {}
  Eigen::Matrix<double, 2, Eigen::Dynamic> q, p;
  std::vector<State::Frame> frames;
  std::vector<double> rows;
  std::barrier<> sync{2};
};

/// One domain: bodies [first, last) of the whole system (the lattice is in descending z, so a
/// half of the sphere is a range of indices), of which [own_first, own_last) are its own.
struct Domain {
  int first, last, own_first, own_last;
  bool own(int local) const { return first + local >= own_first && first + local < own_last; }
};

}  // namespace

TEST_CASE("two domains with halos step their bodies to the bits of the whole system") {
  sesi::parallel::set_threads(1);  // (the domains' threads are their own; none inside them)
  // Few steps: the bodies move little, so the halo is little wider than the cutoff, and the halo
  // bodies within reach of a domain's own have partners outside it (their rows are incomplete: only
  // the refresh after the drift gives the domain their true positions at the kick).
  const int n = 600, steps = 6;
  const double dt = 0.005, cutoff = 2.5;
  const Chart chart(radius_for(2, n));
  const State start = lattice_state(chart, n, 2.0, 41);
  const Sys whole(chart, std::vector<double>(n, 1.0), sesi::LennardJones<double>{1.0, 1.0, cutoff});

  // The bodies' largest move over the run bounds the halo it needs: every pair within the cutoff
  // at some step was within cutoff + 2 * move at the start. Found by running the whole system,
  // whose states are also the reference.
  std::vector<State> reference{start};
  std::vector<double> energies;
  {
    Engine engine(sesi::RechartPolicy<double>{});
    State x = start;
    auto w = whole.make_workspace();
    for (int k = 0; k < steps; ++k) {
      engine.do_step(std::cref(whole), x, 0.0, dt);
      reference.push_back(x);
      energies.push_back(whole.energy(x, w));
    }
  }
  double move = 0.0;  // the largest chord from a body's start to where it is at any step
  for (std::size_t k = 1; k < reference.size(); ++k) {
    for (int b = 0; b < n; ++b) {
      Eigen::Vector3d x0, x1;
      chart.embed(Eigen::Vector2d(start.q.col(b)), x0);
      chart.embed(Eigen::Vector2d(reference[k].q.col(b)), x1);
      x1 = reference[k].frames[static_cast<std::size_t>(b)] * x1;
      move = std::max(move, (x1 - x0).norm());
    }
  }
  // A body outside a domain's halo started at least halo away in z, hence in distance, from every
  // body the domain owns; each moved a distance of at most (pi / 2) x its chord (2R asin(c/2R)
  // <= pi c / 2), so with halo = cutoff + 4 move > cutoff + pi move no such pair comes within the
  // cutoff.
  const double halo = cutoff + 4.0 * move;
  MESSAGE("largest chord moved " << move << ", halo " << halo << " on a sphere of radius " << chart.radius());
  REQUIRE(halo < 2.0 * cutoff);  // halo bodies within the cutoff of a domain's own have partners outside

  // The cut at z = 0 (body index n / 2 on the lattice of descending z); the halos reach halo in z.
  int up = 0, down = n;  // the first body with z < halo, the last with z > -halo (exclusive)
  for (int b = 0; b < n; ++b) {
    const double z = chart.radius() * (1.0 - (2.0 * b + 1.0) / n);
    if (z >= halo) up = b + 1;
    if (z > -halo) down = b + 1;
  }
  const Domain north{0, down, 0, n / 2}, south{up, n, n / 2, n};
  REQUIRE(down < n);
  REQUIRE(up > 0);

  Shared shared(n);
  std::vector<std::vector<State>> stepped(2);
  std::vector<std::vector<double>> energy(2);
  const auto run = [&](const Domain& d, int which) {
    const int m = d.last - d.first;
    Sys sys(chart, std::vector<double>(static_cast<std::size_t>(m), 1.0), sesi::LennardJones<double>{1.0, 1.0, cutoff});
    std::vector<int> halo_bodies;
    for (int l = 0; l < m; ++l) {
      if (!d.own(l)) halo_bodies.push_back(l);
    }
    sys.set_domain(
        [&](const std::vector<double>& rows) {
          for (int l = 0; l < m; ++l) {
            if (d.own(l)) shared.rows[static_cast<std::size_t>(d.first + l)] = rows[static_cast<std::size_t>(l)];
          }
          shared.sync.arrive_and_wait();
          const double total = sesi::parallel::sum_in_order(shared.rows);
          shared.sync.arrive_and_wait();
          return total;
        },
        [&](State& x, sesi::Workspace<Chart>& w) {
          for (int l = 0; l < m; ++l) {
            if (d.own(l)) shared.q.col(d.first + l) = x.q.col(l);
          }
          shared.sync.arrive_and_wait();
          for (const int l : halo_bodies) x.q.col(l) = shared.q.col(d.first + l);
          shared.sync.arrive_and_wait();
          sys.refresh_bodies(x, w, halo_bodies);
        });
    State x(2, m);
    x.q = start.q.middleCols(d.first, m);
    x.p = start.p.middleCols(d.first, m);
    Engine engine(sesi::RechartPolicy<double>{});
    auto w = sys.make_workspace();
    for (int k = 0; k < steps; ++k) {
      engine.do_step(std::cref(sys), x, 0.0, dt);
      // After the step (and its re-chartings): the halo's whole state from its owner.
      for (int l = 0; l < m; ++l) {
        if (!d.own(l)) continue;
        shared.q.col(d.first + l) = x.q.col(l);
        shared.p.col(d.first + l) = x.p.col(l);
        shared.frames[static_cast<std::size_t>(d.first + l)] = x.frames[static_cast<std::size_t>(l)];
      }
      shared.sync.arrive_and_wait();
      for (const int l : halo_bodies) {
        x.q.col(l) = shared.q.col(d.first + l);
        x.p.col(l) = shared.p.col(d.first + l);
        x.frames[static_cast<std::size_t>(l)] = shared.frames[static_cast<std::size_t>(d.first + l)];
      }
      shared.sync.arrive_and_wait();
      stepped[static_cast<std::size_t>(which)].push_back(x);
      energy[static_cast<std::size_t>(which)].push_back(sys.energy(x, w));
    }
  };
  std::thread a(run, std::cref(north), 0), b(run, std::cref(south), 1);
  a.join();
  b.join();

  const Domain domains[2] = {north, south};
  for (int k = 0; k < steps; ++k) {
    INFO("step " << k + 1);
    for (std::size_t which = 0; which < 2; ++which) {
      const Domain& d = domains[which];
      const State& mine = stepped[which][static_cast<std::size_t>(k)];
      for (int g = d.own_first; g < d.own_last; ++g) {
        INFO("body " << g);
        REQUIRE(same_body(mine, g - d.first, reference[static_cast<std::size_t>(k + 1)], g));
      }
      CHECK(energy[which][static_cast<std::size_t>(k)] == energies[static_cast<std::size_t>(k)]);
    }
  }
}
