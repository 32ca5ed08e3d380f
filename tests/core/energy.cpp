// Energy: no drift over 10^6 steps on smooth bounded scenes (issue #2). A symplectic method
// conserves a modified energy H~ = H + O(tau^p) over exponentially long times (HLW IX.8), so
// |H(x_k) - H(x_0)| oscillates with a bounded amplitude: its maximum over the second half of the
// run is not above the first half's by more than a factor 1.5. A drifting method (non-symplectic,
// or a symplectic method with a bug that breaks the structure) grows its energy error linearly
// or faster: factor 2 or more between the halves. Round-off adds a random walk of about
// sqrt(10^6) eps |H| ~ 1e-13, far below the O(tau^p) amplitude (1e-5 .. 1e-3 here).
//
// The scenes keep the bodies away from the chart's poles for all time through a conserved
// momentum that the chart sees exactly (the last angle is cyclic for potentials symmetric about
// the pole axis): a spherical pendulum on S^2, a central trap on H^2, a pendulum on S^3.
#include <algorithm>
#include <cmath>

#include <doctest/doctest.h>

#include "common.hpp"

namespace {

using namespace coretest;

struct Halves {
  double first = 0, second = 0;
};

/// Max |H - H_0| over the first and second halves of `steps` steps of tau.
template <class Method, class Sys>
Halves energy_halves(const Sys& sys, sesi::State<typename Sys::Chart> x, double tau, long steps) {
  using Scalar = typename Sys::Scalar;
  auto w = sys.make_workspace();
  const double e0 = static_cast<double>(sys.energy(x, w));
  Method stepper;
  Halves h;
  for (long k = 0; k < steps; ++k) {
    stepper.do_step(sys, x, Scalar(k) * Scalar(tau), Scalar(tau));
    const double err = std::abs(static_cast<double>(sys.energy(x, w)) - e0);
    double& slot = k < steps / 2 ? h.first : h.second;
    slot = std::max(slot, err);
  }
  return h;
}

/// V = k m x_axis: a pendulum hanging along the axis (the potential of uniform gravity).
template <class Space>
struct Pendulum {
  using Scalar = typename Space::Scalar;
  using Ambient = typename Space::Ambient;
  Scalar k;
  int axis;  ///< the ambient coordinate the pendulum hangs along
  Scalar value(const Space&, const Ambient& x, Scalar m) const { return k * m * x[axis]; }
  void gradient(const Space& s, const Ambient&, Scalar m, Ambient& g) const {
    g.setZero(s.ambient_dim());
    g[axis] = k * m;
  }
};

constexpr long steps = 1000000;

}  // namespace

TEST_CASE("energy: Strang on S^2 (spherical pendulum), 10^6 steps, no drift") {
  using Chart = sesi::Sphere<2, double>;
  // Hangs along x_3 = R cos q_1: the axis of the chart, so p_2 is conserved exactly and keeps
  // the body off the poles.
  const sesi::System sys(Chart(1.25), std::vector<double>{1.0}, Pendulum<Chart>{1.0, 2});
  sesi::State<Chart> x(2, 1);
  x.q << 1.2, 0.3;
  x.p << 0.4, 0.8;
  const auto h = energy_halves<sesi::Strang<Chart>>(sys, x, 0.05, steps);
  MESSAGE("S^2 Strang: first half ", h.first, ", second half ", h.second);
  CHECK(h.first > 0);
  CHECK(h.second <= 1.5 * h.first);
}

TEST_CASE("energy: Strang on H^2 (central trap), 10^6 steps, no drift") {
  using Chart = sesi::Hyperbolic<2, double>;
  // The trap centred on the chart origin is symmetric about it: p_2 is conserved exactly.
  Chart chart(1.25);
  Trap<Chart> trap{0.5, Chart::Ambient::Zero()};
  const sesi::System sys(chart, std::vector<double>{1.0}, trap);
  sesi::State<Chart> x(2, 1);
  x.q << 0.8, 0.3;
  x.p << 0.3, 0.9;
  const auto h = energy_halves<sesi::Strang<Chart>>(sys, x, 0.05, steps);
  MESSAGE("H^2 Strang: first half ", h.first, ", second half ", h.second);
  CHECK(h.first > 0);
  CHECK(h.second <= 1.5 * h.first);
}

TEST_CASE("energy: Yoshida4 on S^3 (pendulum), 10^6 steps, no drift") {
  using Chart = sesi::Sphere<3, double>;
  // Hangs along x_4 = R cos q_1; the motion in (q_2, q_3) is free motion on S^2 with conserved
  // p_3 != 0, which keeps q_2 off its poles.
  const sesi::System sys(Chart(1.25), std::vector<double>{1.0}, Pendulum<Chart>{1.0, 3});
  sesi::State<Chart> x(3, 1);
  x.q << 1.2, 1.4, 0.3;
  x.p << 0.4, 0.3, 0.8;
  const auto h = energy_halves<sesi::Yoshida4<Chart>>(sys, x, 0.05, steps);
  MESSAGE("S^3 Yoshida4: first half ", h.first, ", second half ", h.second);
  CHECK(h.first > 0);
  CHECK(h.second <= 1.5 * h.first);
}
