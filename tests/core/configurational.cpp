// The configurational temperature (include/sesi/diagnostics.hpp) and the Laplacians behind it
// (System::laplacian_sum, special::radial_laplacian, special::chord_laplacian); issue #25.
//
//  - the Laplacian of each built-in term against a finite-difference Laplacian along geodesics
//    (the trace of the Hessian: sum_i d^2/dt^2 V(exp_x(t e_i)) over an orthonormal basis e_i),
//    on S^2, S^3, H^2, H^3, E^2, near d = 0 and near the antipode of S^n;
//  - the identity <|grad V|^2> = kT <Delta V> of the canonical position marginal exp(-V/kT) dvol,
//    by 1-D quadrature over the distance of a pair (S^2: the seed's chord well, H^2: a harmonic
//    pair): deterministic, no sampling;
//  - the sums with 600 Lennard-Jones bodies (the threaded rows and the Verlet list): the same bits
//    on one thread and two, and through the list and all pairs.
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include <doctest/doctest.h>

#include "common.hpp"

#include <sesi/diagnostics.hpp>
#include <sesi/parallel.hpp>
#include <sesi/recharting.hpp>
#include <sesi/special_functions.hpp>

namespace {

using namespace coretest;

constexpr double eps = std::numeric_limits<double>::epsilon();

// ---- geometry of the test: the ambient metric, geodesics, tangent bases --------------------------

/// The ambient metric G: Minkowski (space part minus the last coordinate) on H^n, else Euclidean.
template <class Space>
double ip(const Space& space, const typename Space::Ambient& u, const typename Space::Ambient& v) {
  if (space.curvature() < 0) {
    const int n = space.dim();
    return u.head(n).dot(v.head(n)) - u[n] * v[n];
  }
  return u.dot(v);
}

/// exp_x(t e) for a unit tangent e at x: cs(t) x + sn(t) e (a great circle on S^n, a hyperbola on
/// H^n, a line on E^n; the generalised trigonometric functions of the curvature).
template <class Space>
typename Space::Ambient geodesic(const Space& space, const typename Space::Ambient& x,
                                 const typename Space::Ambient& e, double t) {
  const double k = space.curvature();
  return (sesi::special::cs(k, t) * x + sesi::special::sn(k, t) * e).eval();
}

/// An orthonormal basis of the tangent space at x (metric G) whose first vector is along `first`.
template <class Space>
std::vector<typename Space::Ambient> tangent_basis(const Space& space, const typename Space::Ambient& x,
                                                   const typename Space::Ambient& first) {
  using Ambient = typename Space::Ambient;
  const int a = space.ambient_dim();
  std::vector<Ambient> candidates{first};
  for (int k = 0; k < a; ++k) candidates.push_back(Ambient::Unit(a, k));
  std::vector<Ambient> basis;
  for (Ambient v : candidates) {
    if (space.curvature() != 0) v -= ip(space, v, x) / ip(space, x, x) * x;
    for (const Ambient& e : basis) v -= ip(space, v, e) * e;
    const double v2 = ip(space, v, v);
    if (v2 > 0.05) basis.push_back(v / std::sqrt(v2));  // skip what is nearly in the span already
    if (static_cast<int>(basis.size()) == space.dim()) break;
  }
  REQUIRE(static_cast<int>(basis.size()) == space.dim());
  return basis;
}

template <class Space>
sesi::State<Space> state_at(const Space& space, const std::vector<typename Space::Ambient>& points) {
  sesi::State<Space> s(space.dim(), static_cast<int>(points.size()));
  typename Space::Point q(space.dim());
  for (std::size_t b = 0; b < points.size(); ++b) {
    space.chart(points[b], q);
    s.q.col(static_cast<Eigen::Index>(b)) = q;
  }
  return s;
}

// ---- the finite-difference Laplacian and its bound ----------------------------------------------

/// sum_i (g_i(h) - 2 g_i(0) + g_i(-h)) / h^2 with g_i(t) = f(exp_x(t e_i)), and the bound on its
/// distance from the Laplacian, derived term by term:
///  - truncation: (h^2/12) |g_i''''(xi)| per direction. g'''' is measured by the fourth difference
///    at step H = L/100 (its round-off 16 delta / H^4 added); a factor 2 covers its variation over
///    [-h, h] and its own O(H^2) truncation (the profile's scale is L >= 100 H);
///  - round-off: 4 delta / h^2 per direction, delta = the error of one evaluation of f: 8 ulps of
///    |f| and of |f'| times the points' size |x| + |y| + d (the points and the distance carry a few
///    ulps of it);
///  - the analytic Laplacian's own round-off: 16 ulps of sum_i |D_i| (the Hessian's eigenvalues
///    f'' and ctn f' in absolute value, the basis starting radially), and the error delta_d =
///    4 eps (|x| + |y| + d) of the distance moving f' (so ctn f' by (n - 1) |ctn f''| delta_d) and
///    f'' (by |f'''| delta_d <= 16 sum_i |D_i| delta_d / L for profiles up to LJ's d^-12).
/// h = L 1e-4 balances the two: truncation ~ 1e-9 and round-off ~ 1e-7 of |f| / L^2.
struct FiniteDifference {
  double laplacian = 0, bound = 0;
};
template <class Space, class F>
FiniteDifference fd_laplacian(const Space& space, const typename Space::Ambient& x,
                              const std::vector<typename Space::Ambient>& basis, double L, double size,
                              double ctn_f2, F&& f) {
  const double h = 1e-4 * L, H = 1e-2 * L;
  FiniteDifference out;
  double sum_abs = 0;
  for (const auto& e : basis) {
    double delta = 0;
    const auto g = [&](double t) {
      double slope = 0;
      const double v = f(geodesic(space, x, e, t), slope);
      delta = std::max(delta, 8 * eps * (std::abs(v) + slope * size));
      return v;
    };
    const double g0 = g(0);
    const double d2 = (g(h) - 2 * g0 + g(-h)) / (h * h);
    const double d4 = (g(2 * H) - 4 * g(H) + 6 * g0 - 4 * g(-H) + g(-2 * H)) / (H * H * H * H);
    out.laplacian += d2;
    sum_abs += std::abs(d2);
    out.bound += h * h / 12 * 2 * (std::abs(d4) + 16 * delta / (H * H * H * H)) + 4 * delta / (h * h);
  }
  const double delta_d = 4 * eps * size;
  const int n = space.dim();
  out.bound += 16 * eps * sum_abs + delta_d * ((n - 1) * std::abs(ctn_f2) + 16 * sum_abs / L);
  return out;
}

/// The chord of x, y in the ambient metric (the distance a chord_distance term gets).
template <class Space>
double chord_of(const Space& space, const typename Space::Ambient& x, const typename Space::Ambient& y) {
  const typename Space::Ambient u = x - y;
  return std::sqrt(std::max(0.0, ip(space, u, u)));
}

/// The largest |analytic - finite difference| / bound seen (reported, not asserted).
double worst_ratio = 0;

struct Case {
  double d;  // distance of the pair (or of the body from the centre)
  double L;  // the profile's length scale: its distance to the nearest singular point (FD step L 1e-4)
};

/// Delta_x of a pair term W(d(x, y)) at distance d: the System's sum over both bodies, halved
/// (both ends count, and a pair term's Laplacian is the same at each), against the finite
/// difference at x.
template <class Space, class Term>
void check_pair_term(const Space& space, const Term& term, const std::vector<Case>& cases, std::uint32_t seed) {
  using Ambient = typename Space::Ambient;
  std::mt19937 rng(seed);
  const double mi = 0.8, mj = 1.25;
  const sesi::System sys(space, std::vector<double>{mi, mj}, term);
  for (const Case& c : cases) {
    Ambient x(space.ambient_dim());
    space.embed(random_point(space, rng), x);
    Ambient r(space.ambient_dim());
    std::normal_distribution<double> normal;
    for (int k = 0; k < r.size(); ++k) r[k] = normal(rng);
    const auto basis = tangent_basis(space, x, r);
    const Ambient y = geodesic(space, x, basis.front(), c.d);
    const double lap = sys.laplacian_sum(state_at(space, {x, y})) / 2;
    const double k = space.curvature();
    double f2;
    if constexpr (sesi::is_chord_term<Term>) {
      f2 = term.second_derivative(space, chord_of(space, x, y), mi, mj);
    } else {
      f2 = term.second_derivative(space, c.d, mi, mj);
    }
    const double ctn_f2 = sesi::special::cs(k, c.d) / sesi::special::sn(k, c.d) * f2;
    const double size = x.norm() + y.norm() + c.d;
    const FiniteDifference fd = fd_laplacian(space, x, basis, c.L, size, ctn_f2, [&](const Ambient& p, double& slope) {
      const double arg = sesi::is_chord_term<Term> ? chord_of(space, p, y) : space.distance(p, y);
      slope = std::abs(term.derivative(space, arg, mi, mj));
      return static_cast<double>(term.value(space, arg, mi, mj));
    });
    INFO(Space::name, " n = ", space.dim(), ", d = ", c.d, ": analytic ", lap, ", finite difference ", fd.laplacian,
         ", bound ", fd.bound);
    CHECK(std::isfinite(lap));
    CHECK(std::abs(lap - fd.laplacian) <= fd.bound);
    worst_ratio = std::max(worst_ratio, std::abs(lap - fd.laplacian) / fd.bound);
  }
}

/// Delta_x of the central cotangent term about y at distance d (one body).
template <class Space>
void check_central_term(const Space& space, double k_strength, const std::vector<Case>& cases, std::uint32_t seed) {
  using Ambient = typename Space::Ambient;
  std::mt19937 rng(seed);
  const double m = 1.3;
  for (const Case& c : cases) {
    Ambient x(space.ambient_dim());
    space.embed(random_point(space, rng), x);
    Ambient r(space.ambient_dim());
    std::normal_distribution<double> normal;
    for (int k = 0; k < r.size(); ++k) r[k] = normal(rng);
    const auto basis = tangent_basis(space, x, r);
    sesi::CentralCotangent<Space> term;
    term.k = k_strength;
    term.center = geodesic(space, x, basis.front(), c.d);
    const sesi::System sys(space, std::vector<double>{m}, term);
    const double lap = sys.laplacian_sum(state_at(space, {x}));
    const double kappa = space.curvature();
    const double f2 = -k_strength * m * sesi::special::ctn_second_derivative(kappa, c.d);
    const double ctn_f2 = sesi::special::ctn(kappa, c.d) * f2;
    const double size = x.norm() + term.center.norm() + c.d;
    const FiniteDifference fd = fd_laplacian(space, x, basis, c.L, size, ctn_f2, [&](const Ambient& p, double& slope) {
      slope = std::abs(k_strength * m * sesi::special::ctn_derivative(kappa, space.distance(p, term.center)));
      return term.value(space, p, m);
    });
    INFO(Space::name, " n = ", space.dim(), ", d = ", c.d, ": analytic ", lap, ", finite difference ", fd.laplacian,
         ", bound ", fd.bound);
    CHECK(std::isfinite(lap));
    CHECK(std::abs(lap - fd.laplacian) <= fd.bound);
    worst_ratio = std::max(worst_ratio, std::abs(lap - fd.laplacian) / fd.bound);
  }
}

/// Every built-in term on one space of radius R (pi R: the antipode on S^n, else no bound).
template <class Space>
void check_all_terms(const Space& space, double R) {
  const bool sphere = space.curvature() > 0;
  const double far = sphere ? std::numbers::pi * R : 1e9;
  // A profile singular at d = 0 (and, on S^n, at the antipode): L = its distance to them.
  const auto cone = [&](double d) { return std::min({d, far - d, 1.0}); };
  std::vector<Case> general{{0.35, cone(0.35)}, {0.9, cone(0.9)}, {1.6, cone(1.6)}};
  if (sphere) general.push_back({far - 0.05, 0.05});
  // k/2 d^2 is smooth at d = 0: near it, L = 1 (or the distance to the antipode's cone).
  const std::vector<Case> near_zero{{1e-3, std::min(1.0, far - 1e-3)}, {1e-6, std::min(1.0, far - 1e-6)}};
  check_pair_term(space, sesi::HarmonicPair<double>{1.3, 0.4}, general, 1);
  check_pair_term(space, sesi::HarmonicPair<double>{1.3, 0.0}, near_zero, 2);
  if (sphere) {
    // k/2 (d - pi R)^2 = k/2 d(x, -y)^2 is smooth at the antipode (the helper's limit there).
    const std::vector<Case> near_antipode{{far - 1e-3, 1.0}, {far - 1e-6, 1.0}};
    check_pair_term(space, sesi::HarmonicPair<double>{1.3, far}, near_antipode, 3);
  }
  check_pair_term(space, sesi::CotangentGravity<double>{0.7}, general, 4);
  check_central_term(space, 0.9, general, 5);
  // Lennard-Jones inside its cutoff (sigma = 0.3: the repulsive wall, the minimum, the tail).
  const sesi::LennardJones<double> lj{1.0, 0.3, 0.75};
  check_pair_term(space, lj, {{0.3, 0.3}, {0.34, 0.34}, {0.5, 0.5}}, 6);
  // The seed's chord well inside its domain s = chord / (sqrt(3) R) < 1 (s <= 0.83 here), L: the
  // distance to d = 0 and to s = 1.
  const sesi::ChordWell<double> well(0.8);
  check_pair_term(space, well, {{0.3, 0.3}, {0.8, 0.3}, {1.2, 0.2}}, 7);
}

TEST_CASE("laplacian: each built-in term against finite differences along geodesics (S^2, S^3, H^2, H^3, E^2)") {
  check_all_terms(sesi::Sphere<2, double>(1.3), 1.3);
  check_all_terms(sesi::Sphere<3, double>(1.3), 1.3);
  check_all_terms(sesi::Hyperbolic<2, double>(0.9), 0.9);
  check_all_terms(sesi::Hyperbolic<3, double>(0.9), 0.9);
  check_all_terms(sesi::Euclidean<2, double>(), 1.0);
  MESSAGE("largest |analytic - finite difference| / bound: ", worst_ratio);
}

TEST_CASE("laplacian helpers: the limits at sn = 0 and c = 0") {
  using sesi::special::chord_laplacian;
  using sesi::special::radial_laplacian;
  // A function smooth at the point (f' = 0 there): Delta f = n f''.
  CHECK(radial_laplacian(3, 0.0, 1.0, 0.0, 2.5) == 7.5);
  CHECK(radial_laplacian(2, 0.0, -1.0, 0.0, 2.5) == 5.0);  // the antipode of S^n: cs = -1
  CHECK(chord_laplacian(1.0, 3, 0.0, 0.0, 2.5) == 7.5);
  // A cone (f' != 0 at the point) has no Laplacian there.
  CHECK(std::isnan(radial_laplacian(2, 0.0, 1.0, 0.4, 2.5)));
  CHECK(std::isnan(chord_laplacian(-1.0, 2, 0.0, 0.4, 2.5)));
  // k d^2 / 2 at d = 1e-8 on S^2 (R = 1): k + cot(d) k d = 2k - k d^2 / 3; exact to round-off.
  const double d = 1e-8;
  CHECK(std::abs(radial_laplacian(2, std::sin(d), std::cos(d), 1.3 * d, 1.3) - 2.6) <= 4 * eps * 2.6);
  // The chord form at the antipode of S^2 (c = 2R, R = 1): |grad c|^2 = 0, Delta c = -n / 2R.
  CHECK(std::abs(chord_laplacian(1.0, 2, 2.0, 1.0, 5.0) - (-1.0)) <= 4 * eps);
}

// ---- the identity <|grad V|^2> = kT <Delta V> -----------------------------------------------------

/// Composite Simpson on [a, b] with m (even) intervals.
template <class F>
double simpson(double a, double b, int m, F&& f) {
  const double h = (b - a) / m;
  double s = f(a) + f(b);
  for (int i = 1; i < m; ++i) s += (i % 2 ? 4 : 2) * f(a + i * h);
  return s * h / 3;
}

/// For a pair at distance d (body 0 fixed, body 1 along a geodesic), the canonical position
/// marginal of the pair's distance is sn(d)^(n-1) exp(-W(d)/kT) (body 0 anywhere: the measure is
/// invariant), and the configurational sums are functions of d: sum_b |grad_b V|^2 and
/// sum_b Delta_b V from sesi::configurational_sums. Returns {<|grad V|^2>, kT <Delta V>, and
/// kT <Delta_flat V>} as integrals (unnormalised), where Delta_flat drops the curvature (the
/// Euclidean Laplacian f'' + (n - 1) f' / d, a wrong answer the check must tell apart).
struct Integrals {
  double grad2, lap, flat, lap_abs;
};
template <class Space, class Term>
Integrals pair_integrals(const Space& space, const Term& term, double kT, double a, double b, int m) {
  using Ambient = typename Space::Ambient;
  const sesi::System sys(space, std::vector<double>{1.0, 1.0}, term);
  std::mt19937 rng(17);
  Ambient x(space.ambient_dim());
  space.embed(random_point(space, rng), x);
  Ambient r = Ambient::Ones(space.ambient_dim());
  const auto basis = tangent_basis(space, x, r);
  const double kappa = space.curvature();
  const int n = space.dim();
  struct Row {
    double weight, grad2, lap, flat;
  };
  const auto row = [&](double d) {
    const auto s = state_at(space, {x, geodesic(space, x, basis.front(), d)});
    const auto sums = sesi::configurational_sums(sys, s);
    const double w = std::pow(sesi::special::sn(kappa, d), n - 1) * std::exp(-sys.potential_energy(s) / kT);
    double f1, f2;
    if constexpr (sesi::is_chord_term<Term>) {
      const double c = 2 * sesi::special::sn(kappa, d / 2);
      f1 = term.derivative(space, c, 1.0, 1.0) * sesi::special::cs(kappa, d / 2);  // dW/dd = W_c c'(d)
      f2 = term.second_derivative(space, c, 1.0, 1.0) * std::pow(sesi::special::cs(kappa, d / 2), 2) -
           term.derivative(space, c, 1.0, 1.0) * kappa * c / 4;  // W_cc c'^2 + W_c c''
    } else {
      f1 = term.derivative(space, d, 1.0, 1.0);
      f2 = term.second_derivative(space, d, 1.0, 1.0);
    }
    return Row{w, sums[0], sums[1], 2 * (f2 + (n - 1) * f1 / d)};
  };
  Integrals out{};
  out.grad2 = simpson(a, b, m, [&](double d) { const Row r = row(d); return r.weight * r.grad2; });
  out.lap = kT * simpson(a, b, m, [&](double d) { const Row r = row(d); return r.weight * r.lap; });
  out.flat = kT * simpson(a, b, m, [&](double d) { const Row r = row(d); return r.weight * r.flat; });
  out.lap_abs = kT * simpson(a, b, m, [&](double d) { const Row r = row(d); return r.weight * std::abs(r.lap); });
  return out;
}

// The quadrature bound: Simpson's error is (b - a) h^4 max|F''''| / 180. The integrands are a
// bell of width sigma (S^2: sigma_d = 0.15, H^2: sigma = 1) times smooth factors, so
// max|F''''| <~ 30 max|F| / sigma^4 (a Gaussian's F''''(0) = 3 F / sigma^4, times 10 for the
// factors) and the integral is >~ sigma max|F|: relative error <= (b - a)/sigma (h/sigma)^4 / 6,
// below 2e-9 for m = 4000 intervals ((b - a)/sigma <= 14, h/sigma <= 1/250). Bound: 1e-8 of the
// integral of |Delta V| (the truncated tails weigh below e^-40).

TEST_CASE("configurational temperature: <|grad V|^2> = kT <Delta V> for a chord-well pair on S^2 (quadrature)") {
  // The seed's well, theta0 = 0.8, strength 2, R = 1.3, kT = 0.02: minimum at s = sin 0.8 = 0.72,
  // width sigma_s = 0.05 (sigma_d = 0.15). Integrated over s in [0.3, 0.999]: W/kT > 73 below,
  // and W(s = 1)/kT = 2 cos^2(0.8)/0.02 = 48.6 at the domain's edge s = 1 (where dW/ds blows up as
  // 1/sqrt(1 - s), integrably weighted by e^-48).
  const double R = 1.3, kT = 0.02;
  const sesi::Sphere<2, double> space(R);
  const auto d_of = [&](double s) { return 2 * R * std::asin(std::sqrt(3.0) * s / 2); };
  const Integrals in = pair_integrals(space, sesi::ChordWell<double>(0.8), kT, d_of(0.3), d_of(0.999), 4000);
  MESSAGE("S^2 chord well: <|grad V|^2> ", in.grad2, ", kT <Delta V> ", in.lap, ", flat ", in.flat,
          ", residual / sum|Delta V| ", std::abs(in.grad2 - in.lap) / in.lap_abs);
  CHECK(std::abs(in.grad2 - in.lap) <= 1e-8 * in.lap_abs);
  // The curvature's part of <Delta V>: 0.7 % here (a narrow well), 1e5 times the bound.
  CHECK(std::abs(in.grad2 - in.flat) > 1e-3 * in.lap_abs);
}

TEST_CASE("configurational temperature: <|grad V|^2> = kT <Delta V> for a harmonic pair on H^2 (quadrature)") {
  // W = k d^2 / 2, k = 1, kT = 1 (sigma = 1), R = 0.9: the density sinh(d/R) e^{-d^2/2} on
  // [1e-9, 12] (beyond 12 it is below e^-58; below 1e-9, where the pair's distance gradient is
  // undefined at d = 0, the integrands ~ d weigh 1e-18).
  const double kT = 1.0;
  const sesi::Hyperbolic<2, double> space(0.9);
  const Integrals in = pair_integrals(space, sesi::HarmonicPair<double>{1.0, 0.0}, kT, 1e-9, 12.0, 4000);
  MESSAGE("H^2 harmonic pair: <|grad V|^2> ", in.grad2, ", kT <Delta V> ", in.lap, ", flat ", in.flat,
          ", residual / sum|Delta V| ", std::abs(in.grad2 - in.lap) / in.lap_abs);
  CHECK(std::abs(in.grad2 - in.lap) <= 1e-8 * in.lap_abs);
  CHECK(std::abs(in.grad2 - in.flat) > 1e-2 * in.lap_abs);  // the curvature's part is seen
}

TEST_CASE("configurational temperature: NaN where a term has no Laplacian") {
  const sesi::Sphere<2, double> space(1.0);
  using Ambient = sesi::Sphere<2, double>::Ambient;
  const auto user = sesi::make_external([](const Ambient& x, double) { return x[0]; },
                                        [](const Ambient&, double) { return Ambient(1.0, 0.0, 0.0); });
  const sesi::System sys(space, std::vector<double>{1.0}, user);
  sesi::State<sesi::Sphere<2, double>> s(2, 1);
  s.set_body(0, Eigen::Vector2d(1.0, 0.3), Eigen::Vector2d(0.0, 0.0));
  CHECK(std::isnan(sesi::configurational_temperature(sys, s)));
}

TEST_CASE("configurational sums: the same through body frames and a cluster frame (H^2)") {
  // The program's runs on S^n and H^n carry re-charted bodies (State::frames) and, on H^n, a
  // cluster frame: the sums are isometry invariants and must not see them. 6 bodies >= 0.5
  // apart at radius 0.6..1.2, a harmonic pair and a central term about a centre at radius 0.2.
  using H2 = sesi::Hyperbolic<2, double>;
  const H2 space(1.0);
  sesi::CentralCotangent<H2> centre;
  centre.k = 0.5;
  H2::Point qc(2);
  qc << 0.2, 0.3;
  space.embed(qc, centre.center);
  const sesi::System sys(space, std::vector<double>{1.0, 0.7, 1.3, 0.9, 1.1, 0.8},
                         sesi::HarmonicPair<double>{1.0, 0.3}, centre);
  const sesi::State<H2> s = initial_state(sys, 31);
  const auto plain = sesi::configurational_sums(sys, s);
  // Bodies re-charted: a policy that finds all of them in danger (radius below 2); those moving
  // deeper in (4 of the 6 here) are turned or homed.
  sesi::RechartPolicy<double> policy;
  policy.min_radius = 2.0;
  sesi::State<H2> framed = s;
  const auto done = sesi::rechart(sys, framed, policy);
  REQUIRE(done.total() >= 2);
  const auto in_frames = sesi::configurational_sums(sys, framed);
  // A cluster frame at a point at radius 1.5 (cluster_radius 0.5: the frame does move there).
  sesi::State<H2> clustered = s;
  H2::Point qa(2);
  qa << 1.5, -0.4;
  H2::Ambient at(3);
  space.embed(qa, at);
  policy.cluster_radius = 0.5;
  REQUIRE(sesi::enter_cluster_frame(sys, clustered, policy, &at));
  const auto in_cluster = sesi::configurational_sums(sys, clustered);
  // Bound: the maps through the frames put each point within ~16 ulps of its size (|x| <= cosh 2
  // < 4 here) and the terms are smooth at scale >= 0.4 (the closest approach), so each term moves by
  // <= 16 eps 4 / 0.4 |f'| / |f| <~ 64 ulps times its steepness (<= 3 for d^2 and ctn at these
  // distances): 256 ulps of each sum.
  for (int k = 0; k < 2; ++k) {
    INFO("sum ", k, ": plain ", plain[k], ", frames ", in_frames[k], ", cluster ", in_cluster[k]);
    CHECK(std::abs(in_frames[k] - plain[k]) <= 256 * eps * std::abs(plain[k]));
    CHECK(std::abs(in_cluster[k] - plain[k]) <= 256 * eps * std::abs(plain[k]));
  }
  MESSAGE("frames: relative differences ", std::abs(in_frames[0] / plain[0] - 1), ", ", std::abs(in_frames[1] / plain[1] - 1),
          "; cluster: ", std::abs(in_cluster[0] / plain[0] - 1), ", ", std::abs(in_cluster[1] / plain[1] - 1));
}

// ---- many bodies: the same bits for any thread count -------------------------------------------

TEST_CASE("configurational sums: 600 Lennard-Jones bodies on S^2, the same bits on one thread and two") {
  // 600 bodies on a Fibonacci lattice of S^2 (R = 8: spacing 1.16 sigma), jittered by 0.1:
  // >= 2 parallel::min_parallel_bodies, so the rows run in chunks on two threads, and the LJ term
  // goes through a Verlet list (System::rows_from = 256); plus a long-range cotangent gravity.
  const int N = 600;
  const double R = 8.0;
  using S2 = sesi::Sphere<2, double>;
  const S2 space(R);
  std::mt19937 rng(23);
  std::uniform_real_distribution<double> jitter(-0.05, 0.05);
  sesi::State<S2> s(2, N);
  for (int b = 0; b < N; ++b) {
    const double theta = std::acos(1 - 2 * (b + 0.5) / N), phi = b * std::numbers::pi * (3 - std::sqrt(5.0));
    s.set_body(b, Eigen::Vector2d(theta + jitter(rng) / R, phi + jitter(rng) / R), Eigen::Vector2d(0.0, 0.0));
  }
  auto sys = sesi::System(space, std::vector<double>(N, 1.0), sesi::LennardJones<double>{1.0, 1.0, 2.5},
                          sesi::CotangentGravity<double>{0.01});
  const auto on = [&](int threads) {
    sesi::parallel::set_threads(threads);
#if defined(_OPENMP)
    CHECK(sesi::parallel::chunks_for(N) == (threads == 1 ? 1 : 8));  // the loops do split
#endif
    const auto sums = sesi::configurational_sums(sys, s);
    sesi::parallel::set_threads(0);
    return sums;
  };
  const auto one = on(1), two = on(2);
  CHECK(one[0] == two[0]);
  CHECK(one[1] == two[1]);
  sys.set_pair_search(decltype(sys)::PairSearch::all_pairs);
  const auto all = on(2);
  CHECK(all[0] == one[0]);
  CHECK(all[1] == one[1]);
  // Against the pairs summed here, each pair's Laplacian (the same helper) counted twice: the two
  // sums differ in order only, each within (terms) eps sum|t| of the exact sum (recursive
  // summation, Higham, Accuracy and Stability, eq. 4.4).
  double direct = 0, direct_abs = 0;
  long terms = 0;
  typename S2::Ambient xi(3), xj(3);
  typename S2::Point q(2);
  const auto lj = std::get<0>(sys.terms());
  const auto grav = std::get<1>(sys.terms());
  for (int i = 0; i < N; ++i) {
    q = s.q.col(i);
    space.embed(q, xi);
    for (int j = i + 1; j < N; ++j) {
      q = s.q.col(j);
      space.embed(q, xj);
      const auto g = space.pair_geometry(xi, xj);
      const double d = space.distance_of(g);
      const double t_lj = sesi::special::radial_laplacian(2, g.sn, g.cs(), lj.derivative(space, d, 1.0, 1.0),
                                                          lj.second_derivative(space, d, 1.0, 1.0));
      const double t_grav = sesi::special::radial_laplacian(2, g.sn, g.cs(), grav.derivative(space, g, 1.0, 1.0),
                                                            grav.second_derivative(space, g, 1.0, 1.0));
      direct += 2 * (t_lj + t_grav);
      direct_abs += 2 * (std::abs(t_lj) + std::abs(t_grav));
      terms += 4;
    }
  }
  MESSAGE("600 bodies: sum |grad V|^2 ", one[0], ", sum Delta V ", one[1], " (direct ", direct, ", difference ",
          one[1] - direct, ", bound ", 2 * static_cast<double>(terms) * eps * direct_abs, ")");
  CHECK(std::isfinite(one[1]));
  CHECK(std::abs(one[1] - direct) <= 2 * static_cast<double>(terms) * eps * direct_abs);
}

}  // namespace
