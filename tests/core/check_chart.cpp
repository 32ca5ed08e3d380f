// sesi::check_chart (issue #14): the built-in charts pass it at random points of their safe
// regions; charts with the mistakes it is for fail it with a line naming the level, the
// coordinate or the derivative: a K_i that reads q_i (compiles, runs, and is neither symplectic
// nor explicit), a kinetic_dq of the wrong sign, a pull-back that is not J^T.
#include <random>
#include <tuple>
#include <vector>

#include <doctest/doctest.h>
#include <sesi/check_chart.hpp>

#include "common.hpp"

namespace {

using namespace coretest;

template <class Chart>
std::vector<typename Chart::Point> samples(const Chart& chart) {
  std::mt19937 rng(11);
  std::vector<typename Chart::Point> out;
  for (int k = 0; k < 4; ++k) out.push_back(random_point(chart, rng));
  return out;
}

/// S^2 with one of three mistakes.
enum class Mistake { level_reads_own_coordinate, wrong_sign_dq, pullback_not_transposed };
template <Mistake M>
struct BrokenSphere {
  using Inner = sesi::Sphere<2, double>;
  using Scalar = double;
  using Point = Inner::Point;
  using Ambient = Inner::Ambient;
  static constexpr int dimension = 2;
  static constexpr int ambient_dimension = 3;
  Inner inner{1.0};
  int dim() const { return 2; }
  int ambient_dim() const { return 3; }
  double kinetic(int i, const Point& q, double pi, double m) const {
    const double k = inner.kinetic(i, q, pi, m);
    if constexpr (M == Mistake::level_reads_own_coordinate) {
      if (i == 1) return k * (1.0 + 0.1 * std::cos(q[1]));  // K_2 reads q_2
    }
    return k;
  }
  double kinetic_dp(int i, const Point& q, double pi, double m) const {
    if constexpr (M == Mistake::level_reads_own_coordinate) {
      if (i == 1) return inner.kinetic_dp(i, q, pi, m) * (1.0 + 0.1 * std::cos(q[1]));
    }
    return inner.kinetic_dp(i, q, pi, m);
  }
  double kinetic_dq(int i, int k, const Point& q, double pi, double m) const {
    const double d = inner.kinetic_dq(i, k, q, pi, m);
    if constexpr (M == Mistake::wrong_sign_dq) return -d;
    if constexpr (M == Mistake::level_reads_own_coordinate) {
      if (i == 1) return d * (1.0 + 0.1 * std::cos(q[1]));
    }
    return d;
  }
  void embed(const Point& q, Ambient& x) const { inner.embed(q, x); }
  void pullback(const Point& q, const Ambient& g, Point& out) const {
    inner.pullback(q, g, out);
    if constexpr (M == Mistake::pullback_not_transposed) std::swap(out[0], out[1]);
  }
};

bool mentions(const sesi::ChartCheck& c, const std::string& text) {
  for (const std::string& f : c.failures) {
    if (f.find(text) != std::string::npos) return true;
  }
  return false;
}

}  // namespace

using BuiltInCharts =
    std::tuple<sesi::Sphere<1, double>, sesi::Sphere<2, double>, sesi::Sphere<4, double>,
               sesi::Sphere<Eigen::Dynamic, double>, sesi::Hyperbolic<1, double>, sesi::Hyperbolic<2, double>,
               sesi::Hyperbolic<4, double>, sesi::Euclidean<1, double>, sesi::Euclidean<3, double>>;

TEST_CASE_TEMPLATE_DEFINE("check_chart: the built-in charts pass", Chart, builtin_charts) {
  const Chart chart = make_chart<Chart>(Chart::dimension == Eigen::Dynamic ? 5 : Chart::dimension);
  const auto points = samples(chart);
  const sesi::ChartCheck c = sesi::check_chart(chart, std::span<const typename Chart::Point>(points), 1.5);
  INFO(c.report());
  CHECK(static_cast<bool>(c));
  CHECK(c.checked > 0);
}
TEST_CASE_TEMPLATE_APPLY(builtin_charts, BuiltInCharts);

TEST_CASE("check_chart: finds a level that reads its own coordinate, a wrong sign, a wrong pull-back") {
  const std::vector<Eigen::Vector2d> points = {{1.1, 0.4}, {1.9, -2.0}};
  const auto own = sesi::check_chart(BrokenSphere<Mistake::level_reads_own_coordinate>{}, std::span(points));
  INFO(own.report());
  CHECK(!own);
  CHECK(mentions(own, "K_2 depends on q_2"));
  CHECK(!mentions(own, "K_1 depends"));

  const auto sign = sesi::check_chart(BrokenSphere<Mistake::wrong_sign_dq>{}, std::span(points));
  CHECK(!sign);
  CHECK(mentions(sign, "kinetic_dq(1, 0)"));
  CHECK(!mentions(sign, "depends on"));

  const auto pullback = sesi::check_chart(BrokenSphere<Mistake::pullback_not_transposed>{}, std::span(points));
  CHECK(!pullback);
  CHECK(mentions(pullback, "pullback"));
}
