// The observables library (src/analysis, docs/observables.md): the exact shell measure, g(r) = 1
// for an ideal gas on S^2, H^2 and E^2 by a chi-squared test at a fixed seed, the neighbour-cell
// counts equal to the all-pairs counts, and the MSD and VACF of bodies on known geodesics.
#include <doctest/doctest.h>

#include <cmath>
#include <cstdint>
#include <numbers>
#include <optional>
#include <random>
#include <vector>

#include <sesi/spaces/hyperbolic.hpp>

#include "analysis.hpp"

namespace {

using sesi::analysis::Rdf;
using sesi::analysis::Region;
using sesi::analysis::SpaceKind;
using sesi::analysis::SpaceSpec;
constexpr double pi = std::numbers::pi;

/// Uniform doubles in [0, 1) from the 53 high bits of mt19937_64 (fully specified, unlike
/// std::uniform_real_distribution's algorithm), so the samples are the same everywhere.
struct Uniform {
  std::mt19937_64 engine;
  explicit Uniform(std::uint64_t seed) : engine(seed) {}
  double operator()() { return static_cast<double>(engine() >> 11) * 0x1p-53; }
};

/// A uniform point on S^2 of radius R (Archimedes: z uniform in [-R, R]).
Eigen::VectorXd on_sphere(Uniform& u, double radius) {
  const double z = 2 * u() - 1, phi = 2 * pi * u(), rho = std::sqrt(1 - z * z);
  return Eigen::Vector3d(rho * std::cos(phi), rho * std::sin(phi), z) * radius;
}

/// A uniform point in the geodesic disc of radius D about H^2's origin (area element
/// R sinh(r/R) dr dphi: cosh(r/R) = 1 + u (cosh(D/R) - 1)).
Eigen::VectorXd in_hyperbolic_disc(Uniform& u, double radius, double D) {
  const double r = std::acosh(1 + u() * (std::cosh(D / radius) - 1)), phi = 2 * pi * u();
  return Eigen::Vector3d(std::sinh(r) * std::cos(phi), std::sinh(r) * std::sin(phi), std::cosh(r)) * radius;
}

/// A uniform point in the disc of radius D about E^2's origin (r = D sqrt(u)).
Eigen::VectorXd in_flat_disc(Uniform& u, double D) {
  const double r = D * std::sqrt(u()), phi = 2 * pi * u();
  return Eigen::Vector2d(r * std::cos(phi), r * std::sin(phi));
}

}  // namespace

TEST_CASE("shell volumes are the exact measure of S^n, H^n and E^n") {
  // The 8-point rule's remainder is below 1e-33 of each piece (analysis.cpp); what is left is
  // the rounding of sums of up to a few hundred terms: 1e-13 relative is 450 eps.
  const double R = 1.3;
  const SpaceSpec s2{SpaceKind::sphere, 2, R}, s3{SpaceKind::sphere, 3, R};
  const SpaceSpec h2{SpaceKind::hyperbolic, 2, R}, h3{SpaceKind::hyperbolic, 3, R};
  // S^2: 2 pi R^2 (cos(a/R) - cos(b/R)), as 4 pi R^2 sin((a+b)/2R) sin((b-a)/2R) without the
  // difference's cancellation; the whole S^3: 2 pi^2 R^3.
  for (const auto& [a, b] : {std::pair{0.0, 0.01}, std::pair{0.3, 0.7}, std::pair{2.5, pi * R}}) {
    const double exact = 4 * pi * R * R * std::sin((a + b) / (2 * R)) * std::sin((b - a) / (2 * R));
    CHECK(std::abs(sesi::analysis::shell_volume(s2, a, b) / exact - 1) < 1e-13);
  }
  CHECK(std::abs(sesi::analysis::total_volume(s2) / (4 * pi * R * R) - 1) < 1e-13);
  CHECK(std::abs(sesi::analysis::shell_volume(s3, 0, pi * R) / (2 * pi * pi * R * R * R) - 1) < 1e-13);
  // H^2's disc: 2 pi R^2 (cosh(D/R) - 1); H^3's ball: pi R^3 (sinh(2D/R) - 2D/R).
  for (const double D : {0.05, 1.0, 7.0}) {
    const double disc = 2 * pi * R * R * (std::cosh(D / R) - 1);
    CHECK(std::abs(sesi::analysis::total_volume(h2, D) / disc - 1) < 1e-13);
    const double ball = pi * R * R * R * (std::sinh(2 * D / R) - 2 * D / R);
    CHECK(std::abs(sesi::analysis::total_volume(h3, D) / ball - 1) < 1e-12);  // the closed form's own cancellation at D = 0.05: 1e-13
  }
  // The default r_max: the whole sphere for a few bodies, ten mean spacings for many.
  Uniform u(24);
  Eigen::MatrixXd few(3, 3), many(3, 10000);
  for (int b = 0; b < 3; ++b) few.col(b) = on_sphere(u, R);
  for (int b = 0; b < 10000; ++b) many.col(b) = on_sphere(u, 30.0);
  CHECK(sesi::analysis::default_rdf_max(s2, few) == pi * R);
  const double ten_spacings = 10 * std::sqrt(4 * pi * 900 / 10000);  // pow and Gamma: a few eps apart
  CHECK(std::abs(sesi::analysis::default_rdf_max(SpaceSpec{SpaceKind::sphere, 2, 30.0}, many) / ten_spacings - 1) < 1e-14);
  // The MSD's saturation on S^2 and S^3: R^2 (pi^2/2 - 2) and R^2 (pi^2/3 - 1/2).
  CHECK(std::abs(sesi::analysis::msd_saturation(s2) / (R * R * (pi * pi / 2 - 2)) - 1) < 1e-13);
  CHECK(std::abs(sesi::analysis::msd_saturation(s3) / (R * R * (pi * pi / 3 - 0.5)) - 1) < 1e-13);
}

TEST_CASE("ideal gas on S^2: g(r) = 1 over [0, pi R] (chi-squared, fixed seed)") {
  // Two independent uniform bodies per frame: each frame puts its one pair in bin k with
  // probability shell_k / area, so the unordered counts (counts / 2) are multinomial and
  // Pearson's statistic over the K bins, which cover [0, pi R], is chi-squared with K - 1 dof.
  const double R = 1.3;
  const int bins = 20, frames = 20000;
  Rdf rdf(SpaceSpec{SpaceKind::sphere, 2, R}, pi * R, bins);
  Uniform u(25);
  Eigen::MatrixXd X(3, 2);
  for (int f = 0; f < frames; ++f) {
    X.col(0) = on_sphere(u, R);
    X.col(1) = on_sphere(u, R);
    rdf.accumulate(X);
  }
  double chi2 = 0, pairs = 0;
  for (int k = 0; k < bins; ++k) {
    const double observed = rdf.counts()[k] / 2.0, expected = rdf.expected()[k] / 2;
    chi2 += (observed - expected) * (observed - expected) / expected;
    pairs += observed;
  }
  CHECK(pairs == frames);
  CHECK(chi2 < 36.19);  // chi-squared, 19 dof, 1 % critical value
  const std::vector<double> g = rdf.g();
  CHECK(std::abs(g[bins / 2] - 1) < 0.2);  // a middle bin: expected 1570 pairs, 5 sigma = 0.13
}

namespace {

/// The conservative chi-squared statistic of an open region's counts, 2 bodies uniform in the
/// region per frame. A frame adds (a + b) 1[d in bin k] to count k, a, b in {0, 1} saying
/// whether each body is a shell centre; (a + b)^2 <= 2 (a + b), so the count's variance about
/// the library's expectation is at most 2 x expected, and sum_k (count - expected)^2 /
/// (2 expected) is at most chi-squared with K dof (each term's mean <= 1; 1 pair per frame, so
/// the bins' counts covary negatively as in a multinomial).
double open_region_statistic(const Rdf& rdf) {
  double chi2 = 0;
  for (int k = 0; k < rdf.bins(); ++k) {
    const double d = rdf.counts()[k] - rdf.expected()[k];
    chi2 += d * d / (2 * rdf.expected()[k]);
  }
  return chi2;
}

}  // namespace

TEST_CASE("ideal gas in an H^2 disc and an E^2 disc: g(r) = 1 within r_max of the centres (chi-squared)") {
  // Bodies uniform in the disc of radius D. Only bodies at least r_max inside it are shell
  // centres: their whole shell lies in the disc, where the others are uniform at density
  // (N - 1) / area, so g = 1 at every r < r_max; shells reaching past the edge would be
  // partly empty (g < 1 by the edge's share), which is why they are not counted.
  const double R = 1.0, D = 2.0, r_max = 0.8;
  const int bins = 10, frames = 60000;
  for (const SpaceKind kind : {SpaceKind::hyperbolic, SpaceKind::euclidean}) {
    CAPTURE(static_cast<int>(kind));
    const bool hyperbolic = kind == SpaceKind::hyperbolic;
    Rdf rdf(SpaceSpec{kind, 2, R}, r_max, bins);
    const Region region{hyperbolic ? Eigen::VectorXd(Eigen::Vector3d(0, 0, R)) : Eigen::VectorXd(Eigen::Vector2d(0, 0)), D};
    Uniform u(26);
    Eigen::MatrixXd X(hyperbolic ? 3 : 2, 2);
    for (int f = 0; f < frames; ++f) {
      for (int b = 0; b < 2; ++b) X.col(b) = hyperbolic ? in_hyperbolic_disc(u, R, D) : in_flat_disc(u, D);
      rdf.accumulate(X, region);
    }
    // Expected counts: 40 (H^2) and 69 (E^2) in the first bin, thousands in the last.
    CHECK(rdf.expected()[0] > 30);
    CHECK(open_region_statistic(rdf) < 23.21);  // chi-squared, 10 dof, 1 % critical value
  }
}

TEST_CASE("g(r) through the neighbour cells counts exactly the pairs all pairs count") {
  Uniform u(27);
  const auto same = [](Rdf& cells, Rdf& all, const Eigen::MatrixXd& X, const std::optional<Region>& region) {
    cells.accumulate(X, region);
    all.accumulate_all_pairs(X, region);
    CHECK(cells.counts() == all.counts());
    CHECK(cells.expected() == all.expected());
    long total = 0;
    for (const auto c : cells.counts()) total += c;
    CHECK(total > 1000);  // the test sees many pairs
  };
  {
    const double R = 4.0;
    Eigen::MatrixXd X(3, 600);
    for (int b = 0; b < 600; ++b) X.col(b) = on_sphere(u, R);
    Rdf cells(SpaceSpec{SpaceKind::sphere, 2, R}, 1.5, 30), all(SpaceSpec{SpaceKind::sphere, 2, R}, 1.5, 30);
    same(cells, all, X, std::nullopt);
  }
  {
    // H^2: near the origin, and the same cluster boosted 12 radii out (read in a frame there).
    const double R = 1.0, D = 4.0;
    Eigen::MatrixXd X(3, 600);
    for (int b = 0; b < 600; ++b) X.col(b) = in_hyperbolic_disc(u, R, D);
    Rdf cells(SpaceSpec{SpaceKind::hyperbolic, 2, R}, 1.0, 25), all(SpaceSpec{SpaceKind::hyperbolic, 2, R}, 1.0, 25);
    same(cells, all, X, std::nullopt);
    const sesi::Hyperbolic<Eigen::Dynamic> chart(R, 2);
    Eigen::MatrixXd boost;
    chart.boost_to(Eigen::VectorXd(Eigen::Vector3d(std::sinh(12.0), 0, std::cosh(12.0))), boost);
    const Eigen::MatrixXd far = boost * X;
    Rdf far_cells(SpaceSpec{SpaceKind::hyperbolic, 2, R}, 1.0, 25), far_all(SpaceSpec{SpaceKind::hyperbolic, 2, R}, 1.0, 25);
    same(far_cells, far_all, far, std::nullopt);
  }
  {
    Eigen::MatrixXd X(3, 600);
    for (int b = 0; b < 600; ++b) X.col(b) = Eigen::Vector3d(8 * u(), 8 * u(), 8 * u());
    Rdf cells(SpaceSpec{SpaceKind::euclidean, 3, 1.0}, 1.2, 12), all(SpaceSpec{SpaceKind::euclidean, 3, 1.0}, 1.2, 12);
    same(cells, all, X, std::nullopt);
  }
}

TEST_CASE("MSD and VACF of bodies on geodesics at constant speed") {
  // On a great circle of S^2 at angular speed w, d(x(t0), x(t0 + t)) = R w t while R w t <= pi R,
  // then 2 pi R - R w t; the velocity carried along the circle (its own geodesic) is the
  // velocity there, so the VACF is the squared speed (R w)^2 at every lag short of antipodes. On
  // H^2's geodesic x = R (sinh wt, 0, cosh wt): MSD (R w t)^2 and VACF (R w)^2 at every lag.
  // Bounds: the points' and the distance's rounding, a few eps relative: 1e-12; on H^2 the
  // VACF's Minkowski products of vectors of size cosh(wt) cancel down to (R w)^2, so their
  // rounding is eps cosh^2(wt) relative: 4 eps cosh^2 of the last frame's wt, 2.9e-11.
  const double R = 1.7, w = 0.3, dt = 0.25;
  const int count = 80;
  for (const SpaceKind kind : {SpaceKind::sphere, SpaceKind::hyperbolic}) {
    CAPTURE(static_cast<int>(kind));
    sesi::analysis::Frames frames;
    frames.space = SpaceSpec{kind, 2, R};
    for (int k = 0; k < count; ++k) {
      const double s = w * k * dt;
      Eigen::MatrixXd x(3, 1), v(3, 1);
      if (kind == SpaceKind::sphere) {
        x.col(0) = Eigen::Vector3d(std::cos(s), std::sin(s), 0) * R;
        v.col(0) = Eigen::Vector3d(-std::sin(s), std::cos(s), 0) * (R * w);
      } else {
        x.col(0) = Eigen::Vector3d(std::sinh(s), 0, std::cosh(s)) * R;
        v.col(0) = Eigen::Vector3d(std::cosh(s), 0, std::sinh(s)) * (R * w);
      }
      frames.t.push_back(k * dt);
      frames.x.push_back(x);
      frames.v.push_back(v);
    }
    const auto m = sesi::analysis::msd(frames, count - 1);
    const auto c = sesi::analysis::vacf(frames, count - 1);
    REQUIRE(m.value.size() == static_cast<std::size_t>(count));
    for (int lag = 1; lag < count; ++lag) {
      CAPTURE(lag);
      const double t = lag * dt, arc = R * w * t;
      const bool wrapped = kind == SpaceKind::sphere && arc > pi * R;
      const double exact = wrapped ? (2 * pi * R - arc) * (2 * pi * R - arc) : arc * arc;
      CHECK(std::abs(m.value[lag] / exact - 1) < 1e-12);
      CHECK(m.samples[lag] == count - lag);
      const double last = std::cosh(w * (count - 1) * dt);
      const double vacf_bound = kind == SpaceKind::sphere ? 1e-12 : 4 * 0x1p-52 * last * last;
      if (std::abs(arc - pi * R) > 0.1) CHECK(std::abs(c.value[lag] / (R * R * w * w) - 1) < vacf_bound);
    }
  }
}
