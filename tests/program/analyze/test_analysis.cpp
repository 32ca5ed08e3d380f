// The observables library (src/analysis, docs/observables.md): the exact shell measure, g(r) = 1
// for an ideal gas on S^2, H^2 and E^2 by a chi-squared test at a fixed seed, the neighbour-cell
// counts equal to the all-pairs counts, and the MSD and VACF of bodies on known geodesics; on a
// periodic box and a compact surface (issue #26) the same, by the minimum image and the unwrapped
// positions, and the topology read from a run's files.
#include <doctest/doctest.h>

#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include <sesi/spaces/hyperbolic.hpp>
#include <sesi/topologies/hyperbolic_surface.hpp>
#include <sesi/topologies/periodic_box.hpp>

#include "analysis.hpp"
#include "errors.hpp"

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

// ---- on a quotient: a periodic box of E^n, a compact surface H^2/Gamma (issue #26) ---------------

namespace {

SpaceSpec box_space(std::vector<double> edges) {
  SpaceSpec s{SpaceKind::euclidean, static_cast<int>(edges.size()), 1.0};
  s.box = std::move(edges);
  return s;
}

SpaceSpec surface_space(int genus, double radius) {
  SpaceSpec s{SpaceKind::hyperbolic, 2, radius};
  s.genus = genus;
  return s;
}

/// A uniform point of the box [0, L_1) x ... x [0, L_n).
Eigen::VectorXd in_box(Uniform& u, const std::vector<double>& edges) {
  Eigen::VectorXd x(static_cast<Eigen::Index>(edges.size()));
  for (std::size_t k = 0; k < edges.size(); ++k) x(static_cast<Eigen::Index>(k)) = edges[k] * u();
  return x;
}

/// A uniform point of the surface's polygon D: uniform in the disc of the circumradius about the
/// origin (hyperbolic area measure, in_hyperbolic_disc), kept when it lies in D (rejection keeps
/// the uniform measure restricted to D).
Eigen::VectorXd in_polygon(Uniform& u, const sesi::HyperbolicSurface<double>& surface) {
  while (true) {
    const Eigen::Vector3d y = in_hyperbolic_disc(u, surface.radius(), surface.circumradius());
    if (surface.outside(y) == 0.0) return y;
  }
}

/// Pearson's statistic of two-body frames: the one unordered pair of each frame falls in bin k
/// with probability shell_k / V, or beyond r_max with the rest: a multinomial over bins + 1
/// categories, chi-squared with `bins` degrees of freedom. Exact on a quotient up to its largest
/// cutoff, where the ball about a body embeds in the quotient (the covering space's shell is
/// the quotient's).
double two_body_statistic(const Rdf& rdf, long frames) {
  double chi2 = 0, inside = 0, expected_inside = 0;
  for (int k = 0; k < rdf.bins(); ++k) {
    const double observed = rdf.counts()[k] / 2.0, expected = rdf.expected()[k] / 2;
    chi2 += (observed - expected) * (observed - expected) / expected;
    inside += observed;
    expected_inside += expected;
  }
  const double rest = static_cast<double>(frames) - inside, expected_rest = static_cast<double>(frames) - expected_inside;
  return chi2 + (rest - expected_rest) * (rest - expected_rest) / expected_rest;
}

}  // namespace

TEST_CASE("ideal gas on an E^2 box and a genus-2 surface: g(r) = 1 up to the largest cutoff (chi-squared)") {
  const int bins = 10;
  {
    const std::vector<double> edges{3.0, 4.0};
    const SpaceSpec space = box_space(edges);
    CHECK(sesi::analysis::max_cutoff(space) == 1.5);  // half the shorter edge
    CHECK(sesi::analysis::total_volume(space) == 12.0);
    const long frames = 20000;
    Rdf rdf(space, 1.5, bins);
    Uniform u(31);
    Eigen::MatrixXd X(2, 2);
    for (long f = 0; f < frames; ++f) {
      X.col(0) = in_box(u, edges);
      X.col(1) = in_box(u, edges);
      rdf.accumulate(X);
    }
    CHECK(rdf.centres() == 2 * frames);  // every body is a shell centre
    CHECK(rdf.expected()[0] > 200);      // pi 0.15^2 / 12 x 2 x 20000: 236 ordered pairs
    CHECK(two_body_statistic(rdf, frames) < 23.21);  // chi-squared, 10 dof, 1 % critical value
  }
  {
    const sesi::HyperbolicSurface<double> surface(2, 1.0);
    const SpaceSpec space = surface_space(2, 1.0);
    const double r_max = sesi::analysis::max_cutoff(space);
    CHECK(r_max == surface.max_cutoff());
    CHECK(std::abs(sesi::analysis::total_volume(space) / (4 * pi) - 1) < 1e-15);  // Gauss-Bonnet, 4 pi (g - 1) R^2
    const long frames = 40000;
    Rdf rdf(space, r_max, bins);
    Uniform u(32);
    Eigen::MatrixXd X(3, 2);
    for (long f = 0; f < frames; ++f) {
      X.col(0) = in_polygon(u, surface);
      X.col(1) = in_polygon(u, surface);
      rdf.accumulate(X);
    }
    CHECK(rdf.centres() == 2 * frames);
    CHECK(rdf.expected()[0] > 30);  // 2 pi (cosh(r_max / 10) - 1) / 4 pi x 2 x 40000
    CHECK(two_body_statistic(rdf, frames) < 23.21);  // chi-squared, 10 dof, 1 % critical value
  }
}

TEST_CASE("g(r) on a quotient: the ghost images count exactly the minimum-image pairs of all pairs") {
  Uniform u(33);
  const auto same = [](const SpaceSpec& space, double r_max, const Eigen::MatrixXd& X) {
    Rdf cells(space, r_max, 20), all(space, r_max, 20);
    cells.accumulate(X);
    all.accumulate_all_pairs(X);
    CHECK(cells.counts() == all.counts());
    CHECK(cells.expected() == all.expected());
    long total = 0;
    for (const auto c : cells.counts()) total += c;
    CHECK(total > 1000);  // the test sees many pairs
    return cells.counts();
  };
  for (const std::vector<double>& edges : {std::vector<double>{7.0, 9.0}, std::vector<double>{5.0, 6.0, 7.0}}) {
    CAPTURE(edges.size());
    const SpaceSpec space = box_space(edges);
    const auto n = static_cast<Eigen::Index>(edges.size());
    Eigen::MatrixXd X(n, 500);
    for (int b = 0; b < 500; ++b) X.col(b) = in_box(u, edges);
    const auto counts = same(space, sesi::analysis::max_cutoff(space), X);
    same(space, 1.1, X);
    // The same bodies given in other cells of the lattice: reduced into the box, the same pairs.
    Eigen::MatrixXd moved = X;
    for (int b = 0; b < 500; b += 3) moved(b % n, b) += (b % 2 ? 3.0 : -2.0) * edges[static_cast<std::size_t>(b % n)];
    Rdf again(space, sesi::analysis::max_cutoff(space), 20);
    again.accumulate(moved);
    CHECK(again.counts() == counts);
  }
  for (const auto& shape : {std::pair{2, 2.0}, std::pair{3, 1.5}}) {
    // (not a structured binding: CAPTURE's lambda cannot capture one under Clang 14)
    const int genus = shape.first;
    const double radius = shape.second;
    CAPTURE(genus);
    const sesi::HyperbolicSurface<double> surface(genus, radius);
    const SpaceSpec space = surface_space(genus, radius);
    Eigen::MatrixXd X(3, 300);  // all pairs try 1 + 4g (4g - 2) images each: few bodies suffice
    for (int b = 0; b < 300; ++b) X.col(b) = in_polygon(u, surface);
    same(space, sesi::analysis::max_cutoff(space), X);
    same(space, 0.5 * sesi::analysis::max_cutoff(space), X);
  }
}

TEST_CASE("g(r) on a quotient refuses r_max beyond the largest cutoff, naming it") {
  const auto message = [](const SpaceSpec& space, double r_max) {
    try {
      Rdf rdf(space, r_max, 10);
    } catch (const sesi::program::InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  const std::string box = message(box_space({3.0, 4.0}), 1.6);
  CHECK(box.find("--rdf-max") != std::string::npos);
  CHECK(box.find("the largest allowed cutoff is 1.5") != std::string::npos);
  const SpaceSpec surface = surface_space(2, 1.0);
  const double top = sesi::analysis::max_cutoff(surface);
  CHECK(message(surface, top * (1 + 1e-12)).find("the largest allowed cutoff is " + sesi::program::format_number(top)) !=
        std::string::npos);
  CHECK(message(surface, top).empty());
}

TEST_CASE("MSD on a box and on a genus-2 surface: bodies moving freely across sides have MSD (v t)^2") {
  const int count = 120;
  const double dt = 0.5;
  {
    // Straight lines u(t) = u0 + v t in E^2, kept in the box by PeriodicBox::reduce with their
    // image counts, as a run keeps them.
    const std::vector<double> edges{3.0, 4.0};
    const sesi::PeriodicBox<double, Eigen::Dynamic> box(Eigen::Vector2d(3.0, 4.0));
    sesi::analysis::Frames frames;
    frames.space = box_space(edges);
    const Eigen::Vector2d v0(0.7, -0.45), v1(-0.2, 1.3), u0(0.5, 3.9), u1(2.9, 0.1);
    double largest = 0;  // the largest unwrapped coordinate
    for (int k = 0; k < count; ++k) {
      Eigen::MatrixXd x(2, 2);
      sesi::analysis::ImageCounts n = sesi::analysis::ImageCounts::Zero(2, 2);
      x.col(0) = u0 + v0 * (k * dt);
      x.col(1) = u1 + v1 * (k * dt);
      largest = std::max(largest, x.cwiseAbs().maxCoeff());
      for (int b = 0; b < 2; ++b) {
        auto col = x.col(b);
        box.reduce(col, n.col(b));
      }
      frames.t.push_back(k * dt);
      frames.x.push_back(x);
      frames.images.push_back(n);
    }
    CHECK(frames.images.back().cwiseAbs().maxCoeff() >= 15);  // many crossings
    const auto m = sesi::analysis::msd(frames, count - 1);
    // Each coordinate x = u - L n carries the rounding of u and of the reduction, 2 eps |u| at
    // most, so each unwrapped difference (x_p - x_o) + L (n_p - n_o) is within 8 eps U of the
    // exact one (U the largest coordinate); d^2 is then within 2 sqrt(2) 8 eps U / d relative
    // (plus its square), d >= the smaller speed x dt at lag 1.
    const double d_min = std::min(v0.norm(), v1.norm()) * dt;
    const double bound = 2 * std::sqrt(2.0) * 8 * 0x1p-52 * largest / d_min;
    for (int lag = 1; lag < count; ++lag) {
      CAPTURE(lag);
      const double t = lag * dt;
      const double exact = (v0.squaredNorm() + v1.squaredNorm()) * t * t / 2;
      CHECK(std::abs(m.value[lag] / exact - 1) < bound);
    }
    // Without the counts there is no MSD on a box.
    frames.images.clear();
    CHECK_THROWS_AS(sesi::analysis::msd(frames), sesi::program::InputError);
  }
  {
    // A geodesic of H^2 at speed R w, u(t) = R (sinh(wt + s0) cos a - ..., cosh(wt + s0)) through a
    // point off the origin (a boost B), kept in the polygon by reduce with its word W (u = W x),
    // as a run keeps it (HyperbolicSurface::append_inverse); its velocity carried along.
    const double R = 1.0, w = 0.1;
    const sesi::HyperbolicSurface<double> surface(2, R);
    sesi::analysis::Frames frames;
    frames.space = surface_space(2, R);
    const sesi::Hyperbolic<Eigen::Dynamic> chart(R, 2);
    Eigen::MatrixXd boost;
    chart.boost_to(Eigen::VectorXd(Eigen::Vector3d(0.3, -0.4, std::sqrt(1 + 0.25) * R)), boost);
    const double angle = 0.7;
    const Eigen::Vector3d direction(std::cos(angle), std::sin(angle), 0);
    int crossings = 0;
    for (int k = 0; k < count; ++k) {
      const double s = w * k * dt - 3.0;
      Eigen::Vector3d u = boost * (direction * std::sinh(s) + Eigen::Vector3d(0, 0, std::cosh(s))) * R;
      Eigen::Vector3d v = boost * (direction * std::cosh(s) + Eigen::Vector3d(0, 0, std::sinh(s))) * (R * w);
      sesi::HyperbolicSurface<double>::Word applied, word;
      surface.reduce(u, applied);
      for (const auto a : applied) v = (surface.generator(a) * v).eval();
      surface.append_inverse(word, applied);
      if (!frames.words.empty() && frames.words.back()[0] != word) ++crossings;
      frames.t.push_back(k * dt);
      frames.x.emplace_back(Eigen::MatrixXd(u));
      frames.v.emplace_back(Eigen::MatrixXd(v));
      frames.words.push_back({word});
    }
    CHECK(crossings >= 3);  // the body crossed several sides
    const auto m = sesi::analysis::msd(frames, count - 1);
    const auto c = sesi::analysis::vacf(frames, count - 1);
    // At lag t the later point carried next to the earlier one, W_o^{-1} W_p x_p, lies within
    // arc + r_c of the origin (x_o is in D, within the circumradius r_c), so it and every product
    // of the chain that makes it (u, the reduction's generators, W_o^{-1} W_p) have entries of
    // size S = R cosh((arc + r_c) / R), each rounding to a few eps of S: the distance is within
    // 8 eps S of arc, so d^2 within 16 eps S / arc relative. The VACF's Minkowski products of
    // vectors of size S cancel down to (R w)^2: within 16 eps (S / R)^2 relative.
    for (int lag = 1; lag < count; ++lag) {
      CAPTURE(lag);
      const double arc = R * w * lag * dt, size = R * std::cosh((arc + surface.circumradius()) / R);
      CHECK(std::abs(m.value[lag] / (arc * arc) - 1) < 16 * 0x1p-52 * size / arc);
      CHECK(std::abs(c.value[lag] / (R * R * w * w) - 1) < 16 * 0x1p-52 * (size / R) * (size / R));
    }
    frames.words.clear();
    CHECK_THROWS_AS(sesi::analysis::msd(frames), sesi::program::InputError);
  }
}

TEST_CASE("a run's box or genus, image counts and words are read from summary.json and trajectory.csv") {
  namespace fs = std::filesystem;
  const fs::path dir = fs::temp_directory_path() / ("sesi-test-analysis-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const auto write = [&](const std::string& name, const std::string& text) { std::ofstream(dir / name) << text; };
  // E^1 box of edge 2: one body at x = 1.5 with image count -1, then 0.5 with count 3.
  write("summary.json",
        R"({"complete": true, "space": {"kind": "euclidean", "dim": 1, "box": [2.0], "max_cutoff": 1.0},)"
        R"( "bodies": 1, "trajectory": "trajectory.csv", "masses": [2.0]})");
  write("trajectory.csv", "t,b1_q1,b1_p1,b1_x1,b1_n1\n0,1.5,0.5,1.5,-1\n1,0.5,0.5,0.5,3\n");
  {
    const auto info = sesi::analysis::read_run_info(dir);
    CHECK(info.space.box == std::vector<double>{2.0});
    const auto frames = sesi::analysis::read_frames(dir, info, {});
    REQUIRE(frames.images.size() == 2);
    CHECK(frames.images[0](0, 0) == -1);
    CHECK(frames.images[1](0, 0) == 3);
    const auto m = sesi::analysis::msd(frames, 1);
    CHECK(m.value[1] == 49.0);  // (0.5 + 2 x 3) - (1.5 - 2) = 7: exact in binary
  }
  // Genus 2, R = 1: the origin with the identity, then the same point with the word g_0 g_5
  // ("1.6"): the body's unwrapped point moved from o to g_0 g_5 o.
  write("summary.json",
        R"({"complete": true, "space": {"kind": "hyperbolic", "dim": 2, "radius": 1.0, "genus": 2},)"
        R"( "bodies": 1, "trajectory": "trajectory.csv"})");
  write("trajectory.csv",
        "t,b1_q1,b1_q2,b1_p1,b1_p2,b1_x1,b1_x2,b1_x3,b1_u1,b1_u2,b1_u3,b1_word\n"
        "0,0,0,0,0,0,0,1,0,0,1,e\n1,0,0,0,0,0,0,1,0,0,1,1.6\n");
  {
    const auto info = sesi::analysis::read_run_info(dir);
    CHECK(info.space.genus == 2);
    const auto frames = sesi::analysis::read_frames(dir, info, {});
    REQUIRE(frames.words.size() == 2);
    CHECK(frames.words[1][0] == sesi::analysis::Word{0, 5});
    CHECK(sesi::analysis::word_text(frames.words[1][0]) == "1.6");
    const sesi::HyperbolicSurface<double> surface(2, 1.0);
    const Eigen::Vector3d o(0, 0, 1), moved = surface.element({0, 5}) * o;
    const double exact = std::acosh(moved(2));  // d(o, y) = acosh(y_0 / R) from the origin
    const auto m = sesi::analysis::msd(frames, 1);
    CHECK(std::abs(std::sqrt(m.value[1]) / exact - 1) < 1e-13);  // acosh of entries ~30: a few eps of each product
  }
  // A word that is not one: one line naming it.
  write("trajectory.csv",
        "t,b1_q1,b1_q2,b1_p1,b1_p2,b1_x1,b1_x2,b1_x3,b1_u1,b1_u2,b1_u3,b1_word\n0,0,0,0,0,0,0,1,0,0,1,9\n");
  CHECK_THROWS_AS(sesi::analysis::read_frames(dir, sesi::analysis::read_run_info(dir), {}), sesi::program::InputError);
  fs::remove_all(dir);
}
