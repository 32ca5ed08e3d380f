// Topologies (issue #26): the periodic box of E^n and the compact hyperbolic surfaces of genus g
// (Sausset & Tarjus, J. Phys. A 40, 12873 (2007)), checked against their geometry: the polygon's
// formulas, the generators' side pairings, the group relation, the systole and the largest
// cutoff (against a brute-force search over many more tiles), reduce/outside/nearest_image,
// and free motion whose unwrapped path is the free geodesic of the cover over many crossings.
// Every bound is derived next to it from the scalar's epsilon and the sizes of what is rounded.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <random>
#include <stdexcept>
#include <vector>

#include <doctest/doctest.h>

#include <sesi/sesi.hpp>

#include "common.hpp"

namespace {

using Surface = sesi::HyperbolicSurface<double>;
using M3 = Surface::Matrix;
using V3 = Surface::Vector;
using LD = long double;
constexpr double eps = std::numeric_limits<double>::epsilon();
// gamma_3 = 3 eps / (1 - 3 eps) < 4 eps: the rounding of a 3-term dot product relative to the
// sum of |terms| (Higham, Accuracy and Stability of Numerical Algorithms, 3.1). With Frobenius
// norms, |fl(A B) - A B|_F <= gamma_3 |A|_F |B|_F.
constexpr double gamma3 = 4 * eps;

double lorentz(const V3& x, const V3& y) { return Surface::lorentz(x, y); }
double fro(const M3& m) { return m.norm(); }
M3 eta() { return M3(Eigen::Vector3d(1, 1, -1).asDiagonal()); }
/// Distance on the unit hyperboloid from the chord: <x - y, x - y>_L = 4 sinh^2(d/2), without
/// acosh's loss near 0 (a tangential error delta in x - y changes d by <= delta).
double dist(const V3& x, const V3& y) {
  const V3 d = x - y;
  return 2 * std::asinh(std::sqrt(std::max(0.0, lorentz(d, d))) / 2);
}

/// The standard boost o -> v (unit hyperboloid), as Hyperbolic::boost_to.
M3 boost_to(const V3& v) {
  M3 b = M3::Identity();
  b.topLeftCorner<2, 2>() += v.head<2>() * v.head<2>().transpose() / (1 + v[2]);
  b.topRightCorner<2, 1>() = v.head<2>();
  b.bottomLeftCorner<1, 2>() = v.head<2>().transpose();
  b(2, 2) = v[2];
  return b;
}
/// The point at distance r from o in direction angle th.
V3 polar(double r, double th) { return V3(std::sinh(r) * std::cos(th), std::sinh(r) * std::sin(th), std::cosh(r)); }

/// A bound on the rounding of the product g_{w_1} ... g_{w_L} computed left to right: the error
/// made at step m, <= gamma_3 |P_{m-1}|_F |g_{w_m}|_F, is carried by the rest of the product R_m
/// = g_{w_{m+1}} ... g_{w_L} (so multiplied by at most |R_m|_F). Norms from the computed factors
/// (their own rounding changes the bound by a relative ~eps only).
double product_bound(const Surface& s, const Surface::Word& w) {
  const auto len = w.size();
  std::vector<M3> suffix(len + 1, M3::Identity());  // suffix[m] = g_{w_{m+1}} ... g_{w_L} (0-based: w[m..])
  for (std::size_t m = len; m-- > 0;) suffix[m] = s.generator(w[m]) * suffix[m + 1];
  double bound = 0;
  M3 p = M3::Identity();
  for (std::size_t m = 0; m < len; ++m) {
    bound += gamma3 * fro(p) * fro(s.generator(w[m])) * fro(suffix[m + 1]);
    p = p * s.generator(w[m]);
  }
  return bound;
}

}  // namespace

TEST_CASE("topology: the regular 4g-gon of a genus-g surface (inradius, circumradius, angle, area)") {
  for (int g = 2; g <= 8; ++g) {
    CAPTURE(g);
    const Surface s(g, 1.0);
    const int n = s.sides();
    const double cot = 1 / std::tan(std::numbers::pi / n);
    // Vertices have time coordinate cot^2 and normals entries <= cot, each entry built from
    // cot(pi/4g) with relative rounding <= 10 eps (tan, a division, squares, a sqrt). An inner
    // product of such vectors (or of the tangents at a vertex, entries ~cot^4 of O(cot^2) norm)
    // is off by <= (3 gamma_3 + 20 eps) cot^4 = 32 eps cot^4 relative to the result's scale;
    // acosh/acos turn it into a length or angle with derivative 1/sinh d (lengths >= 1.5 here:
    // < 0.5) or 1/sin(alpha) (alpha >= pi/16: < 5.2). At most 4 such inner products per check.
    const double tol = 4 * 5.2 * 32 * eps * std::pow(cot, 4);
    CHECK(n == 4 * g);
    CHECK(s.images().size() == std::size_t(1 + n * (n - 2)));  // D, 4g edge neighbours, 4g (4g - 3) at vertices only
    for (int k = 0; k < n; ++k) {
      CAPTURE(k);
      const V3& a = s.vertex((k + n - 1) % n);
      const V3& b = s.vertex(k);
      const V3& c = s.vertex((k + 1) % n);
      // vertices at the circumradius, on their sides' lines
      CHECK(std::abs(std::acosh(a[2]) - s.circumradius()) <= tol);
      CHECK(std::abs(lorentz(a, s.normal(k))) <= tol);
      CHECK(std::abs(lorentz(b, s.normal(k))) <= tol);
      CHECK(std::abs(lorentz(s.normal(k), s.normal(k)) - 1) <= tol);
      // the side's midpoint is at the inradius (cosh = cot) and the side is twice it long
      V3 mid = a + b;
      mid /= std::sqrt(-lorentz(mid, mid));
      CHECK(std::abs(std::acosh(mid[2]) - s.inradius()) <= tol);
      CHECK(std::abs(std::acosh(cot) - s.inradius()) <= tol);
      CHECK(std::abs(dist(a, b) - s.side_length()) <= tol);
      // interior angle pi/(2g) at vertex b, between the tangents towards a and c
      const V3 ta = a + lorentz(a, b) * b, tc = c + lorentz(c, b) * b;
      const double angle = std::acos(lorentz(ta, tc) / std::sqrt(lorentz(ta, ta) * lorentz(tc, tc)));
      CHECK(std::abs(angle - std::numbers::pi / (2 * g)) <= tol);
    }
    // Gauss-Bonnet: area = (n - 2) pi - n alpha = 4 pi (g - 1).
    CHECK(std::abs(s.area() - ((n - 2) * std::numbers::pi - n * std::numbers::pi / (2 * g))) <= 16 * eps * s.area());
  }
}

TEST_CASE("topology: generators pair side k+2g with side k, and generator(k+2g) = generator(k)^-1") {
  for (int g = 2; g <= 8; ++g) {
    CAPTURE(g);
    const Surface s(g, 1.0);
    const int n = s.sides(), half = 2 * g;
    for (int k = 0; k < n; ++k) {
      CAPTURE(k);
      const M3& gk = s.generator(k);
      const M3& gi = s.generator((k + half) % n);
      CHECK(s.inverse(k) == (k + half) % n);
      // A product of two matrices with entries built from cot(pi/4g) (relative rounding <= 10 eps
      // each: cosh 2 rho = 2 cot^2 - 1 and sinh 2 rho = 2 cot sqrt(cot^2 - 1) agree with
      // cosh^2 - sinh^2 = 1 only to that): (gamma_3 + 20 eps) |g|_F^2 = 24 eps |g|_F^2.
      const double tol = 24 * eps * fro(gk) * fro(gk);
      CHECK((gi * gk - M3::Identity()).cwiseAbs().maxCoeff() <= tol);
      CHECK((gk.transpose() * eta() * gk - eta()).cwiseAbs().maxCoeff() <= 2 * tol);  // two products
      // side k+2g (its endpoints v_{k+2g-1}, v_{k+2g}) onto side k (v_k, v_{k-1}); D's centre onto
      // its mirror image in side k, o - 2 <o, n_k> n_k. One product g v, both built with relative
      // rounding <= 10 eps: (gamma_3 + 20 eps) |g|_F |v|, and the target's own 10 eps |v|.
      const double tv = 24 * eps * fro(gk) * s.vertex(0).norm() + 10 * eps * s.vertex(0).norm();
      CHECK((gk * s.vertex((k + half + n - 1) % n) - s.vertex(k)).cwiseAbs().maxCoeff() <= tv);
      CHECK((gk * s.vertex((k + half) % n) - s.vertex((k + n - 1) % n)).cwiseAbs().maxCoeff() <= tv);
      // the midpoint of side k+2g onto the midpoint of side k (both at the inradius)
      const double th = 2 * std::numbers::pi * k / n;
      CHECK((gk * polar(s.inradius(), th + std::numbers::pi) - polar(s.inradius(), th)).cwiseAbs().maxCoeff() <= tv);
      const V3 o(0, 0, 1);
      const V3 mirror = o - 2 * lorentz(o, s.normal(k)) * s.normal(k);
      CHECK((gk * o - mirror).cwiseAbs().maxCoeff() <= tv);
      // the inverse's side: generator(k+2g) takes D across side k+2g
      CHECK(s.outside(gi * V3(0, 0, 1)) > 0);
      CHECK(s.outside(gk * polar(0.5, 2 * std::numbers::pi * k / n)) > 0);
    }
  }
}

TEST_CASE("topology: the walk around a vertex closes (the group relation), and images() are its tiles") {
  for (int g = 2; g <= 8; ++g) {
    CAPTURE(g);
    const Surface s(g, 1.0);
    const int n = s.sides();
    REQUIRE(s.relation().size() == std::size_t(n));
    const M3 rel = s.element(s.relation());
    const double bound = product_bound(s, s.relation());
    MESSAGE("g = ", g, ": relation residual ", (rel - M3::Identity()).norm(), " bound ", bound);
    CHECK((rel - M3::Identity()).norm() <= bound);
    // The relation is cyclically reduced (no letter next to its inverse), uses every letter once.
    std::vector<int> seen(std::size_t(n), 0);
    for (int m = 0; m < n; ++m) {
      ++seen[std::size_t(s.relation()[std::size_t(m)])];
      CHECK(s.relation()[std::size_t((m + 1) % n)] != s.inverse(s.relation()[std::size_t(m)]));
    }
    CHECK(std::count(seen.begin(), seen.end(), 1) == n);
    // Every image is its word's product; its tile shares a vertex with D; tiles are distinct.
    CHECK(s.images()[0] == M3::Identity());
    double worst = 0, closest = std::numeric_limits<double>::infinity();
    for (std::size_t k = 0; k < s.images().size(); ++k) {
      const M3& e = s.images()[k];
      // The closed form B Rot B^{-1} Rot': three products of matrices of norm <= |B|_F (rotations:
      // sqrt 3) and the rotations' own rounding (angle and cos/sin: a few eps): 64 eps |B|_F^2.
      const double closed = 64 * eps * std::pow(fro(boost_to(s.vertex(0))), 2);
      const double tol = product_bound(s, s.image_word(int(k))) + closed;
      worst = std::max(worst, (s.element(s.image_word(int(k))) - e).norm() / tol);
      // (e v_i is off by <= 24 eps |e|_F |v| ~ 1e-9 |v| at g = 8; other vertices are >= the side
      // length ~ |v| apart: 1e-6 |v| tells them apart)
      bool shares = false;
      for (int i = 0; i < n && !shares; ++i)
        for (int j = 0; j < n && !shares; ++j)
          shares = (e * s.vertex(i) - s.vertex(j)).norm() < 1e-6 * s.vertex(j).norm();
      CHECK(shares);
      for (std::size_t l = 0; l < k; ++l) closest = std::min(closest, -lorentz(e.col(2), s.images()[l].col(2)));
    }
    CHECK(worst <= 1);
    // Centres >= 2 inradius apart (cosh 2 rho = 2 cot^2 - 1; equal for edge neighbours): their
    // inner product, of entries <= X (the largest time coordinate of a centre), rounds by <=
    // gamma_3 3 X^2, and the centres carry the closed form's 64 eps |B|_F^2 ~ 64 eps X each.
    double x_max = 0;
    for (const auto& e : s.images()) x_max = std::max(x_max, e(2, 2));
    const double two_rho = 2 * std::pow(1 / std::tan(std::numbers::pi / n), 2) - 1;  // cosh(2 inradius)
    CHECK(closest >= two_rho - (3 * gamma3 + 2 * 64 * eps) * x_max * x_max);
  }
}

TEST_CASE("topology: systole and the largest cutoff") {
  // The Bolza surface: the systole is 2 acosh(1 + sqrt 2) (the generators' translation length).
  // systole() is the least acosh((tr - 1) / 2) over the traces of images() and their products;
  // a trace of A B is a sum of 9 products, off by <= 10 eps |A|_F |B|_F (and the entries' own
  // relative ~10 eps: 20 eps in all), through d acosh((tr - 1)/2) / d tr = 1 / (2 sinh l).
  const Surface bolza(2, 1.0);
  const double l = 2 * std::acosh(1 + std::sqrt(2.0));
  double biggest = 0;
  for (const auto& m : bolza.images()) biggest = std::max(biggest, fro(m));
  CHECK(std::abs(bolza.systole() - l) <= 20 * eps * biggest * biggest / (2 * std::sinh(l)) + 4 * eps * l);
  CHECK(bolza.max_cutoff() == doctest::Approx(bolza.systole() / 2).epsilon(1e-15));
  for (int g = 2; g <= 8; ++g) {
    CAPTURE(g);
    const Surface s(g, 2.5);
    MESSAGE("g = ", g, ": systole/R ", s.systole() / 2.5, " delta/R ", s.star_margin() / 2.5, " max_cutoff/R ",
            s.max_cutoff() / 2.5);
    // No generator is shorter than the systole; it is exact (below 2 delta, see systole()).
    CHECK(s.systole() <= 2 * s.inradius() * (1 + 1e-14));
    CHECK(s.systole() < 2 * s.star_margin());
    CHECK(s.max_cutoff() <= s.systole() / 2);
    CHECK(s.max_cutoff() <= s.star_margin());
    CHECK(s.max_cutoff() > 0.5 * s.inradius());
    // Lengths scale with R.
    const Surface unit(g, 1.0);
    CHECK(s.max_cutoff() == doctest::Approx(2.5 * unit.max_cutoff()).epsilon(1e-14));
    CHECK(s.area() == doctest::Approx(4 * std::numbers::pi * (g - 1) * 6.25).epsilon(1e-15));
  }
  CHECK_THROWS_AS(Surface(1, 1.0), std::invalid_argument);
  CHECK_THROWS_AS(Surface(Surface::max_genus + 1, 1.0), std::invalid_argument);
  CHECK_THROWS_AS(Surface(2, 0.0), std::invalid_argument);
  CHECK_THROWS_AS(Surface(2, std::numeric_limits<double>::infinity()), std::invalid_argument);
}

namespace {
/// Every element g_a g_b g_c (g_a in images(), g_b, g_c in images()): a much larger set of
/// tiles than images() (all within three stars of D) to search the true nearest image in.
std::vector<M3> many_tiles(const Surface& s) {
  std::vector<M3> out;
  for (const auto& a : s.images())
    for (const auto& b : s.images()) out.push_back(a * b);
  return out;
}
/// A point of D: a uniform direction and radius up to the circumradius, reduced into D.
V3 random_in_domain(const Surface& s, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(0, 1);
  V3 y = polar(u(rng) * s.circumradius() / s.radius(), 2 * std::numbers::pi * u(rng)) * s.radius();
  Surface::Word applied;
  s.reduce(y, applied);
  return y;
}
/// y moved by the geodesic of length d in direction th (in y's boost frame).
V3 moved(const V3& y, double d, double th, double radius) {
  return boost_to(y / radius) * polar(d / radius, th) * radius;
}
}  // namespace

TEST_CASE("topology: below max_cutoff the minimum image is unique and nearest_image finds it") {
  std::mt19937_64 rng(26);
  std::uniform_real_distribution<double> u(0, 1);
  for (int g : {2, 3}) {
    CAPTURE(g);
    const double radius = 1.7;
    const Surface s(g, radius);
    const auto tiles = many_tiles(s);
    const double rc = s.max_cutoff();
    int near = 0;
    for (int trial = 0; trial < (g == 2 ? 300 : 60); ++trial) {
      // Pairs across sides at distances around the cutoff: y = x moved by up to 1.3 r_c, reduced.
      const V3 x = random_in_domain(s, rng);
      V3 y = moved(x, 1.3 * rc * u(rng), 2 * std::numbers::pi * u(rng), radius);
      Surface::Word applied;
      s.reduce(y, applied);
      // brute force: every image in `tiles` within r_c of x, and the least distance
      // (tiles holds each element many times: count distinct image points, 1e-9 R apart or more;
      // distinct images of y are >= the systole apart)
      double best = std::numeric_limits<double>::infinity();
      std::vector<V3> within;
      for (const auto& t : tiles) {
        const V3 ty = t * y;
        const double d = radius * dist(x / radius, ty / radius);
        best = std::min(best, d);
        const auto same = [&](const V3& w) { return radius * dist(w / radius, ty / radius) < 1e-9 * radius; };
        if (d < rc && std::none_of(within.begin(), within.end(), same)) within.push_back(ty);
      }
      V3 z = y;
      const int k = s.nearest_image(x, z);
      const double dk = radius * dist(x / radius, z / radius);
      // dist() from the chord: the points (entries <= cosh(2 circumradius) ~ 70) are rounded by
      // ~ 10 eps * 70 per product: 1e-6 R is far above that and far below the systole.
      CHECK(within.size() <= 1);
      if (best < rc) {
        ++near;
        CHECK(std::abs(dk - best) <= 1e-6 * radius);
        V3 again = y;
        s.apply(k, again);
        CHECK((again - z).norm() == 0);
      }
    }
    CHECK(near > 10);  // the test saw pairs within the cutoff
  }
}

TEST_CASE("topology: outside, reduce, images_near on the surface") {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(0, 1);
  for (int g : {2, 5}) {
    CAPTURE(g);
    const double radius = 2.0;
    const Surface s(g, radius);
    const int n = s.sides();
    CHECK(s.outside(V3(0, 0, radius)) == 0);
    for (int k = 0; k < n; ++k) {
      CAPTURE(k);
      // The vertices and the side midpoints are on D's boundary: inside (slack()).
      CHECK(s.outside(s.vertex(k) * radius) == 0);
      const double th = 2 * std::numbers::pi * k / n;
      const V3 mid = polar(s.inradius() / radius, th) * radius;
      CHECK(s.outside(mid) == 0);
      // Beyond side k's midpoint, on its perpendicular, the distance is the overshoot h; beyond a
      // vertex on the ray from o, the distance to that vertex. The test point (time coordinate X
      // <= cosh(circumradius + 0.3)) and the vertex carry relative rounding <= 10 eps per entry,
      // so their difference is off by <= 20 eps X sqrt(3), a tangential error that changes the
      // chord distance by at most as much; the side's normal (entries <= cot) turns the same into
      // <= 20 eps X cot sqrt(3) in sinh of the distance: 40 eps X cot bounds both, times R.
      const double xmax = std::cosh(s.circumradius() / radius + 0.3), cot = 1 / std::tan(std::numbers::pi / n);
      const double tol = 40 * eps * xmax * cot * radius;
      // (h above slack(): at g = 5 a point 1e-9 past a vertex is within it, so inside)
      for (double h : {1e-6, 0.01, 0.3}) {
        CHECK(std::abs(s.outside(polar(s.inradius() / radius + h, th) * radius) - radius * h) <= tol);
        CHECK(std::abs(s.outside(polar(s.circumradius() / radius + h, th + std::numbers::pi / n) * radius) -
                       radius * h) <= tol);
      }
      // A point on a side is not moved by reduce (no flip-flop); one just outside moves once.
      V3 y = mid;
      Surface::Word applied;
      s.reduce(y, applied);
      CHECK(applied.empty());
      y = polar(s.inradius() / radius + 1e-7, th) * radius;
      s.reduce(y, applied);
      CHECK(applied == Surface::Word{std::int16_t(s.inverse(k))});
      CHECK(s.outside(y) == 0);
    }
    // Far points: reduce brings them into D; the letters' product (applied last on the left)
    // maps the input to the output.
    for (int trial = 0; trial < 100; ++trial) {
      const V3 y0 = polar(6 * u(rng), 2 * std::numbers::pi * u(rng)) * radius;
      V3 y = y0;
      Surface::Word applied;
      s.reduce(y, applied);
      CHECK(s.outside(y) == 0);
      // The letters, applied one by one in long double, take y0 to y: each step g y_m of reduce
      // rounds by <= (gamma_3 + 10 eps) |g|_F |y_m| (the generator's own entries: 10 eps), an
      // error that the later isometries carry without growing it as a distance (tangentially;
      // the part normal to the hyperboloid does not count in the chord).
      Eigen::Matrix<LD, 3, 1> yl = y0.cast<LD>();
      double bound = 0;
      for (auto a : applied) {
        bound += 14 * eps * fro(s.generator(a)) * double(yl.norm());
        yl = s.generator(a).cast<LD>() * yl;
      }
      CHECK(radius * dist(y / radius, yl.cast<double>() / radius) <= bound + 4 * eps * y.norm());
      // and that point of the orbit is the one nearest to o (D is o's Dirichlet domain)
      for (const auto& e : s.images()) CHECK(-lorentz(e * y, V3(0, 0, 1)) >= -lorentz(y, V3(0, 0, 1)) * (1 - 1e-12));
    }
    // images_near finds exactly the images within reach of D (against all of images()).
    for (int trial = 0; trial < 50; ++trial) {
      const V3 y = random_in_domain(s, rng);
      const double reach = s.max_cutoff() * u(rng);
      std::vector<int> got;
      s.images_near(y, reach, got);
      std::vector<int> want;
      for (int k = 0; k < int(s.images().size()); ++k) {
        V3 z = y;
        s.apply(k, z);
        if (s.outside(z) <= reach) want.push_back(k);
      }
      CHECK(got == want);
      CHECK(!got.empty());
      CHECK(got.front() == 0);
    }
  }
}

TEST_CASE("topology: words (append_inverse keeps W gamma^-1 freely reduced)") {
  // Exact, in the free group on the letters: W' = reduce(W inv(a_1) ... inv(a_m)), so W' followed
  // by a_m ... a_1 (the word of gamma = g_{a_m} ... g_{a_1}) freely reduces back to W.
  const Surface s(3, 1.0);
  auto freely_reduce = [&](const Surface::Word& w) {
    Surface::Word out;
    for (auto l : w) {
      if (!out.empty() && out.back() == s.inverse(l)) {
        out.pop_back();
      } else {
        out.push_back(l);
      }
    }
    return out;
  };
  std::mt19937_64 rng(3);
  std::uniform_int_distribution<int> letter(0, s.sides() - 1);
  int cancelled = 0;
  for (int trial = 0; trial < 500; ++trial) {
    Surface::Word w, applied;
    for (int i = 0; i < 4; ++i) s.append_inverse(w, Surface::Word{std::int16_t(letter(rng))});
    for (int i = 0; i < 3; ++i) applied.push_back(std::int16_t(letter(rng)));
    // half the time the first applied letter undoes W's last one (a body going back)
    if (trial % 2 == 0 && !w.empty()) applied.front() = w.back();
    const Surface::Word before = w;
    s.append_inverse(w, applied);
    for (std::size_t i = 1; i < w.size(); ++i) CHECK(w[i] != s.inverse(w[i - 1]));
    if (w.size() < before.size() + applied.size()) ++cancelled;
    Surface::Word back = w;
    for (auto it = applied.rbegin(); it != applied.rend(); ++it) back.push_back(*it);
    CHECK(freely_reduce(back) == before);
  }
  CHECK(cancelled >= 200);
  // and geometrically on a short case: W' gamma = W
  Surface::Word w{1, 7}, applied{5, 9};
  const M3 before = s.element(w);
  s.append_inverse(w, applied);
  CHECK(w == Surface::Word{1, 7, 11, 3});  // (5 + 6) mod 12, (9 + 6) mod 12
  const M3 gamma = s.generator(9) * s.generator(5);
  // four generator products (|g|_F ~ 16 at g = 3) with relative rounding ~24 eps each step
  CHECK((s.element(w) * gamma - before).norm() <= 4 * 24 * eps * std::pow(fro(s.generator(0)), 6));
}

TEST_CASE("topology: frames stay Lorentz over 10^4 wraps (orthonormalise)") {
  const Surface s(2, 1.0);
  M3 f = boost_to(polar(2.0, 0.3)) * M3::Identity();
  M3 plain = f;
  std::mt19937_64 rng(1);
  std::uniform_int_distribution<int> letter(0, s.sides() - 1);
  for (int i = 0; i < 10000; ++i) {
    // a letter and its inverse: the frame comes back to a bounded size (|F|_F ~ cosh 2-ish)
    const int a = letter(rng);
    f = s.generator(a) * f;
    Surface::orthonormalise(f);
    f = s.generator(s.inverse(a)) * f;
    Surface::orthonormalise(f);
    plain = s.generator(s.inverse(a)) * (s.generator(a) * plain).eval();
  }
  // The rebuilt F = B(y) Q has entries with relative rounding of a few eps (B from y's spatial
  // part, y_t = sqrt(1 + |y_s|^2)): its defect is that of evaluating F^T eta F, 2 gamma_3 |F|_F^2,
  // plus 2 * 8 eps |F|_F^2 for the entries' own rounding: 24 eps |F|_F^2.
  const double defect = (f.transpose() * eta() * f - eta()).cwiseAbs().maxCoeff();
  const double plain_defect = (plain.transpose() * eta() * plain - eta()).cwiseAbs().maxCoeff();
  MESSAGE("defect after 2 x 10^4 wraps: rebuilt ", defect, ", plain products ", plain_defect);
  CHECK(defect <= 24 * eps * fro(f) * fro(f));
  CHECK((f.col(2) - plain.col(2)).norm() <= 1e-6 * fro(plain));  // same point (plain drifts by ~1e-9 relative)
}

TEST_CASE("topology: the periodic box") {
  using Box = sesi::PeriodicBox<double, 3>;
  const Box box(Eigen::Vector3d(2.0, 3.0, 5.0));
  CHECK(box.max_cutoff() == 1.0);
  CHECK(box.outside(Eigen::Vector3d(0, 0, 0)) == 0);
  CHECK(box.outside(Eigen::Vector3d(2.0, 1, 1)) == 0.0);  // the upper face belongs to the next image
  CHECK(box.outside(Eigen::Vector3d(2.5, 1, -0.75)) == 0.75);
  // reduce: x - L floor(x / L), counts += floor; unwrapped x + L n is the input
  Eigen::Vector3d x(-0.5, 7.25, 4.0);
  Eigen::Matrix<std::int64_t, 3, 1> counts = Eigen::Matrix<std::int64_t, 3, 1>::Zero();
  CHECK(box.reduce(x, counts));
  CHECK(x == Eigen::Vector3d(1.5, 1.25, 4.0));
  CHECK(counts == Eigen::Matrix<std::int64_t, 3, 1>(-1, 2, 0));
  // a tiny negative coordinate rounds to L: it is mapped to 0 with the count unchanged
  x = Eigen::Vector3d(-1e-17, 0.5, 0.5);
  counts.setZero();
  box.reduce(x, counts);
  CHECK(x[0] == 0.0);
  CHECK(counts[0] == 0);
  CHECK(box.outside(x) == 0);
  // nearest image: the image of y nearest x
  Eigen::Vector3d y(1.9, 0.1, 4.9);
  box.nearest_image(Eigen::Vector3d(0.1, 2.9, 0.2), y);
  CHECK((y - Eigen::Vector3d(-0.1, 3.1, -0.1)).norm() <= 8 * eps);
  CHECK_THROWS_AS(Box(Eigen::Vector3d(1, 0, 1)), std::invalid_argument);
  CHECK_THROWS_AS(Box(Eigen::Vector3d(1, -1, 1)), std::invalid_argument);
  CHECK_THROWS_AS(Box(Eigen::Vector3d(1, std::numeric_limits<double>::quiet_NaN(), 1)), std::invalid_argument);
  CHECK_THROWS_AS(Box(Eigen::Vector3d(1, std::numeric_limits<double>::infinity(), 1)), std::invalid_argument);
  const sesi::PeriodicBox<double, Eigen::Dynamic> dyn(Eigen::VectorXd::Constant(5, 4.0));
  CHECK(dyn.dim() == 5);
  CHECK(dyn.identity_images(3).rows() == 5);
  CHECK(dyn.identity_images(3).cols() == 3);
}

TEST_CASE("topology: wrap moves every outside body once one is beyond the margin (box)") {
  using Chart = sesi::Quotient<sesi::Euclidean<2>, sesi::PeriodicBox<double, 2>>;
  const Chart chart(sesi::Euclidean<2>(), sesi::PeriodicBox<double, 2>(Eigen::Vector2d(4.0, 4.0)));
  const sesi::System<Chart> sys(chart, std::vector<double>{1.0, 1.0});
  sesi::State<Chart> s(2, 2);
  s.set_body(0, {4.05, 1.0}, {0.0, 0.0});
  s.set_body(1, {1.0, -0.01}, {0.0, 0.0});
  auto images = chart.topology().identity_images(2);
  CHECK(sesi::wrap(sys, s, images, 0.1) == 0);  // both outside by less than the margin
  CHECK(s.q(0, 0) == 4.05);
  s.q(0, 0) = 4.2;
  CHECK(sesi::wrap(sys, s, images, 0.1) == 2);  // one beyond: both are reduced
  // one subtraction of numbers <= 4.2 from inputs rounded to eps/2 relative: <= 4.2 eps
  CHECK(std::abs(s.q(0, 0) - 0.2) <= 4.2 * eps);
  CHECK(images(0, 0) == 1);
  CHECK(images(1, 1) == -1);
  CHECK(std::abs(s.q(1, 1) - 3.99) <= 4 * eps);
  static_assert(sesi::HasTopology<Chart> && !sesi::HasTopology<sesi::Euclidean<2>>);
  static_assert(!sesi::ClusterChart<sesi::Quotient<sesi::Hyperbolic<2>, Surface>>);
  static_assert(sesi::ClusterChart<sesi::Hyperbolic<2>>);
}

TEST_CASE("topology: wrap on a surface (margin, frames, words) against a direct evaluation") {
  using Chart = sesi::Quotient<sesi::Hyperbolic<2>, Surface>;
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(0, 1);
  for (int g : {2, 4}) {
    CAPTURE(g);
    const double radius = 1.5;
    const Chart chart(sesi::Hyperbolic<2>(radius), Surface(g, radius));
    const Surface& surf = chart.topology();
    const int bodies = 40;
    const sesi::System<Chart> sys(chart, std::vector<double>(bodies, 1.0));
    int far_seen = 0, quiet_seen = 0;
    for (int trial = 0; trial < 40; ++trial) {
      sesi::State<Chart> s(2, bodies);
      const bool framed = trial % 4 != 0;
      if (framed) s.enable_frames(3);
      // bodies scattered around D: chart origins up to 0.8 inradius from o, bodies up to 1.1
      // inradius (or 0.5: then mostly inside) from their chart's origin
      const double spread = surf.inradius() / radius;
      for (int b = 0; b < bodies; ++b) {
        s.set_body(b, {0.1 + spread * u(rng) * (trial % 2 ? 1.1 : 0.5), 2 * std::numbers::pi * u(rng)}, {0.0, 0.0});
        if (framed) {
          const double th = 2 * std::numbers::pi * u(rng);
          M3 rot = M3::Identity();
          rot.topLeftCorner<2, 2>() << std::cos(th), -std::sin(th), std::sin(th), std::cos(th);
          s.frames[std::size_t(b)] = boost_to(polar(0.8 * spread * u(rng), 2 * std::numbers::pi * u(rng))) * rot;
        }
      }
      auto world = [&](const sesi::State<Chart>& st, int b) {
        Eigen::Vector2d q = st.q.col(b);
        typename Chart::Ambient x;
        chart.embed(q, x);
        return V3(st.framed() ? V3(st.frames[std::size_t(b)] * x) : V3(x));
      };
      const double margin = (trial % 3) * 0.2 * surf.max_cutoff();
      bool far = false;
      for (int b = 0; b < bodies; ++b) far = far || surf.outside(world(s, b)) > margin;
      const sesi::State<Chart> before = s;
      auto images = surf.identity_images(bodies);
      const int moved = sesi::wrap(sys, s, images, margin);
      if (!far) {
        ++quiet_seen;
        CHECK(moved == 0);
        CHECK(s.q == before.q);
        CHECK(s.framed() == before.framed());
        continue;
      }
      ++far_seen;
      int changed = 0;
      for (int b = 0; b < bodies; ++b) {
        const V3 x0 = world(before, b), x1 = world(s, b);
        CHECK(surf.outside(x1) == 0);
        if (!images[std::size_t(b)].empty()) ++changed;
        // W x1 = x0, the letters applied to x1 one by one: each product rounds by <= 14 eps |g|_F
        // |point| (see reduce's test), the same for reduce's own steps inside wrap, and the
        // frame's product and rebuild move x1 by <= (4 eps |gamma|_F |F|_F + 16 eps |F|_F^2)
        // |embed(q)|, |gamma|_F <= |F_after|_F |F_before|_F (gamma = F_after F_before^-1).
        V3 w = x1;
        const auto& word = images[std::size_t(b)];
        double bound = 0;
        for (auto it = word.rbegin(); it != word.rend(); ++it) {
          bound += 2 * 14 * eps * fro(surf.generator(*it)) * w.norm();
          w = surf.generator(*it) * w;
        }
        if (s.framed()) {
          const double f1 = fro(s.frames[std::size_t(b)]);
          const double f0 = before.framed() ? fro(before.frames[std::size_t(b)]) : std::sqrt(3.0);
          Eigen::Vector2d q = s.q.col(b);
          typename Chart::Ambient e;
          chart.embed(q, e);
          bound += (4 * eps * f1 * f0 * f0 + 16 * eps * f1 * f1) * e.norm();
        }
        CHECK(radius * dist(w / radius, x0 / radius) <= bound + 4 * eps * x0.norm());
        CHECK(s.q.col(b) == before.q.col(b));  // q and p untouched
        CHECK(s.p.col(b) == before.p.col(b));
      }
      CHECK(changed == moved);
      CHECK(s.framed());
    }
    CHECK(far_seen > 5);
    CHECK(quiet_seen > 5);
  }
}

TEST_CASE("topology: free motion in a box, unwrapped, is the straight line over many crossings") {
  using Chart = sesi::Quotient<sesi::Euclidean<3>, sesi::PeriodicBox<double, 3>>;
  const Eigen::Vector3d edges(1.0, 1.5, 2.0);
  const Chart chart{sesi::Euclidean<3>(), sesi::PeriodicBox<double, 3>(edges)};
  const sesi::System<Chart> sys(chart, std::vector<double>{1.0, 2.0});
  sesi::State<Chart> s(3, 2);
  s.set_body(0, {0.5, 0.2, 1.9}, {3.1, -2.3, 0.7});
  s.set_body(1, {0.9, 1.4, 0.1}, {-1.7, 5.3, -4.1});
  const sesi::State<Chart> s0 = s;
  auto images = chart.topology().identity_images(2);
  sesi::Strang<Chart> stepper;
  const double dt = 0.01;
  const int steps = 2000;
  int wraps = 0;
  for (int k = 0; k < steps; ++k) {
    stepper.do_step(sys, s, k * dt, dt);
    wraps += sesi::wrap(sys, s, images, 0.05);
  }
  // Each step adds (stages + 1 =) 2 increments h p / m (relative rounding <= 2 eps) to
  // coordinates below L + |h p/m| < 2.1 (each addition rounds by <= eps/2 * 2.1), and each wrap
  // subtracts L n (rounding <= eps/2 |q| twice): per step <= 2 * (eps/2 * 2.1 + 2 eps * 0.03) +
  // eps * 2.1, so 4 eps * 2.1 * steps bounds it, with the unwrapped x + L n exact in long double.
  const double bound = 4 * eps * 2.1 * steps;
  double err = 0;
  for (int b = 0; b < 2; ++b) {
    for (int i = 0; i < 3; ++i) {
      const LD unwrapped = LD(s.q(i, b)) + LD(edges[i]) * LD(images(i, b));
      const LD exact = LD(s0.q(i, b)) + LD(s0.p(i, b)) / LD(sys.mass(b)) * LD(dt) * LD(steps);
      err = std::max(err, double(std::abs(unwrapped - exact)));
      CHECK(s.q(i, b) >= 0);
      CHECK(s.q(i, b) < edges[i]);
    }
  }
  MESSAGE("box: ", wraps, " body wraps, unwrapped error ", err, " bound ", bound);
  CHECK(wraps > 20);
  CHECK(std::abs(images(1, 1)) > 30);  // 5.3 / 2 * 20 / 1.5 = 35 crossings of axis 1 by body 1
  CHECK(err <= bound);
}

TEST_CASE("topology: free motion on the Bolza surface, unwrapped, is the geodesic of H^2") {
  // A body moving radially in its chart (p_2 = 0) follows the exact flow of the Strang step (K_2
  // = 0 then, and K_1's flow is q_1 += h p_1 / (m R^2)): the only errors are rounding. Its chart is
  // re-based every time q_1 passes 2 (F <- F T, T the boost along the ray by q_1 - 1/2, q_1 <- 1/2:
  // the same world point and velocity), so the chart never grows, while wrap() brings it back
  // into D on every crossing. The unwrapped point W_b x_b must stay on the geodesic from x0 in
  // the direction of v0: at distance |v| t from x0 along the ray, so in polar coordinates about
  // x0 its radius is |v| t and its angle that of v0.
  using Chart = sesi::Quotient<sesi::Hyperbolic<2>, Surface>;
  const double radius = 1.3;
  const Chart chart(sesi::Hyperbolic<2>(radius), Surface(2, radius));
  const Surface& surf = chart.topology();
  const sesi::System<Chart> sys(chart, std::vector<double>{1.5});
  sesi::State<Chart> s(2, 1);
  const double speed = 2.0;  // |v|, p_1 = m R^2 q1dot = m R speed
  s.set_body(0, {0.5, 0.9}, {1.5 * radius * speed, 0.0});
  s.enable_frames(3);
  s.frames[0] = boost_to(polar(0.4, 2.0));  // the chart's origin off o
  auto images = surf.identity_images(1);
  // x0 and the unit tangent e of the geodesic, from the initial (double) state in long double
  using V3L = Eigen::Matrix<LD, 3, 1>;
  auto world = [&](V3& x, V3& v) {
    Eigen::Vector2d q = s.q.col(0), p = s.p.col(0);
    typename Chart::Ambient xl, vl;
    chart.embed(q, xl);
    chart.velocity(q, p, sys.mass(0), vl);
    x = s.frames[0] * xl;
    v = s.frames[0] * vl;
  };
  V3 x0d, v0d;
  world(x0d, v0d);
  const V3L x0 = x0d.cast<LD>() / LD(radius);
  auto lor = [](const V3L& a, const V3L& b) { return a[0] * b[0] + a[1] * b[1] - a[2] * b[2]; };
  V3L e = v0d.cast<LD>();
  e += lor(e, x0) * x0;  // tangent at x0 (unit hyperboloid)
  e /= std::sqrt(lor(e, e));
  V3L f = V3L(x0[1] * e[2] - x0[2] * e[1], x0[2] * e[0] - x0[0] * e[2], -(x0[0] * e[1] - x0[1] * e[0]));
  f /= std::sqrt(lor(f, f));  // the other tangent direction at x0
  sesi::Strang<Chart> stepper;
  const double dt = 0.005;
  const int steps = 2400;  // t = 12: distance 24, 18.5 R
  int wraps = 0;
  double worst_r = 0, worst_angle = 0;
  // Each wrap or re-basing replaces F by a rounded product: its error dF, bounded below, moves
  // the world point and turns the direction by <= |dF| |embed(q)|, |embed(q)| <= |(sinh 2, cosh 2)|
  // < 5.3 (q_1 <= 2). Such an error at distance s from x0 changes the radius about x0 by <= it
  // and the angle seen from x0 by <= it (1 + 1/sinh s): a point moved by delta across the line
  // of sight turns it by delta / sinh s; a direction turned by delta moves the point at
  // distance L by delta sinh(L - s), which turns it by delta sinh(L - s) / sinh L <= delta.
  double radial_events = 0, angle_events = 0;
  V3 xb, vb, xa, va;
  for (int k = 1; k <= steps; ++k) {
    stepper.do_step(sys, s, (k - 1) * dt, dt);
    const double travelled = speed * k * dt / radius;
    const double reach = 1 + 1 / std::sinh(travelled);
    if (s.q(0, 0) > 2.0) {
      world(xb, vb);
      const double a = s.q(0, 0) - 0.5, th = s.q(1, 0);
      M3 t = M3::Identity();
      const Eigen::Vector2d dir(std::cos(th), std::sin(th));
      t.topLeftCorner<2, 2>() += (std::cosh(a) - 1) * dir * dir.transpose();
      t.topRightCorner<2, 1>() = std::sinh(a) * dir;
      t.bottomLeftCorner<1, 2>() = std::sinh(a) * dir.transpose();
      t(2, 2) = std::cosh(a);
      // the product (gamma_3) and T's entries (cosh, sinh, cos, sin: <= 4 eps relative): 8 eps |F| |T|
      const double d_f = 8 * eps * fro(s.frames[0]) * fro(t) * 5.3;
      radial_events += d_f;
      angle_events += d_f * reach;
      s.frames[0] = (s.frames[0] * t).eval();
      s.q(0, 0) = 0.5;
      world(xa, va);
      CHECK((xa - xb).norm() <= 1e-9 * xb.norm());  // the re-basing keeps the world point
    }
    const M3 before = s.frames[0];
    if (sesi::wrap(sys, s, images, 0.0) > 0) {
      ++wraps;
      const M3& after = s.frames[0];
      const M3 gamma = after * eta() * before.transpose() * eta();  // after before^{-1}
      // gamma F (gamma_3 |gamma| |F|) and the rebuild (orthonormalise: the rotation read to
      // ~4 eps |F|, lifted by B(y) of norm |F|: <= 16 eps |F|_F^2)
      const double d_f = (gamma3 * fro(gamma) * fro(before) + 16 * eps * fro(after) * fro(after)) * 5.3;
      radial_events += d_f;
      angle_events += d_f * reach;
    }
    for (std::size_t i = 1; i < images[0].size(); ++i) CHECK(images[0][i] != surf.inverse(images[0][i - 1]));
    // the unwrapped point, in long double
    V3 x, v;
    world(x, v);
    Eigen::Matrix<LD, 3, 3> w = Eigen::Matrix<LD, 3, 3>::Identity();
    for (auto l : images[0]) w = (w * surf.generator(l).cast<LD>()).eval();
    const V3L u = w * x.cast<LD>() / LD(radius);
    const LD r = std::acosh(-lor(x0, u));
    const V3L tang = u + lor(u, x0) * x0;
    const LD angle = std::atan2(lor(tang, f), lor(tang, e));
    const LD expected_r = LD(speed) * LD(k) * LD(dt) / LD(radius);
    worst_r = std::max(worst_r, double(std::abs(r - expected_r)));
    worst_angle = std::max(worst_angle, double(std::abs(angle)));
  }
  // Steps move q_1 by h p_1 / (m R^2) along the ray, exact but for rounding: two additions to
  // q_1 <= 2 (eps each) and the increments' relative 3 eps: < 2.1 eps a step, radial only. The
  // reference in long double (eps_ld = eps / 2048) and the rounding of x0 and e are shared or
  // far below. (R scales out: u and x0 are on the unit hyperboloid.)
  const double bound_r = 2.1 * eps * steps + radial_events;
  const double bound_angle = angle_events;
  MESSAGE("surface: ", wraps, " wraps, word length ", images[0].size(), ", radial error ", worst_r, " (bound ",
          bound_r, "), angle error ", worst_angle, " (bound ", bound_angle, ")");
  CHECK(wraps >= 6);
  CHECK(images[0].size() >= 4);
  CHECK(worst_r <= bound_r);
  CHECK(worst_angle <= bound_angle);
  // The bounds can tell a wrong letter: any other element moves a point by >= the systole, while
  // points within bound_r in radius and bound_angle in angle about x0 at distance L are within
  // bound_r + bound_angle sinh L of each other.
  const double travelled = speed * steps * dt / radius;
  CHECK(bound_r + bound_angle * std::sinh(travelled) < 1e-2 * surf.systole() / radius);
  CHECK(surf.outside(chart.topology().radius() * V3(0, 0, 1)) == 0);
}
