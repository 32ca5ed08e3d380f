// Pair terms and neighbour structures on quotients (issue #26): an E^2 periodic box and compact
// hyperbolic surfaces of genus 2 and 3 (Sausset & Tarjus, J. Phys. A 40, 12873 (2007)). The index
// finds exactly the images within reach (periodic cells; ghost images); a pair straddling a side
// feels the force of its image pair in the covering space; forces through the lists equal the
// all-pairs minimum-image rows to the bit; 1, 2 and 3 threads step to the same bits; a box's
// Verlet list survives a wrap.
#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
#include <utility>
#include <vector>

#include <doctest/doctest.h>

#include <sesi/neighbours.hpp>
#include <sesi/recharting.hpp>
#include <sesi/stepper.hpp>

#include "common.hpp"
#include "topology_scenes.hpp"

namespace {

using namespace topotest;
constexpr double eps = std::numeric_limits<double>::epsilon();
using LJ = sesi::LennardJones<double>;

template <class Point>
Eigen::MatrixXd matrix_of(const std::vector<Point>& points) {
  Eigen::MatrixXd X(points.front().size(), static_cast<Eigen::Index>(points.size()));
  for (std::size_t b = 0; b < points.size(); ++b) X.col(static_cast<Eigen::Index>(b)) = points[b];
  return X;
}

// ---- the index ----------------------------------------------------------------------------------

/// Box: lists hold j (the minimum image is taken by the system). Every j with minimum-image
/// distance < reach is listed, and only those, except within a relative `slack` of the reach.
void check_box_index(const Box2& chart, const Eigen::MatrixXd& X, double reach) {
  sesi::NeighbourIndex<Box2> index;
  sesi::NeighbourLists lists;
  index.build(chart, X, reach, lists);
  const int n = static_cast<int>(X.cols());
  REQUIRE(lists.bodies() == n);
  CHECK(lists.image.empty());
  // The chord and the distance are the same norm of the same difference (E^2): they differ by
  // the rounding of the minimum image and the norm, a few eps relative.
  const double slack = 16 * eps;
  long missing = 0, extra = 0, unsorted = 0, listed = 0;
  for (int i = 0; i < n; ++i) {
    std::set<int> in_list;
    for (int k = lists.begin(i); k < lists.end(i); ++k) {
      const int j = lists.index[static_cast<std::size_t>(k)];
      if (k > lists.begin(i) && !(lists.index[static_cast<std::size_t>(k) - 1] < j)) ++unsorted;
      in_list.insert(j);
    }
    listed += static_cast<long>(in_list.size());
    for (int j = 0; j < n; ++j) {
      if (j == i) continue;
      const double d = min_image_distance(chart, X.col(i), X.col(j));
      const bool in = in_list.count(j) > 0;
      if (d < reach * (1 - slack) && !in) ++missing;
      if (d > reach * (1 + slack) && in) ++extra;
    }
  }
  CHECK(missing == 0);
  CHECK(extra == 0);
  CHECK(unsorted == 0);
  CHECK(listed > 0);
}

/// Surface: lists hold (j, k), k an index of images(); every image within reach of body i (k = 0
/// included, j == i excluded) is listed, and only those, up to the chord's round-off.
void check_surface_index(const Surface& chart, const Eigen::MatrixXd& X, double reach, long& across) {
  sesi::NeighbourIndex<Surface> index;
  sesi::NeighbourLists lists;
  index.build(chart, X, reach, lists);
  const auto& t = chart.topology();
  const int n = static_cast<int>(X.cols());
  REQUIRE(lists.bodies() == n);
  REQUIRE(lists.image.size() == lists.index.size());
  // Points reach D' = circumradius + margin + reach from the centre (ghosts), where coordinates
  // of size R cosh(D'/R) carry eps R cosh(D'/R) each: a chord of points `reach` apart errs by
  // eps cosh^2(D'/R) R / reach relative, a distance from their Minkowski product by
  // eps cosh^2(D'/R) (R / reach)^2 (tests/many/neighbours.cpp); 64 of them.
  const double R = t.radius(), far = std::cosh((t.circumradius() + 2 * reach) / R);
  const double slack = 64 * eps * far * far * std::pow(1 + R / reach, 2);
  long missing = 0, extra = 0, unsorted = 0, listed = 0;
  Eigen::Vector3d y;
  for (int i = 0; i < n; ++i) {
    std::set<std::pair<int, int>> in_list;
    for (int e = lists.begin(i); e < lists.end(i); ++e) {
      const std::pair<int, int> jk(lists.index[static_cast<std::size_t>(e)], lists.image[static_cast<std::size_t>(e)]);
      if (e > lists.begin(i) &&
          !(std::make_pair(lists.index[static_cast<std::size_t>(e) - 1], lists.image[static_cast<std::size_t>(e) - 1]) < jk))
        ++unsorted;
      in_list.insert(jk);
      if (jk.second != 0) ++across;
    }
    listed += static_cast<long>(in_list.size());
    for (int j = 0; j < n; ++j) {
      if (j == i) continue;
      for (int k = 0; k < static_cast<int>(t.images().size()); ++k) {
        y = X.col(j);
        t.apply(k, y);
        const double d = chart.distance(X.col(i), y);
        const bool in = in_list.count({j, k}) > 0;
        if (d < reach * (1 - slack) && !in) ++missing;
        if (d > reach * (1 + slack) && in) ++extra;
      }
    }
  }
  CHECK(missing == 0);
  CHECK(extra == 0);
  CHECK(unsorted == 0);
  CHECK(listed > 0);
}

}  // namespace

TEST_CASE("the neighbour index on a quotient finds exactly the images within reach") {
  SUBCASE("E^2 box: periodic cells, and an axis too short for three") {
    const Box2 chart = box2(12.0, 7.5);
    // Bodies up to 0.5 outside the box, as between wraps.
    const Eigen::MatrixXd X = matrix_of(uniform_points(chart, 300, 0.5, 31));
    check_box_index(chart, X, 2.0);  // 6 x 3 cells
    check_box_index(chart, X, 3.0);  // 4 x 2 cells: the short axis searched whole
    check_box_index(chart, X, 3.75);  // reach = L2 / 2
  }
  SUBCASE("genus 2 and 3: ghost images") {
    for (int genus : {2, 3}) {
      const Surface chart = surface(genus, surface_radius(genus, 200, 0.5));
      const double cut = chart.topology().max_cutoff();
      // Bodies up to 0.3 max_cutoff outside the polygon; reach = max_cutoff (1 + skin).
      const Eigen::MatrixXd X = matrix_of(uniform_points(chart, 200, 0.3 * cut, 32 + genus));
      long across = 0;
      check_surface_index(chart, X, cut * (1 + sesi::default_skin_fraction), across);
      CHECK(across > 0);  // pairs met through a side were listed
    }
  }
}

// ---- a pair straddling a side -----------------------------------------------------------------

namespace {

/// The point at distance d from x in direction theta (the exponential map).
Eigen::Vector2d walk(const Box2&, const Eigen::Vector2d& x, double d, double theta) {
  return x + d * Eigen::Vector2d(std::cos(theta), std::sin(theta));
}
Eigen::Vector3d walk(const Surface& chart, const Eigen::Vector3d& x, double d, double theta) {
  Eigen::Vector3d e1, e2;
  tangent_basis(chart, x, e1, e2);
  const double R = chart.radius();
  return std::cosh(d / R) * x + R * std::sinh(d / R) * (std::cos(theta) * e1 + std::sin(theta) * e2);
}
/// y into the domain; returns how many group letters (box: axes) that took.
int reduce(const Box2& chart, Eigen::Vector2d& y) {
  Eigen::Matrix<std::int64_t, 2, 1> c = Eigen::Matrix<std::int64_t, 2, 1>::Zero();
  chart.topology().reduce(y, c);
  return static_cast<int>((c.array() != 0).count());
}
int reduce(const Surface& chart, Eigen::Vector3d& y) {
  sesi::HyperbolicSurface<double>::Word applied;
  chart.topology().reduce(y, applied);
  return static_cast<int>(applied.size());
}
/// The length scale of round-off in a pair's geometry (tests/many/neighbours.cpp): R, or on E^n
/// the points' own size.
double length_of(const Box2&, const Eigen::VectorXd& x, const Eigen::VectorXd& y) {
  return std::max({1.0, x.norm(), y.norm()});
}
double length_of(const Surface& chart, const Eigen::VectorXd&, const Eigen::VectorXd&) { return chart.radius(); }

/// For pairs x_i in D and y at distance d across a side (x_j = y reduced into D): the 2-body
/// quotient system's gradients and energy equal those of the pair (x_i, image of x_j nearest x_i)
/// and (image of x_i nearest x_j, x_j) in the covering space, and those images are the pair
/// built.
template <class Chart>
void check_straddling(const Chart& chart, double cutoff, std::uint64_t seed, int wanted) {
  const LJ lj{1.0, 1.0, cutoff};
  sesi::System quotient(chart, std::vector<double>{1.0, 1.0}, lj);
  sesi::System cover(chart.cover(), std::vector<double>{1.0, 1.0}, lj);
  auto wq = quotient.make_workspace();
  auto wc = cover.make_workspace();
  std::mt19937_64 rng(seed);
  int straddling = 0, corners = 0;
  double worst_image = 0, worst = 0;
  for (int tries = 0; straddling < wanted && tries < 100 * wanted; ++tries) {
    const auto xi = uniform_points(chart, 1, 0.0, rng())[0];
    const double d = (0.9 + 0.6 * manytest::uniform(rng)) * lj.sigma;  // the well, 0.9..1.5 sigma
    auto xj = walk(chart, xi, d, 2 * std::numbers::pi * manytest::uniform(rng));
    const auto y = xj;
    const int letters = reduce(chart, xj);
    if (letters == 0) continue;
    ++straddling;
    corners += letters > 1;
    // The images the topology finds: of x_j nearest x_i, and of x_i nearest x_j. The first is the
    // y built, up to rounding: reduce took y to x_j by group matrices of entries up to M, and the
    // image's matrix (entries up to M) took it back, each product erring by a few eps times the
    // entries times the point: 64 eps M^2 |y| (M = 1 and |y| + L on a box: a translation).
    auto yi = xj, zj = xi;
    double scale = 0;
    if constexpr (std::is_same_v<Chart, Box2>) {
      chart.topology().nearest_image(xi, yi);
      scale = y.cwiseAbs().maxCoeff() + chart.topology().edges().maxCoeff();
    } else {
      const int k = chart.topology().nearest_image(xi, yi);
      const double M = chart.topology().images()[static_cast<std::size_t>(k)].cwiseAbs().maxCoeff();
      scale = M * M * y.cwiseAbs().maxCoeff();
    }
    chart.topology().nearest_image(xj, zj);
    worst_image = std::max(worst_image, (yi - y).cwiseAbs().maxCoeff() / (64 * eps * scale));
    // The quotient system on (x_i, x_j).
    wq.X.col(0) = xi;
    wq.X.col(1) = xj;
    quotient.ambient_gradient(wq);
    const double eq = quotient.ambient_potential_energy(wq);
    // The covering space on (x_i, y_i) for body i, on (z_j, x_j) for body j.
    wc.X.col(0) = xi;
    wc.X.col(1) = yi;
    cover.ambient_gradient(wc);
    const Eigen::VectorXd gi = wc.G.col(0);
    const double ec = cover.ambient_potential_energy(wc);
    wc.X.col(0) = zj;
    wc.X.col(1) = xj;
    cover.ambient_gradient(wc);
    const Eigen::VectorXd gj = wc.G.col(1);
    // Rows (the quotient) and the symmetric pair loop (2 bodies on the cover) round differently.
    // The distance and its gradient cancel terms of the size of the points against a result of
    // size d (tests/many/neighbours.cpp): the distance errs by ~eps L c, c = 1 + (|x|^2 + |y|^2)
    // / (L d), and its gradient, a unit covector whose ambient components are up to s = max(|x|,
    // |y|) / L (1 on E^n, where L bounds the points), by ~eps c s (H^2: the Minkowski product
    // <x, y> errs by eps |x| |y| and is multiplied by x / sinh(d/R)). So G = W'(d) grad d errs
    // by eps c s (|W'| + |W''| L): 64 of that. The energy: |W'| times the distance's error plus |W| eps.
    const double L = length_of(chart, Eigen::VectorXd(xi), Eigen::VectorXd(yi));
    const double condition = 1 + (xi.squaredNorm() + yi.squaredNorm()) / (L * d);
    const double dw = std::abs(lj.derivative(chart.cover(), d, 1, 1));
    const double d2w = std::abs(lj.second_derivative(chart.cover(), d, 1, 1));
    const double s = std::max({L, xi.norm(), yi.norm(), zj.norm(), xj.norm()}) / L;
    const double bound_g = 64 * eps * condition * s * (dw + d2w * L);
    const double bound_e = 64 * eps * (std::abs(lj.value(chart.cover(), d, 1, 1)) + dw * L * condition);
    worst = std::max({worst, (Eigen::VectorXd(wq.G.col(0)) - gi).cwiseAbs().maxCoeff() / bound_g,
                      (Eigen::VectorXd(wq.G.col(1)) - gj).cwiseAbs().maxCoeff() / bound_g, std::abs(eq - ec) / bound_e});
  }
  CHECK(straddling == wanted);
  CHECK(corners > 0);  // pairs across a corner (box) or near a vertex (two letters) were met too
  CHECK(worst_image < 1.0);
  CHECK(worst < 1.0);
}

}  // namespace

TEST_CASE("a pair straddling a side feels the force of its image pair in the covering space") {
  SUBCASE("E^2 box") { check_straddling(box2(6.0, 5.0), 2.5, 41, 200); }
  SUBCASE("genus 2") { check_straddling(surface(2, 4.0), 2.5, 42, 200); }
  SUBCASE("genus 3") { check_straddling(surface(3, 3.0), 2.5, 43, 200); }
}

// ---- lists against all pairs --------------------------------------------------------------------

namespace {

template <class Chart>
using LJSystem = sesi::System<Chart, LJ>;

struct Sums {
  Eigen::MatrixXd gradient;
  double energy, laplacian;
};
template <class Chart>
Sums sums(LJSystem<Chart>& sys, const sesi::State<Chart>& s, typename LJSystem<Chart>::PairSearch search) {
  sys.set_pair_search(search);
  auto w = sys.make_workspace();
  Sums out;
  typename sesi::State<Chart>::Matrix g;
  sys.potential_gradient(s, w, g);
  out.gradient = g;
  out.energy = sys.potential_energy(s, w);
  out.laplacian = sys.laplacian_sum(s, w);
  return out;
}

/// The lists give the bits of the all-pairs rows: both sum each body's partners in ascending
/// order on the same image (the box's nearest image; the surface's image k, the unique one within
/// range, which nearest_image also finds, by the same matrix product).
template <class Chart>
void check_lists_equal_all_pairs(const Chart& chart, int n, double cutoff, double margin, std::uint64_t seed) {
  REQUIRE(cutoff <= chart.topology().max_cutoff());
  LJSystem<Chart> sys(chart, std::vector<double>(static_cast<std::size_t>(n), 1.0), LJ{1.0, 1.0, cutoff});
  REQUIRE(sys.by_rows());
  const auto s = state_from(chart, uniform_points(chart, n, margin, seed), 1.0, seed + 1);
  using Search = typename LJSystem<Chart>::PairSearch;
  const Sums a = sums(sys, s, Search::automatic), b = sums(sys, s, Search::all_pairs);
  CHECK(a.gradient.allFinite());
  CHECK(a.gradient.cwiseAbs().maxCoeff() > 0);
  CHECK((a.gradient.array() == b.gradient.array()).all());
  CHECK(a.energy == b.energy);
  CHECK(a.laplacian == b.laplacian);
}

}  // namespace

TEST_CASE("forces through the lists equal the all-pairs minimum-image rows to the bit") {
  // Bodies up to a quarter of the cutoff outside the domain (the program's wrap margin).
  SUBCASE("E^2 box") { check_lists_equal_all_pairs(box2(16.0, 12.0), 200, 2.5, 0.6, 51); }
  SUBCASE("genus 2") {
    const Surface chart = surface(2, surface_radius(2, 200, 0.5));
    check_lists_equal_all_pairs(chart, 200, 2.5, 0.6, 52);
  }
  SUBCASE("genus 3") {
    const Surface chart = surface(3, surface_radius(3, 160, 0.5));
    check_lists_equal_all_pairs(chart, 160, 2.5, 0.6, 53);
  }
}

// ---- threads --------------------------------------------------------------------------------------

namespace {

template <class Chart>
struct Outcome {
  sesi::State<Chart> state;
  typename Chart::Topology::Images images;
  double energy, laplacian;
  Eigen::MatrixXd gradient;
  int wrapped;
};

template <class Chart, class Stepper>
Outcome<Chart> run(const LJSystem<Chart>& sys, sesi::State<Chart> s, int threads, int steps, double dt) {
  sesi::parallel::set_threads(threads);
  Stepper stepper;
  auto images = sys.chart().topology().identity_images(s.bodies());
  int wrapped = 0;
  for (int k = 0; k < steps; ++k) {
    stepper.do_step(sys, s, 0.0, dt);
    wrapped += sesi::wrap(sys, s, images, 0.0);  // margin 0: a wrap whenever a body is outside
  }
  auto w = sys.make_workspace();
  typename sesi::State<Chart>::Matrix g;
  sys.potential_gradient(s, w, g);
  Outcome<Chart> out{s, images, sys.energy(s, w), sys.laplacian_sum(s, w), g, wrapped};
  sesi::parallel::set_threads(0);
  return out;
}

template <class Chart, class Stepper>
void check_thread_counts(const LJSystem<Chart>& sys, const sesi::State<Chart>& s0, double dt) {
  REQUIRE(sys.bodies() >= 3 * sesi::parallel::min_parallel_bodies);  // work for three threads
  const auto one = run<Chart, Stepper>(sys, s0, 1, 20, dt);
  CHECK(one.state.q.allFinite());
  CHECK(one.wrapped > 0);  // bodies crossed sides
  for (int threads : {2, 3}) {
    const auto many = run<Chart, Stepper>(sys, s0, threads, 20, dt);
    CHECK((many.state.q.array() == one.state.q.array()).all());
    CHECK((many.state.p.array() == one.state.p.array()).all());
    CHECK(many.state.frames == one.state.frames);
    CHECK(many.images == one.images);
    CHECK(many.energy == one.energy);
    CHECK(many.laplacian == one.laplacian);
    CHECK((many.gradient.array() == one.gradient.array()).all());
  }
  if (!sesi::parallel::available()) MESSAGE("built without OpenMP: every count ran on one thread");
}

}  // namespace

TEST_CASE("1, 2 and 3 threads give the same bits on a quotient") {
  const int n = 800;
  SUBCASE("E^2 box") {
    const double L = std::sqrt(n / 0.5);
    const Box2 chart = box2(L, L);
    LJSystem<Box2> sys(chart, std::vector<double>(n, 1.0), LJ{1.0, 1.0, 2.5});
    const auto s0 = state_from(chart, spaced_points(chart, n, 1.0, 61), 1.0, 62);
    check_thread_counts<Box2, sesi::Composition<sesi::coefficients::Strang, Box2>>(sys, s0, 0.005);
  }
  SUBCASE("genus 2") {
    const Surface chart = surface(2, surface_radius(2, n, 0.5));
    LJSystem<Surface> sys(chart, std::vector<double>(n, 1.0), LJ{1.0, 1.0, 2.5});
    const auto s0 = state_from(chart, spaced_points(chart, n, 1.0, 63), 1.0, 64);
    check_thread_counts<Surface, sesi::RechartingComposition<sesi::coefficients::Strang, Surface>>(sys, s0, 0.005);
  }
}

// ---- the Verlet list across a wrap ------------------------------------------------------------

TEST_CASE("a box's Verlet list survives a wrap; a surface's rebuilds and stays right") {
  SUBCASE("E^2 box") {
    const Box2 chart = box2(10.0, 10.0);
    Eigen::MatrixXd X = matrix_of(uniform_points(chart, 100, 0.0, 71));
    sesi::VerletList<Box2> list;
    list.update(chart, X, 2.5);
    const auto before = list.update(chart, X, 2.5);
    REQUIRE(list.builds() == 1);
    // Every body moved by a whole box (a wrap's change of the world point): the same point of the
    // torus, no rebuild, the same lists.
    X.row(0).array() += 10.0;
    X.row(1).array() -= 10.0;
    const auto& after = list.update(chart, X, 2.5);
    CHECK(list.builds() == 1);
    CHECK(after.index == before.index);
    // A body moved by more than half the skin rebuilds.
    X(0, 3) += 0.2;
    list.update(chart, X, 2.5);
    CHECK(list.builds() == 2);
  }
  SUBCASE("genus 2") {
    const Surface chart = surface(2, 4.0);
    const auto& t = chart.topology();
    // Bodies up to 0.6 outside the polygon, as between wraps.
    Eigen::MatrixXd X = matrix_of(uniform_points(chart, 60, 0.6, 72));
    int out = 0;
    while (out < X.cols() && !(t.outside(Eigen::Vector3d(X.col(out))) > 0.1)) ++out;
    REQUIRE(out < X.cols());
    sesi::VerletList<Surface> list;
    const auto before = list.update(chart, X, 2.5);
    // Body `out` brought back into the polygon (what a wrap does to its world point).
    Eigen::Vector3d y = X.col(out);
    sesi::HyperbolicSurface<double>::Word applied;
    t.reduce(y, applied);
    X.col(out) = y;
    const auto& after = list.update(chart, X, 2.5);
    CHECK(list.builds() == 2);
    // Its partners are the same bodies, seen through other images (a pair's images change by the
    // element moved, the partners do not).
    std::set<int> p0, p1;
    for (int e = before.begin(out); e < before.end(out); ++e) p0.insert(before.index[static_cast<std::size_t>(e)]);
    for (int e = after.begin(out); e < after.end(out); ++e) p1.insert(after.index[static_cast<std::size_t>(e)]);
    CHECK(p0 == p1);
    CHECK(!p0.empty());
  }
}
