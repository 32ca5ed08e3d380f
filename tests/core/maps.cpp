// The maps of the built-in spaces (issue #2): chart <-> embedding for points, momentum <->
// velocity, geodesic distance and its gradient against finite differences, the invariants
// |x| = R and <x,x>_L = -R^2, and the momentum map conserved under a rotation-invariant flow.
#include <algorithm>
#include <cmath>
#include <random>
#include <tuple>

#include <doctest/doctest.h>

#include <sesi/diagnostics.hpp>

#include "common.hpp"

namespace {

using namespace coretest;
using Real = long double;

/// Ratio of the largest to the smallest inverse-metric coefficient at q (1/g_ii = dK_i/dp_i at
/// p_i = m = 1): the condition number of the momentum <-> velocity maps.
template <class Chart>
double metric_condition(const Chart& chart, const typename Chart::Point& q) {
  double lo = 1e300, hi = 0;
  for (int i = 0; i < chart.dim(); ++i) {
    const double g = static_cast<double>(chart.kinetic_dp(i, q, 1, 1));
    lo = std::min(lo, g);
    hi = std::max(hi, g);
  }
  return hi / lo;
}

/// Central difference of the long double embedding along direction dq at q (step 2^-20:
/// truncation delta^2/6 |x'''| ~ 1e-13, round-off eps_ld / delta ~ 1e-13).
template <class Chart>
Eigen::Matrix<Real, Eigen::Dynamic, 1> embed_derivative(const typename Chart::Point& q,
                                                        const typename Chart::Point& dq) {
  using RChart = rebind_t<Chart, Real>;
  const RChart chart = make_chart<RChart>();
  const Real delta = std::ldexp(Real(1), -20);
  typename RChart::Point qp = q.template cast<Real>() + delta * dq.template cast<Real>();
  typename RChart::Point qm = q.template cast<Real>() - delta * dq.template cast<Real>();
  typename RChart::Ambient xp, xm;
  chart.embed(qp, xp);
  chart.embed(qm, xm);
  return (xp - xm) / (2 * delta);
}

}  // namespace

TEST_CASE_TEMPLATE_DEFINE("maps: chart and embedding, momentum and velocity, invariants", Chart,
                          maps_points) {
  using Scalar = typename Chart::Scalar;
  const Chart chart = make_chart<Chart>();
  const int n = chart.dim();
  const double e = static_cast<double>(eps<Scalar>());
  std::mt19937 rng(21);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int trial = 0; trial < 20; ++trial) {
    const typename Chart::Point q = random_point(chart, rng);
    typename Chart::Point p(n), q2(n), p2(n), jg(n);
    for (int i = 0; i < n; ++i) p[i] = Scalar(u(rng));
    const Scalar m = Scalar(1.5);
    typename Chart::Ambient x(chart.ambient_dim()), v(chart.ambient_dim()), g(chart.ambient_dim());
    chart.embed(q, x);
    chart.velocity(q, p, m, v);
    const double s = static_cast<double>(pole_distance(chart, q));
    const double xn = static_cast<double>(x.norm()), vn = static_cast<double>(v.norm());

    // Invariants: x is built from n + 1 products of at most n rounded factors, so |x|^2 - R^2
    // (or <x,x> + R^2) is within 2 (n + 2) eps of |x|^2; v is tangent to eps (|x||v|) as well.
    const double c = static_cast<double>(std::abs(chart.constraint(x)));
    const double t = static_cast<double>(std::abs(chart.tangency(x, v)));
    CHECK(c <= 2 * (n + 2) * e * xn * xn);
    CHECK(t <= 4 * (n + 2) * e * xn * vn);

    // Chart round trip: each angle comes from atan2 of coordinates carrying relative errors of
    // (n + 2) eps, divided by the prefix product of sines (>= s^n): |dq| <= 4 (n + 2) eps / s^n.
    chart.chart(x, q2);
    CHECK(static_cast<double>((q2 - q).cwiseAbs().maxCoeff()) <=
          4 * (n + 2) * e / std::pow(s, n) * std::max(1.0, static_cast<double>(q.cwiseAbs().maxCoeff())));

    // Momentum round trip p -> v -> p: two maps of (n + 2) rounded factors each, amplified by the
    // metric's condition number: |dp| <= 4 (n + 2) eps kappa |p|.
    chart.momentum(q, v, m, p2);
    const double kappa = metric_condition(chart, q);
    CHECK(static_cast<double>((p2 - p).norm()) <= 4 * (n + 2) * e * kappa * static_cast<double>(p.norm()));

    // velocity = J qdot against central differences of the embedding (long double), and
    // pullback = J^T g against the same columns of J. Tolerance: the library's round-off,
    // 4 (n + 2) eps (|v| + |x| |qdot|) (J's entries are bounded by |x| and R), plus the
    // difference quotient's error, below 1e-11 (|x| |qdot|)^... for these O(1) arguments.
    typename Chart::Point qdot(n);
    for (int i = 0; i < n; ++i) qdot[i] = chart.kinetic_dp(i, q, p[i], m);
    const auto fd = embed_derivative<Chart>(q, qdot);
    const double qd = static_cast<double>(qdot.norm());
    const double scale = vn + std::max(xn, 1.0) * qd;
    CHECK(static_cast<double>((v.template cast<Real>() - fd).norm()) <= 4 * (n + 2) * e * scale + 1e-11 * (1 + scale));

    for (int i = 0; i < chart.ambient_dim(); ++i) g[i] = Scalar(u(rng));
    chart.pullback(q, g, jg);
    for (int k = 0; k < n; ++k) {
      typename Chart::Point ek = Chart::Point::Zero(n);
      ek[k] = 1;
      const Real ref = embed_derivative<Chart>(q, ek).dot(g.template cast<Real>());
      const double col = std::max(xn, 1.0) * static_cast<double>(g.norm());
      CHECK(std::abs(static_cast<double>(Real(jg[k]) - ref)) <= 4 * (n + 2) * e * col + 1e-11 * (1 + col));
    }
  }
}
TEST_CASE_TEMPLATE_APPLY(maps_points, AllCharts<double>);

TEST_CASE_TEMPLATE_DEFINE("maps: distance and its gradient", Chart, maps_distance) {
  using Scalar = typename Chart::Scalar;
  const Chart chart = make_chart<Chart>();
  const int n = chart.dim();
  const double e = static_cast<double>(eps<Scalar>());
  // Two bodies at geodesic distance >= 0.5 (and >= 0.5 from antipodal on S^n): random_state.
  const auto sys = sesi::System<Chart>(chart, std::vector<Scalar>{1, 1});
  std::mt19937 rng(8);
  for (int trial = 0; trial < 20; ++trial) {
    const auto st = random_state(sys, rng);
    const typename Chart::Point qa = st.q.col(0), qb = st.q.col(1);
    typename Chart::Ambient x, y, g;
    chart.embed(qa, x);
    chart.embed(qb, y);
    const Scalar d = chart.distance(x, y);
    // Reference from the same points in long double by the textbook formula.
    Real ref;
    const auto X = x.template cast<Real>(), Y = y.template cast<Real>();
    if constexpr (is_sphere<Chart>) {
      const Real r = chart.radius();
      ref = r * std::acos(X.dot(Y) / (r * r));
    } else if constexpr (is_hyperbolic<Chart>) {
      const Real r = chart.radius();
      ref = r * std::acosh(-sesi::minkowski(X, Y) / (r * r));
    } else {
      ref = (X - Y).norm();
    }
    // 2 R atan2(|x - y|, |x + y|): each norm has a relative error <= (n + 3) eps, which moves
    // the angle by at most half their sum; the reference's acos/acosh is well conditioned at
    // these separations. Bound: 2 (n + 3) eps (R + d).
    const double r = is_euclidean<Chart> ? 1.0 : static_cast<double>(test_radius<Scalar>());
    CHECK(std::abs(static_cast<double>(Real(d) - ref)) <= 2 * (n + 3) * e * (r + static_cast<double>(d)));

    // Gradient: (J^T grad)_k = d/ds distance(embed(q + s e_k), y), by central differences in
    // long double (step 2^-20: error ~ 1e-12 |f'''|, and f''' <= 1/sin^2(d/R) / R^2 <= 5 for
    // these separations), against the library's double gradient (round-off ~ 10 (n + 3) eps).
    // Bound 1e-10: above both by two orders, below any wrong sign or factor by ten.
    chart.distance_gradient(x, y, g);
    typename Chart::Point jg(n);
    chart.pullback(qa, g, jg);
    using RChart = rebind_t<Chart, Real>;
    const RChart rchart = make_chart<RChart>();
    const Real delta = std::ldexp(Real(1), -20);
    for (int k = 0; k < n; ++k) {
      typename RChart::Point qp = qa.template cast<Real>(), qm = qp;
      qp[k] += delta;
      qm[k] -= delta;
      typename RChart::Ambient xp, xm;
      rchart.embed(qp, xp);
      rchart.embed(qm, xm);
      const Real fd = (rchart.distance(xp, Y) - rchart.distance(xm, Y)) / (2 * delta);
      CHECK(std::abs(static_cast<double>(Real(jg[k]) - fd)) <= 1e-10);
    }
    // The gradient as a covector: it annihilates the normal direction, x . g = 0 (Euclidean dot;
    // on H^n the tangent vector is eta g, and <x, eta g>_L = x . g), and has unit length
    // (|g| on S^n and E^n, <g, g>_L on H^n: the distance grows at unit rate along geodesics).
    // Round-off: a few (n + 3) eps.
    if constexpr (!is_euclidean<Chart>) {
      CHECK(std::abs(static_cast<double>(x.dot(g))) <= 4 * (n + 3) * e * static_cast<double>(x.norm() * g.norm()));
    }
    CHECK(std::abs(static_cast<double>(chart.inner(g, g)) - 1) <= 4 * (n + 3) * e * static_cast<double>(g.squaredNorm()));
  }
}
TEST_CASE_TEMPLATE_APPLY(maps_distance,
                         std::tuple<sesi::Sphere<1>, sesi::Sphere<2>, sesi::Sphere<4>,
                                    sesi::Sphere<6>, sesi::Hyperbolic<1>, sesi::Hyperbolic<2>,
                                    sesi::Hyperbolic<4>, sesi::Hyperbolic<6>, sesi::Euclidean<3>>);

namespace {
template <class Chart>
using PairScene = sesi::System<Chart, SoftPair<typename Chart::Scalar>>;

/// Momentum map change |M(T) - M(0)| after Strang steps: component 0 (S^n, H^n: the rotation
/// of the last angle's plane, a symmetry of the chart) and the rest.
template <class Chart>
std::pair<double, double> momentum_change(const PairScene<Chart>& sys,
                                          const sesi::State<Chart>& x0, long steps) {
  const auto m0 = sesi::momentum_map(sys, x0);
  const auto x = run<sesi::Strang<Chart>>(sys, x0, scene_time<Chart>(), steps);
  const auto m1 = sesi::momentum_map(sys, x);
  const Eigen::VectorXd dm = (m1 - m0).cwiseAbs();
  if constexpr (is_euclidean<Chart>) return {dm.maxCoeff(), 0.0};
  const double rest = dm.size() > 1 ? dm.tail(dm.size() - 1).maxCoeff() : 0.0;
  return {dm[0], rest};
}
}  // namespace

TEST_CASE_TEMPLATE_DEFINE("maps: the momentum map under a rotation-invariant pair potential",
                          Chart, maps_momentum) {
  using Scalar = typename Chart::Scalar;
  const Chart chart = make_chart<Chart>();
  const PairScene<Chart> sys(chart, std::vector<Scalar>{1, 1.5, 0.75},
                             SoftPair<Scalar>{Scalar(0.3), Scalar(0.2), Scalar(0.5)});
  const auto x0 = initial_state(sys, 4);
  const int n = chart.dim();
  const long steps = 16;
  const auto [exact1, rest1] = momentum_change(sys, x0, steps);
  const auto [exact2, rest2] = momentum_change(sys, x0, 2 * steps);
  // Conserved exactly by the scheme (every sub-flow commutes with the symmetry: on E^n
  // translations and rotations, Verlet with central pair forces; on S^n and H^n the shift of the
  // last angle, which leaves every level term invariant, and the kick's sum of forces on that
  // angle is zero for a rotation-invariant potential). Round-off: as for reversibility
  // (reversibility.cpp), each sub-step perturbs M by at most (n + 4) eps sum m |x| |v|, 2n + 1
  // sub-steps per step: bound = 2N (2n + 1)(n + 4) eps sum m |x||v| (N = 2 x 16 steps).
  const auto X = sesi::embedding_points(sys, x0);
  const auto V = sesi::embedding_velocities(sys, x0);
  double mxv = 0;
  for (int b = 0; b < 3; ++b) mxv += double(sys.mass(b)) * X.col(b).norm() * std::max(1.0, V.col(b).norm());
  const double bound = 2 * 2 * steps * (2 * n + 1) * (n + 4) * 2.2e-16 * mxv;
  MESSAGE("momentum map: conserved part changes by ", exact2, " (bound ", bound,
          "); the rest by ", rest1, " -> ", rest2);
  CHECK(exact1 <= bound);
  CHECK(exact2 <= bound);
  if constexpr (!is_euclidean<Chart>) {
    if (n >= 2) {
      // The chart breaks the other rotations (docs/scheme.md): they change by O(tau^2), so
      // halving tau divides the change by 4 (order within 0.3 of 2).
      CHECK(std::abs(std::log2(rest1 / rest2) - 2.0) <= 0.3);
    }
  }
}
TEST_CASE_TEMPLATE_APPLY(maps_momentum,
                         std::tuple<sesi::Sphere<1>, sesi::Sphere<2>, sesi::Sphere<5>,
                                    sesi::Hyperbolic<1>, sesi::Hyperbolic<3>, sesi::Euclidean<3>>);

TEST_CASE_TEMPLATE_DEFINE("maps: a chord term sees the chord of the ambient metric", Chart,
                          maps_chord) {
  // W(c) = c^3 / 3 of the chord c: on S^n and E^n the Euclidean |x - y|, on H^n the Minkowski
  // chord 2R sinh(d/2R) (system.hpp, ambient_chord; a Euclidean norm there would not be
  // invariant under the boosts). Energy against the chord of the textbook distance in long
  // double; gradient against central differences of the energy in long double.
  using Scalar = typename Chart::Scalar;
  const Chart chart = make_chart<Chart>();
  const int n = chart.dim();
  auto cube = [](auto c, auto, auto) { return c * c * c / 3; };
  auto square = [](auto c, auto, auto) { return c * c; };
  const auto sys = sesi::System(chart, std::vector<Scalar>{1, 1},
                                sesi::make_pair<sesi::chord_distance>(cube, square));
  using RChart = rebind_t<Chart, Real>;
  const RChart rchart = make_chart<RChart>();
  const auto rsys = sesi::System(rchart, std::vector<Real>{1, 1},
                                 sesi::make_pair<sesi::chord_distance>(cube, square));
  std::mt19937 rng(11);
  for (int trial = 0; trial < 10; ++trial) {
    const auto st = random_state(sys, rng);
    sesi::State<RChart> rst(n, 2);
    rst.q = st.q.template cast<Real>();
    rst.p = st.p.template cast<Real>();
    const auto X = sesi::embedding_points(rsys, rst);
    Real r = 1, c;
    if constexpr (!is_euclidean<Chart>) r = chart.radius();
    if constexpr (is_sphere<Chart>) {
      c = 2 * r * std::sin(r * std::acos(X.col(0).dot(X.col(1)) / (r * r)) / (2 * r));
    } else if constexpr (is_hyperbolic<Chart>) {
      c = 2 * r * std::sinh(r * std::acosh(-sesi::minkowski(X.col(0), X.col(1)) / (r * r)) / (2 * r));
    } else {
      c = (X.col(0) - X.col(1)).norm();
    }
    // Round-off of the points (a few (n + 3) eps R) and of the chord: 3 c^2 of that in W.
    const double v = static_cast<double>(sys.potential_energy(st));
    const double vref = static_cast<double>(c * c * c / 3);
    CHECK(std::abs(v - vref) <= 16 * (n + 3) * 2.2e-16 * static_cast<double>(c * c * (r + c)));

    typename sesi::State<Chart>::Matrix grad;
    auto w = sys.make_workspace();
    sys.potential_gradient(st, w, grad);
    // Central differences in long double, step 2^-20: truncation ~ 1e-12 |V'''|, V''' = O(1).
    const Real delta = std::ldexp(Real(1), -20);
    for (int b = 0; b < 2; ++b) {
      for (int k = 0; k < n; ++k) {
        sesi::State<RChart> sp = rst, sm = rst;
        sp.q(k, b) += delta;
        sm.q(k, b) -= delta;
        const Real fd = (rsys.potential_energy(sp) - rsys.potential_energy(sm)) / (2 * delta);
        CHECK(std::abs(static_cast<double>(grad(k, b)) - static_cast<double>(fd)) <= 1e-9);
      }
    }
  }
}
TEST_CASE_TEMPLATE_APPLY(maps_chord, std::tuple<sesi::Sphere<2>, sesi::Sphere<4>, sesi::Hyperbolic<2>,
                                                sesi::Hyperbolic<4>, sesi::Euclidean<3>>);
