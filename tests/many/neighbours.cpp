// The neighbour index and the pair sums of many bodies (issue #11): the index finds exactly the
// pairs within reach on S^n, H^n (near the origin and far from it) and E^n; forces through a
// Verlet list equal the all-pairs rows to the bit; rows and tiles agree with an independent
// pair sum to round-off; a Verlet list stays right across rebuilds.
#include <algorithm>
#include <cmath>
#include <limits>
#include <set>
#include <utility>
#include <vector>

#include <doctest/doctest.h>

#include <sesi/neighbours.hpp>
#include <sesi/stepper.hpp>

#include "common.hpp"

namespace {

using namespace manytest;
constexpr double eps = std::numeric_limits<double>::epsilon();

/// Lists against all pairs by the chart's own distance. A pair within `slack` (relative) of
/// the reach may fall either way: the chord test and the distance round differently there.
template <class Chart>
void check_index(const Chart& chart, const Eigen::MatrixXd& X, double reach, double slack) {
  sesi::NeighbourIndex<Chart> index;
  sesi::NeighbourLists lists;
  index.build(chart, X, reach, lists);
  const int n = static_cast<int>(X.cols());
  REQUIRE(lists.bodies() == n);
  typename Chart::Ambient x(X.rows()), y(X.rows());
  long missing = 0, extra = 0, unsorted = 0, listed = 0;
  for (int i = 0; i < n; ++i) {
    std::set<int> in_list;
    for (int k = lists.begin(i); k < lists.end(i); ++k) {
      const int j = lists.index[static_cast<std::size_t>(k)];
      if (k > lists.begin(i) && !(lists.index[static_cast<std::size_t>(k) - 1] < j)) ++unsorted;
      in_list.insert(j);
    }
    x = X.col(i);
    for (int j = 0; j < n; ++j) {
      if (j == i) continue;
      y = X.col(j);
      const double d = chart.distance(x, y);
      const bool listed_ij = in_list.count(j) > 0;
      listed += listed_ij;
      if (d < reach * (1 - slack) && !listed_ij) ++missing;
      if (d > reach * (1 + slack) && listed_ij) ++extra;
    }
  }
  CHECK(missing == 0);
  CHECK(extra == 0);
  CHECK(unsorted == 0);
  CHECK(listed == 2 * lists.pairs());
  CHECK(lists.pairs() > n / 10);  // the scene is dense enough to test something
}

}  // namespace

TEST_CASE("the neighbour index finds exactly the pairs within reach") {
  const int n = 600;
  SUBCASE("S^2") {
    const sesi::Sphere<2, double> chart(radius_for(2, n));
    const auto s = random_state(chart, n, 0, 0, 1, 1);
    for (double reach : {1.0, 2.5, 7.0}) check_index(chart, points_of(chart, s), reach, 1e-12);
  }
  SUBCASE("S^3") {
    const sesi::Sphere<3, double> chart(radius_for(3, n));
    const auto s = random_state(chart, n, 0, 0, 1, 2);
    for (double reach : {1.0, 2.5}) check_index(chart, points_of(chart, s), reach, 1e-12);
  }
  SUBCASE("S^5, dynamic size") {
    const sesi::Sphere<Eigen::Dynamic, double> chart(2.0, 5);
    const auto s = random_state(chart, 300, 0, 0, 1, 3);
    check_index(chart, points_of(chart, s), 1.5, 1e-12);
  }
  SUBCASE("E^3") {
    const sesi::Euclidean<3, double> chart;
    const auto s = random_state(chart, n, 12.0, 0, 1, 4);
    for (double reach : {1.0, 2.5}) check_index(chart, points_of(chart, s), reach, 1e-12);
  }
  SUBCASE("H^2 at the origin, and 10 R away") {
    const double R = 3.0, spread = 3.0 * R;
    const sesi::Hyperbolic<2, double> chart(R);
    for (double far : {0.0, 10.0 * R}) {
      const auto s = random_state(chart, n, spread, far, 1, 5);
      for (double reach : {1.0, 2.5, 8.0}) {
        // Bodies reach D = far + spread (13 R, or 3 R), where coordinates of size R e^(D/R) carry eps R
        // e^(D/R) each: a chord of points `reach` apart errs by eps e^(2D/R) R/reach relative, a
        // distance from their Minkowski product by eps e^(2D/R) (R/reach)^2; (1 + R/reach)^2
        // covers both (about 7e-4 at reach 1, 10 R away; 1.4e-12 about the origin, D = 3 R).
        const double slack = eps * std::exp(2.0 * (far + spread) / R) * std::pow(1.0 + R / reach, 2);
        check_index(chart, points_of(chart, s), reach, slack);
      }
    }
  }
  SUBCASE("H^3, strongly curved (R = 1)") {
    const sesi::Hyperbolic<3, double> chart(1.0);
    const auto s = random_state(chart, 400, 3.0, 4.0, 1, 6);
    for (double reach : {0.5, 2.0}) check_index(chart, points_of(chart, s), reach, 1e-9);
  }
}

namespace {

template <class Chart>
using LJSystem = sesi::System<Chart, sesi::LennardJones<double>, sesi::CotangentGravity<double>>;

template <class Chart>
LJSystem<Chart> lj_system(const Chart& chart, int n) {
  return LJSystem<Chart>(chart, std::vector<double>(static_cast<std::size_t>(n), 1.0),
                         sesi::LennardJones<double>{1.0, 1.0, 2.5}, sesi::CotangentGravity<double>{1e-3});
}

/// Chart gradients and energy of s, through the lists or all pairs.
template <class Chart>
std::pair<Eigen::MatrixXd, double> gradient_and_energy(LJSystem<Chart>& sys, const sesi::State<Chart>& s,
                                                        typename LJSystem<Chart>::PairSearch search) {
  sys.set_pair_search(search);
  auto w = sys.make_workspace();
  typename sesi::State<Chart>::Matrix g;
  sys.potential_gradient(s, w, g);
  return {g, sys.potential_energy(s, w)};
}

template <class Chart>
void check_lists_equal_all_pairs(const Chart& chart, const sesi::State<Chart>& s) {
  auto sys = lj_system(chart, s.bodies());
  REQUIRE(sys.by_rows());
  using Search = typename LJSystem<Chart>::PairSearch;
  const auto [g_list, e_list] = gradient_and_energy(sys, s, Search::automatic);
  const auto [g_all, e_all] = gradient_and_energy(sys, s, Search::all_pairs);
  CHECK(g_list.allFinite());
  CHECK((g_list.array() == g_all.array()).all());
  CHECK(e_list == e_all);
  // The lists' pair loop at each vector width this processor runs (config.hpp, simd::level):
  // lanes do a scalar's IEEE operations, with no contraction, so every width gives these bits.
  using sesi::simd::Level;
  for (const Level level : {Level::base, Level::avx2, Level::avx512}) {
    if (static_cast<int>(level) > static_cast<int>(sesi::simd::supported())) continue;
    sesi::simd::set_level(level);
    INFO("vector level " << static_cast<int>(level));
    const auto [g_level, e_level] = gradient_and_energy(sys, s, Search::automatic);
    CHECK((g_level.array() == g_all.array()).all());
  }
  sesi::simd::set_level(Level::avx512);  // (back to the widest supported)
}

}  // namespace

TEST_CASE("forces through the Verlet list equal the all-pairs rows to the bit, at every vector width") {
  // Both sum each body's pairs in ascending order of the partner, so the sums are the same
  // floating-point operations in the same order.
  MESSAGE("vector levels compared: base to " << static_cast<int>(sesi::simd::supported()) << " (0 base, 1 AVX2, 2 AVX-512)");
  const int n = 500;
  SUBCASE("S^2") {
    const sesi::Sphere<2, double> chart(radius_for(2, n));
    check_lists_equal_all_pairs(chart, random_state(chart, n, 0, 0, 1, 7));
  }
  SUBCASE("H^2 far out") {
    const sesi::Hyperbolic<2, double> chart(6.0);
    check_lists_equal_all_pairs(chart, random_state(chart, n, 10.0, 40.0, 1, 8));
  }
  SUBCASE("E^3") {
    const sesi::Euclidean<3, double> chart;
    check_lists_equal_all_pairs(chart, random_state(chart, n, 10.0, 0, 1, 9));
  }
}

namespace {

/// The ambient gradient of every body by a plain double loop over the chart's own distance and
/// distance gradient, and per body the sum of the contributions' sizes (the scale of its
/// round-off).
template <class Chart, class Sys>
void reference_gradient(const Chart& chart, const Sys& sys, const Eigen::MatrixXd& X, Eigen::MatrixXd& G,
                        Eigen::VectorXd& scale) {
  const int n = static_cast<int>(X.cols());
  G.setZero(X.rows(), n);
  scale.setZero(n);
  typename Chart::Ambient x(X.rows()), y(X.rows()), g(X.rows());
  const auto& [lj, gravity] = sys.terms();
  for (int i = 0; i < n; ++i) {
    x = X.col(i);
    for (int j = 0; j < n; ++j) {
      if (j == i) continue;
      y = X.col(j);
      const double d = chart.distance(x, y);
      chart.distance_gradient(x, y, g);
      // Both gradients of the distance cancel terms of the size of the points against a result
      // of size 1 over a distance d: their round-off is eps (|x|^2 + |y|^2) / (L d), L the
      // length scale (R; on E^n the points' own size).
      double length = std::max({1.0, x.norm(), y.norm()});
      if constexpr (requires { chart.radius(); }) length = chart.radius();
      const double condition = 1.0 + (x.squaredNorm() + y.squaredNorm()) / (length * d);
      for (double dw : {lj.derivative(chart, d, 1.0, 1.0), gravity.derivative(chart, d, 1.0, 1.0)}) {
        G.col(i) += dw * g;
        scale[i] += std::abs(dw) * condition;
      }
    }
  }
}

template <class Chart>
void check_rows_against_reference(const Chart& chart, const sesi::State<Chart>& s) {
  auto sys = lj_system(chart, s.bodies());
  REQUIRE(sys.by_rows());
  auto w = sys.make_workspace();
  sys.embed_all(s, w);
  sys.ambient_gradient(w);
  Eigen::MatrixXd G_ref;
  Eigen::VectorXd scale;
  reference_gradient(chart, sys, Eigen::MatrixXd(w.X), G_ref, scale);
  // Each contribution is a few correctly rounded operations, with the conditioning of the
  // distance's gradient (reference_gradient): 64 eps per unit of the summed sizes.
  double worst = 0;
  for (int i = 0; i < s.bodies(); ++i) {
    const double err = (Eigen::VectorXd(w.G.col(i)) - G_ref.col(i)).norm();
    worst = std::max(worst, err / (64 * eps * scale[i]));
  }
  CHECK(worst < 1.0);
}

}  // namespace

TEST_CASE("rows (short range) and tiles (long range) agree with an independent pair sum") {
  const int n = 300;
  SUBCASE("S^2") {
    const sesi::Sphere<2, double> chart(radius_for(2, n));
    check_rows_against_reference(chart, random_state(chart, n, 0, 0, 1, 10));
  }
  SUBCASE("S^3") {
    const sesi::Sphere<3, double> chart(radius_for(3, n));
    check_rows_against_reference(chart, random_state(chart, n, 0, 0, 1, 11));
  }
  SUBCASE("H^2") {
    const sesi::Hyperbolic<2, double> chart(4.0);
    check_rows_against_reference(chart, random_state(chart, n, 8.0, 0.0, 1, 12));
  }
  SUBCASE("E^3") {
    const sesi::Euclidean<3, double> chart;
    check_rows_against_reference(chart, random_state(chart, n, 9.0, 0, 1, 13));
  }
}

TEST_CASE("a Verlet list is rebuilt once a body has moved half its skin, and not before") {
  const int n = 400;
  const sesi::Sphere<2, double> chart(radius_for(2, n));
  const auto s = random_state(chart, n, 0, 0, 1, 14);
  Eigen::MatrixXd X = points_of(chart, s);
  sesi::VerletList<sesi::Sphere<2, double>> list;
  const double range = 2.5, half_skin = list.skin_fraction * range / 2;
  list.update(chart, X, range);
  CHECK(list.builds() == 1);
  // Body 7 moves along a great circle by 0.9 of half the skin: the list stands.
  const Eigen::Vector3d x0 = X.col(7);
  Eigen::Vector3d t = Eigen::Vector3d::UnitZ() - (x0.normalized().z()) * x0.normalized();
  t.normalize();
  const auto moved = [&](double d) {
    const double a = d / chart.radius();
    return Eigen::Vector3d(std::cos(a) * x0 + std::sin(a) * chart.radius() * t);
  };
  X.col(7) = moved(0.9 * half_skin);
  list.update(chart, X, range);
  CHECK(list.builds() == 1);
  X.col(7) = moved(1.1 * half_skin);
  list.update(chart, X, range);
  CHECK(list.builds() == 2);
}

TEST_CASE("update_moved checks the bodies it is told moved, and rebuilds as update would") {
  // System::patch_gradient's check after a re-charting: the lists of the last update stand
  // unless one of the named bodies moved half the skin from the build; then they are rebuilt,
  // and equal a fresh build's.
  const int n = 400;
  const sesi::Sphere<2, double> chart(radius_for(2, n));
  Eigen::MatrixXd X = points_of(chart, random_state(chart, n, 0, 0, 1, 14));
  sesi::VerletList<sesi::Sphere<2, double>> list, fresh;
  const double range = 2.5, half_skin = list.skin_fraction * range / 2;
  list.update(chart, X, range);
  const std::vector<int> none, seven{7};
  list.update_moved(chart, X, range, none);
  CHECK(list.builds() == 1);
  const Eigen::Vector3d x0 = X.col(7);
  Eigen::Vector3d t = Eigen::Vector3d::UnitZ() - (x0.normalized().z()) * x0.normalized();
  t.normalize();
  const auto moved = [&](double d) {
    const double a = d / chart.radius();
    return Eigen::Vector3d(std::cos(a) * x0 + std::sin(a) * chart.radius() * t);
  };
  X.col(7) = moved(0.9 * half_skin);
  list.update_moved(chart, X, range, seven);
  CHECK(list.builds() == 1);
  X.col(7) = moved(1.1 * half_skin);
  const sesi::NeighbourLists& lists = list.update_moved(chart, X, range, seven);
  CHECK(list.builds() == 2);
  const sesi::NeighbourLists& expected = fresh.update(chart, X, range);
  CHECK(lists.offset == expected.offset);
  CHECK(lists.index == expected.index);
  // Another range is a new list, whatever moved.
  list.update_moved(chart, X, 2.0, none);
  CHECK(list.builds() == 3);
}


TEST_CASE("the skin changes when the lists are rebuilt, not the forces") {
  const int n = 400;
  const sesi::Sphere<2, double> chart(radius_for(2, n));
  const auto s = random_state(chart, n, 0, 0, 1, 15);
  // A list built with a wide skin and then asked for a narrow one must rebuild: its half-skin
  // test would otherwise let bodies move further than the narrow list covers.
  const Eigen::MatrixXd X = points_of(chart, s);
  sesi::VerletList<sesi::Sphere<2, double>> list;
  list.skin_fraction = 0.3;
  list.update(chart, X, 2.5);
  list.skin_fraction = 0.1;
  list.update(chart, X, 2.5);
  CHECK(list.builds() == 2);
  // No skin: rebuilt at every update, even where nothing moved.
  list.skin_fraction = 0;
  list.update(chart, X, 2.5);
  list.update(chart, X, 2.5);
  CHECK(list.builds() == 4);
  // Forces and energy through lists of any skin equal the all-pairs rows to the bit.
  auto sys = lj_system(chart, n);
  using Search = LJSystem<sesi::Sphere<2, double>>::PairSearch;
  const auto [g_all, e_all] = gradient_and_energy(sys, s, Search::all_pairs);
  for (const double skin : {0.0, 0.12, 0.5}) {
    sys.set_neighbour_skin(skin);
    const auto [g, e] = gradient_and_energy(sys, s, Search::automatic);
    CHECK((g.array() == g_all.array()).all());
    CHECK(e == e_all);
  }
}

// Issue #27's build (bodies binned by a radix sort of their cells' numbers, candidates scanned
// cell by cell in a sorted copy of the points): the same lists on one thread and on two, a
// visit order that is a permutation of the bodies, and exact lists still when a NaN body's far
// cell (key -2^60) makes the keys' bounding box too large to number (the sort by comparisons).
// Below NeighbourIndex's radix_min_bodies the bodies are sorted by comparisons: exact lists too.
TEST_CASE("the neighbour index is the same on any thread count, with a NaN body, in cell order") {
  // 1200: above 2 min_parallel_bodies, so two threads take part; 300: the sort by comparisons.
  for (const int n : {1200, 300}) {
    INFO("bodies: " << n);
    using Chart = sesi::Sphere<2, double>;
    const Chart chart(radius_for(2, n));
    const auto s = random_state(chart, n, 0, 0, 1, 16);
    Eigen::MatrixXd X = points_of(chart, s);
    for (const bool nan : {false, true}) {
      INFO("NaN body: " << nan);
      if (nan) X(0, 17) = std::numeric_limits<double>::quiet_NaN();
      check_index(chart, X, 2.5, 1e-12);
      sesi::NeighbourLists lists[2];
      for (const int threads : {1, 2}) {
        sesi::parallel::set_threads(threads);
        sesi::NeighbourIndex<Chart> index;
        index.build(chart, X, 2.8, lists[threads - 1]);
      }
      sesi::parallel::set_threads(0);
      CHECK(lists[0].offset == lists[1].offset);
      CHECK(lists[0].index == lists[1].index);
      CHECK(lists[0].visit_order == lists[1].visit_order);
      std::vector<int> order = lists[0].visit_order;
      std::sort(order.begin(), order.end());
      bool permutation = static_cast<int>(order.size()) == n;
      for (int i = 0; permutation && i < n; ++i) permutation = order[static_cast<std::size_t>(i)] == i;
      CHECK(permutation);
      if (nan) CHECK(lists[0].end(17) == lists[0].begin(17));  // a NaN body has no partner
    }
  }
}
