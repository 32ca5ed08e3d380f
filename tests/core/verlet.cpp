// On E^n the chart scheme is Stoermer-Verlet (issue #2; docs/scheme.md): the kick-drift-kick
// form is velocity Verlet, the drift-kick-drift form position Verlet, and the compositions are
// the same compositions of Verlet. Checked against hand-written loops on the same potentials
// (a trap and a linear spring between the two bodies), to round-off.
//
// The bound: the hand loop and the library differ only in the order of rounded operations (the
// library drifts level by level, splits the drift of levels < n into two half drifts in the KDK
// form, and gets the pair force as d (x - y)/d): per step and stage, each coordinate differs by
// at most about 4 eps times the state's size. The scene is linear and the step small
// (h omega < 0.2), so the Verlet map's powers stay bounded by about 1 and these differences add
// up linearly: after N steps of s stages, |difference| <= 4 s N eps max|z| (times 2 for the
// eigenbasis' condition, which is 1 + O(h omega)^2). A wrong form (DKD for KDK) or a wrong
// weight differs by O(h^2) = 1e-3: far above.
#include <array>
#include <cmath>
#include <limits>
#include <tuple>

#include <doctest/doctest.h>

#include "common.hpp"

namespace {

using namespace coretest;
namespace co = sesi::coefficients;

template <class Chart>
using LinearScene = sesi::System<Chart, Trap<Chart>, sesi::HarmonicPair<typename Chart::Scalar>>;

template <class Chart>
LinearScene<Chart> linear_scene() {
  using Scalar = typename Chart::Scalar;
  Chart chart = make_chart<Chart>();
  return LinearScene<Chart>(chart, std::vector<Scalar>{Scalar(1), Scalar(1.5)},
                            Trap<Chart>{Scalar(0.5), trap_centre(chart)},
                            sesi::HarmonicPair<Scalar>{Scalar(0.3), Scalar(0)});
}

/// The potential's gradient by hand: trap m k (x - c), spring k (x_0 - x_1) on body 0 and its
/// negative on body 1.
template <class Chart>
typename sesi::State<Chart>::Matrix gradient(const LinearScene<Chart>& sys,
                                             const typename sesi::State<Chart>::Matrix& q) {
  const auto& trap = std::get<0>(sys.terms());
  const auto& spring = std::get<1>(sys.terms());
  typename sesi::State<Chart>::Matrix g(q.rows(), q.cols());
  for (int b = 0; b < 2; ++b) g.col(b) = (sys.mass(b) * trap.k) * (q.col(b) - trap.c);
  const auto f = (spring.k * (q.col(0) - q.col(1))).eval();
  g.col(0) += f;
  g.col(1) -= f;
  return g;
}

template <class Chart>
void velocity_verlet(const LinearScene<Chart>& sys, sesi::State<Chart>& x,
                     typename Chart::Scalar h) {
  using Scalar = typename Chart::Scalar;
  x.p -= (h / Scalar(2)) * gradient(sys, x.q);
  for (int b = 0; b < 2; ++b) x.q.col(b) += h * x.p.col(b) / sys.mass(b);
  x.p -= (h / Scalar(2)) * gradient(sys, x.q);
}

template <class Chart>
void position_verlet(const LinearScene<Chart>& sys, sesi::State<Chart>& x,
                     typename Chart::Scalar h) {
  using Scalar = typename Chart::Scalar;
  for (int b = 0; b < 2; ++b) x.q.col(b) += (h / Scalar(2)) * x.p.col(b) / sys.mass(b);
  x.p -= h * gradient(sys, x.q);
  for (int b = 0; b < 2; ++b) x.q.col(b) += (h / Scalar(2)) * x.p.col(b) / sys.mass(b);
}

/// N steps of the library method and of the hand-written composition of the Verlet form.
template <class Table, sesi::Splitting Form, class Chart>
void check_verlet(long steps) {
  using Scalar = typename Chart::Scalar;
  const auto sys = linear_scene<Chart>();
  const auto x0 = initial_state(sys, 9);
  const Scalar h = Scalar(0.05);
  sesi::Composition<Table, Chart, Form> stepper;
  const auto w = Table::template weights<Scalar>();
  auto x = x0, y = x0;
  Scalar scale = size_of(x0);
  for (long k = 0; k < steps; ++k) {
    stepper.do_step(sys, x, Scalar(k) * h, h);
    for (const Scalar wk : w) {
      if constexpr (Form == sesi::Splitting::kick_drift_kick) {
        velocity_verlet(sys, y, wk * h);
      } else {
        position_verlet(sys, y, wk * h);
      }
    }
    scale = std::max(scale, size_of(y));
  }
  const Scalar bound = Scalar(2 * 4 * Table::stages) * Scalar(steps) * eps<Scalar>() * scale;
  const Scalar err = distance(x, y);
  MESSAGE(Table::name, Form == sesi::Splitting::kick_drift_kick ? " velocity" : " position",
          " Verlet: difference ", double(err), " (", double(err / (eps<Scalar>() * scale)),
          " eps), bound ", double(bound));
  CHECK(err <= bound);
}

}  // namespace

using EuclideanCharts =
    std::tuple<sesi::Euclidean<1, double>, sesi::Euclidean<2, double>, sesi::Euclidean<3, double>,
               sesi::Euclidean<4, double>, sesi::Euclidean<5, double>, sesi::Euclidean<6, double>>;

TEST_CASE_TEMPLATE_DEFINE("verlet: E^n reproduces velocity and position Verlet", Chart,
                          verlet_dims) {
  check_verlet<co::Strang, sesi::Splitting::kick_drift_kick, Chart>(200);
  check_verlet<co::Strang, sesi::Splitting::drift_kick_drift, Chart>(200);
  check_verlet<co::Yoshida4, sesi::Splitting::kick_drift_kick, Chart>(200);
  check_verlet<co::Yoshida4, sesi::Splitting::drift_kick_drift, Chart>(200);
}
TEST_CASE_TEMPLATE_APPLY(verlet_dims, EuclideanCharts);

TEST_CASE_TEMPLATE("verlet: velocity Verlet in float and long double on E^3", Scalar, float,
                   long double) {
  check_verlet<co::Strang, sesi::Splitting::kick_drift_kick, sesi::Euclidean<3, Scalar>>(200);
  check_verlet<co::Strang, sesi::Splitting::drift_kick_drift, sesi::Euclidean<3, Scalar>>(200);
}

// Issue #14's defect: the kick-drift-kick form reuses the last step's gradient when the system is
// the same. A System rebuilt in the loop with a new spring constant lands at the address of the
// last one; an identity by address reused the old constant's gradient (p = -0.2475 after two
// steps instead of -0.2968 in the scene). Each step here must be velocity Verlet with its
// own k, to round-off: the two loops round the same operations alike up to the library's order of
// the half kicks, a few eps of |z| <= 1 per step.
TEST_CASE("verlet: a System rebuilt every step with new parameters kicks with them") {
  using Chart = sesi::Euclidean<1, double>;
  using Scene = sesi::System<Chart, Trap<Chart>>;
  sesi::Composition<co::Strang, Chart, sesi::Splitting::kick_drift_kick> stepper;
  sesi::State<Chart> x(1, 1);
  x.q(0, 0) = 1.0;
  x.p(0, 0) = 0.0;
  double q = 1.0, p = 0.0;
  const double h = 0.1;
  for (int n = 0; n < 10; ++n) {
    const double k = 1.0 + 0.5 * n;
    Scene scene(Chart{}, std::vector<double>{1.0}, Trap<Chart>{k, Chart::Ambient::Zero()});
    stepper.do_step(scene, x, n * h, h);
    p -= h / 2 * k * q;  // velocity Verlet with this step's k
    q += h * p;
    p -= h / 2 * k * q;
    CHECK(std::abs(x.q(0, 0) - q) <= 8 * (n + 1) * std::numeric_limits<double>::epsilon());
    CHECK(std::abs(x.p(0, 0) - p) <= 8 * (n + 1) * std::numeric_limits<double>::epsilon() * (1 + k));
  }
}
