// Shared scenes, type lists and measurements of the core tests (tests/core/*.cpp).
//
// Every bound in these tests is derived from the method's order, the step and the scalar's
// epsilon; the derivation is written next to each bound. The helpers here only measure.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>
#include <tuple>
#include <vector>

#include <Eigen/Core>

#include <sesi/chart.hpp>
#include <sesi/coefficients.hpp>
#include <sesi/config.hpp>
#include <sesi/potentials.hpp>
#include <sesi/spaces/euclidean.hpp>
#include <sesi/spaces/hyperbolic.hpp>
#include <sesi/spaces/sphere.hpp>
#include <sesi/state.hpp>
#include <sesi/stepper.hpp>
#include <sesi/system.hpp>

namespace coretest {

// ---- invariant checks throw (so that a failing check is a failing test, not an abort) ------

struct CheckFailure : std::runtime_error {
  using std::runtime_error::runtime_error;
};
[[noreturn]] inline void throwing_handler(const char* expr, const char* what, const char* file,
                                          int line) {
  throw CheckFailure(std::string(what) + " (" + expr + ") at " + file + ":" + std::to_string(line));
}
inline const bool check_handler_installed = (sesi::set_check_handler(&throwing_handler), true);

// ---- type lists ----------------------------------------------------------------------------

template <class Scalar>
using AllCharts = std::tuple<
    sesi::Sphere<1, Scalar>, sesi::Sphere<2, Scalar>, sesi::Sphere<3, Scalar>,
    sesi::Sphere<4, Scalar>, sesi::Sphere<5, Scalar>, sesi::Sphere<6, Scalar>,
    sesi::Hyperbolic<1, Scalar>, sesi::Hyperbolic<2, Scalar>, sesi::Hyperbolic<3, Scalar>,
    sesi::Hyperbolic<4, Scalar>, sesi::Hyperbolic<5, Scalar>, sesi::Hyperbolic<6, Scalar>,
    sesi::Euclidean<1, Scalar>, sesi::Euclidean<2, Scalar>, sesi::Euclidean<3, Scalar>,
    sesi::Euclidean<4, Scalar>, sesi::Euclidean<5, Scalar>, sesi::Euclidean<6, Scalar>>;

// (charts that are none of the three, like the generic-path wrapper, count by their curvature
// where it matters.)
template <class Chart>
constexpr bool is_sphere = std::is_same_v<Chart, sesi::Sphere<Chart::dimension, typename Chart::Scalar>>;
template <class Chart>
constexpr bool is_hyperbolic =
    std::is_same_v<Chart, sesi::Hyperbolic<Chart::dimension, typename Chart::Scalar>>;
template <class Chart>
constexpr bool is_euclidean =
    std::is_same_v<Chart, sesi::Euclidean<Chart::dimension, typename Chart::Scalar>>;

/// The same chart type with another scalar.
template <class Chart, class Scalar>
struct Rebind;
template <template <int, class> class Space, int N, class S, class Scalar>
struct Rebind<Space<N, S>, Scalar> {
  using type = Space<N, Scalar>;
};
template <class Chart, class Scalar>
using rebind_t = typename Rebind<Chart, Scalar>::type;

template <class Scalar>
Scalar eps() {
  return std::numeric_limits<Scalar>::epsilon();
}

// ---- charts, terms and scenes --------------------------------------------------------------

/// Radius of the curved test spaces (not 1, so that R is exercised; 5/4 is exact in binary).
template <class Scalar>
Scalar test_radius() {
  return Scalar(5) / Scalar(4);
}

/// A chart of the given type (dim matters for Eigen::Dynamic only).
template <class Chart>
Chart make_chart(int dim = Chart::dimension, typename Chart::Scalar radius =
                                                 test_radius<typename Chart::Scalar>()) {
  if constexpr (requires { Chart(radius, dim); }) {
    return Chart(radius, dim);
  } else {
    (void)radius;
    return Chart(dim);
  }
}

/// External trap V(x) = m k/2 |x - c|^2 on ambient points: a pendulum on S^n (|x| = R makes it
/// linear in x), a confining well on H^n (|x|^2 = R^2 cosh 2 q_1) and E^n. Smooth everywhere.
template <class Space>
struct Trap {
  using Scalar = typename Space::Scalar;
  using Ambient = typename Space::Ambient;
  Scalar k;
  Ambient c;
  Scalar value(const Space&, const Ambient& x, Scalar m) const {
    return m * k / Scalar(2) * (x - c).squaredNorm();
  }
  void gradient(const Space&, const Ambient& x, Scalar m, Ambient& g) const {
    g = (m * k) * (x - c);
  }
};

/// A smooth pair term on the geodesic distance: a spring k d^2/2 with a Gaussian core
/// a exp(-d^2/2s^2). Both are smooth functions of d^2, so the force has no kink.
template <class Scalar>
struct SoftPair {
  using distance_kind = sesi::geodesic_distance;
  Scalar k, a, s;
  template <class Space>
  Scalar value(const Space&, Scalar d, Scalar, Scalar) const {
    using std::exp;
    return k / Scalar(2) * d * d + a * exp(-d * d / (Scalar(2) * s * s));
  }
  template <class Space>
  Scalar derivative(const Space&, Scalar d, Scalar, Scalar) const {
    using std::exp;
    return k * d - a * d / (s * s) * exp(-d * d / (Scalar(2) * s * s));
  }
};

/// The trap's centre: a fixed ambient vector, not aligned with the chart's axes.
template <class Chart>
typename Chart::Ambient trap_centre(const Chart& chart) {
  using Scalar = typename Chart::Scalar;
  typename Chart::Ambient c(chart.ambient_dim());
  for (int i = 0; i < chart.ambient_dim(); ++i) c[i] = Scalar(0.3) * std::cos(Scalar(1.7 * i + 0.4));
  return c;
}

template <class Chart>
using Scene = sesi::System<Chart, Trap<Chart>, SoftPair<typename Chart::Scalar>>;

/// Two bodies (masses 1 and 3/2) with the trap and a soft pair term.
template <class Chart>
Scene<Chart> make_scene(int dim = Chart::dimension) {
  using Scalar = typename Chart::Scalar;
  Chart chart = make_chart<Chart>(dim);
  Trap<Chart> trap{Scalar(0.5), trap_centre(chart)};
  return Scene<Chart>(chart, std::vector<Scalar>{Scalar(1), Scalar(1.5)}, trap,
                      SoftPair<Scalar>{Scalar(0.3), Scalar(0.2), Scalar(0.5)});
}

/// Length of the order runs of the scene: 1, and 1/2 on H^n, where the trap pulls the bodies
/// towards the polar origin (the chart's singular point) and the motion speeds up there.
template <class Chart>
typename Chart::Scalar scene_time() {
  using Scalar = typename Chart::Scalar;
  return is_hyperbolic<Chart> ? Scalar(0.5) : Scalar(1);
}

/// Smallest sine of a polar angle of q (the chart's 1/sin^2 factors are below its inverse square),
/// and for H^n (n >= 2) also sinh q_1. 1 for charts without poles.
template <class Chart>
typename Chart::Scalar pole_distance(const Chart& chart, const typename Chart::Point& q) {
  using std::abs;
  using std::min;
  using std::sin;
  using std::sinh;
  using Scalar = typename Chart::Scalar;
  Scalar s(1);
  if constexpr (is_sphere<Chart>) {
    for (int k = 0; k + 1 < chart.dim(); ++k) s = min(s, abs(sin(q[k])));
  }
  if constexpr (is_hyperbolic<Chart>) {
    if (chart.dim() >= 2) {
      s = min(s, abs(sinh(q[0])));
      for (int k = 1; k + 1 < chart.dim(); ++k) s = min(s, abs(sin(q[k])));
    }
  }
  return s;
}

/// A random point of the chart's safe region: polar angles in [1, 2.1] (sin >= 0.86), the
/// hyperbolic radius in [0.6, 1.2] (n >= 2) or [-0.8, 0.8] (n = 1), the last angle anywhere,
/// Euclidean coordinates in [-1, 1].
template <class Chart, class Rng>
typename Chart::Point random_point(const Chart& chart, Rng& rng) {
  using Scalar = typename Chart::Scalar;
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const auto in = [&](double a, double b) { return Scalar(a + (b - a) * u(rng)); };
  const int n = chart.dim();
  typename Chart::Point q(n);
  for (int k = 0; k < n; ++k) {
    if (chart.curvature() == Scalar(0)) {
      q[k] = in(-1.0, 1.0);
    } else if (k == n - 1 && !(chart.curvature() < Scalar(0) && n == 1)) {
      q[k] = in(-3.0, 3.0);
    } else if (k == 0 && chart.curvature() < Scalar(0)) {
      q[k] = n == 1 ? in(-0.8, 0.8) : in(0.6, 1.2);
    } else {
      q[k] = in(1.0, 2.1);
    }
  }
  return q;
}

/// A random state of `bodies` bodies in the safe region with momenta in [-0.4, 0.4] m, bodies at
/// geodesic distance at least 0.5 from each other (and from antipodes on S^n).
template <class Sys, class Rng>
sesi::State<typename Sys::Chart> random_state(const Sys& sys, Rng& rng) {
  using Chart = typename Sys::Chart;
  using Scalar = typename Chart::Scalar;
  const Chart& chart = sys.chart();
  std::uniform_real_distribution<double> u(-0.4, 0.4);
  sesi::State<Chart> x(chart.dim(), sys.bodies());
  for (int attempt = 0; attempt < 1000; ++attempt) {
    for (int b = 0; b < sys.bodies(); ++b) {
      x.q.col(b) = random_point(chart, rng);
      for (int i = 0; i < chart.dim(); ++i) x.p(i, b) = Scalar(u(rng)) * sys.mass(b);
    }
    bool separated = true;
    typename Chart::Point q(chart.dim());
    typename Chart::Ambient xa(chart.ambient_dim()), xb(chart.ambient_dim());
    for (int a = 0; a < sys.bodies(); ++a) {
      for (int b = a + 1; b < sys.bodies(); ++b) {
        q = x.q.col(a);
        chart.embed(q, xa);
        q = x.q.col(b);
        chart.embed(q, xb);
        const Scalar d = chart.distance(xa, xb);
        if (d < Scalar(0.5)) separated = false;
        if constexpr (is_sphere<Chart>) {
          if (d > std::numbers::pi_v<Scalar> * chart.radius() - Scalar(0.5)) separated = false;
        }
      }
    }
    if (separated) return x;
  }
  throw std::logic_error("random_state: no separated configuration found");
}

template <class Sys>
sesi::State<typename Sys::Chart> initial_state(const Sys& sys, std::uint32_t seed = 7) {
  std::mt19937 rng(seed);
  return random_state(sys, rng);
}

// ---- runs and measurements -----------------------------------------------------------------

/// The runtime-table engine with the weights of Table, as a default-constructible stepper:
/// sesi::Composition<coefficients::Runtime, ...>::of<Table>() steps bit for bit as
/// Composition<Table, ...> (stepper.hpp; tests/program/integrators/test_runtime_composition.cpp
/// checks it for every table). One engine serves every table, so a test of every method compiles
/// it once per chart and form instead of once per table.
template <class Table, class Chart, sesi::Splitting Form = sesi::Splitting::drift_kick_drift>
struct RuntimeComposition : sesi::Composition<sesi::coefficients::Runtime, Chart, Form> {
  using Base = sesi::Composition<sesi::coefficients::Runtime, Chart, Form>;
  using table = Table;
  RuntimeComposition() : Base(Base::template of<Table>()) {}
};

/// x after `steps` steps of t_end/steps with a fresh Stepper.
template <class Stepper, class Sys>
sesi::State<typename Sys::Chart> run(const Sys& sys, sesi::State<typename Sys::Chart> x,
                                     typename Sys::Scalar t_end, long steps) {
  using Scalar = typename Sys::Scalar;
  Stepper stepper;
  const Scalar dt = t_end / Scalar(steps);
  for (long k = 0; k < steps; ++k) stepper.do_step(sys, x, Scalar(k) * dt, dt);
  return x;
}

/// Max-norm distance between two states (q and p).
template <class Chart>
typename Chart::Scalar distance(const sesi::State<Chart>& a, const sesi::State<Chart>& b) {
  using std::max;
  return max((a.q - b.q).cwiseAbs().maxCoeff(), (a.p - b.p).cwiseAbs().maxCoeff());
}

/// Max-norm size of a state (q and p), at least 1.
template <class Chart>
typename Chart::Scalar size_of(const sesi::State<Chart>& a) {
  using std::max;
  using Scalar = typename Chart::Scalar;
  return max({Scalar(1), a.q.cwiseAbs().maxCoeff(), a.p.cwiseAbs().maxCoeff()});
}

/// The order measured from three runs at N, 2N, 4N steps: the differences of the final states
/// e(h) - e(h/2) ~ C h^p (1 - 2^-p) fall by 2^p per halving, so log2(d1/d2) -> p.
struct OrderMeasurement {
  double order;
  double d1, d2;  ///< |x_N - x_2N|, |x_2N - x_4N|
  double scale;   ///< size of the final state
};
template <class Stepper, class Sys>
OrderMeasurement measure_order(const Sys& sys, const sesi::State<typename Sys::Chart>& x0,
                               typename Sys::Scalar t_end, long steps) {
  const auto a = run<Stepper>(sys, x0, t_end, steps);
  const auto b = run<Stepper>(sys, x0, t_end, 2 * steps);
  const auto c = run<Stepper>(sys, x0, t_end, 4 * steps);
  const double d1 = static_cast<double>(distance(a, b)), d2 = static_cast<double>(distance(b, c));
  return {std::log2(d1 / d2), d1, d2, static_cast<double>(size_of(c))};
}

/// Flatten a state as z = (q column-major, then p column-major): q(i,b) and p(i,b) share an
/// index, so the canonical structure is J = [[0, I], [-I, 0]].
template <class Chart>
Eigen::Matrix<typename Chart::Scalar, Eigen::Dynamic, 1> flatten(const sesi::State<Chart>& s) {
  const Eigen::Index m = s.q.size();
  Eigen::Matrix<typename Chart::Scalar, Eigen::Dynamic, 1> z(2 * m);
  z.head(m) = s.q.reshaped();
  z.tail(m) = s.p.reshaped();
  return z;
}
template <class Chart>
void unflatten(const Eigen::Matrix<typename Chart::Scalar, Eigen::Dynamic, 1>& z,
               sesi::State<Chart>& s) {
  const Eigen::Index m = s.q.size();
  s.q.reshaped() = z.head(m);
  s.p.reshaped() = z.tail(m);
}

}  // namespace coretest
