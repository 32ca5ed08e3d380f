#include "analysis.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <variant>

#include <sesi/neighbours.hpp>
#include <sesi/parallel.hpp>
#include <sesi/spaces/euclidean.hpp>
#include <sesi/spaces/hyperbolic.hpp>
#include <sesi/spaces/sphere.hpp>

#include "errors.hpp"

namespace sesi::analysis {

namespace {

constexpr double nan = std::numeric_limits<double>::quiet_NaN();
constexpr double pi = std::numbers::pi;

/// The 8-point Gauss-Legendre rule on [-1, 1] (Abramowitz and Stegun, table 25.4): exact for
/// polynomials of degree <= 15.
constexpr std::array<double, 4> gl_node = {0.18343464249564980494, 0.52553240991632898582, 0.79666647741362673959,
                                           0.96028985649753623168};
constexpr std::array<double, 4> gl_weight = {0.36268378337836198297, 0.31370664587788728734, 0.22238103445337447054,
                                             0.10122853629037625915};

/// The shell's radial density s_R(s)^{n-1} (without Omega_{n-1}).
double radial_density(const SpaceSpec& space, double s) {
  const int m = space.dim - 1;
  if (m == 0) return 1.0;
  const double r = space.radius;
  switch (space.kind) {
    case SpaceKind::sphere:
      return std::pow(r * std::sin(s / r), m);
    case SpaceKind::hyperbolic:
      return std::pow(r * std::sinh(s / r), m);
    case SpaceKind::euclidean:
      break;
  }
  return std::pow(s, m);
}

/// int_a^b weight(s) radial_density(s) ds by the 8-point rule on pieces of width at most
/// R / (4 max(1, n - 1)). The rule's remainder on a piece of width h is
/// h^17 (8!)^4 / (17 (16!)^3) |f^(16)| (Abramowitz and Stegun 25.4.30), and sin^m, sinh^m are
/// sums of exponentials e^{+-k s/R}, k <= m, so |f^(16)| <= (m/R)^16 max|f| (times weight's
/// growth): with h = R / 4m the remainder is below 1e-33 h max|f| on each piece, far below
/// the rounding of the sum.
template <class Weight>
double radial_integral(const SpaceSpec& space, double a, double b, Weight&& weight) {
  if (!(b > a)) return 0.0;
  const double scale = space.kind == SpaceKind::euclidean ? std::max(b, 1.0) : space.radius;
  const double width = scale / (4.0 * std::max(1, space.dim - 1));
  const long pieces = std::max(1L, static_cast<long>(std::ceil((b - a) / width)));
  const double h = (b - a) / static_cast<double>(pieces);
  double total = 0.0;
  for (long k = 0; k < pieces; ++k) {
    const double mid = a + (static_cast<double>(k) + 0.5) * h, half = h / 2;
    double piece = 0.0;
    for (std::size_t j = 0; j < gl_node.size(); ++j) {
      for (const double sign : {-1.0, 1.0}) {
        const double s = mid + sign * half * gl_node[j];
        piece += gl_weight[j] * weight(s) * radial_density(space, s);
      }
    }
    total += piece * half;
  }
  return total;
}

using Charts = std::variant<sesi::Sphere<Eigen::Dynamic>, sesi::Hyperbolic<Eigen::Dynamic>,
                            sesi::Euclidean<Eigen::Dynamic>>;

Charts chart_of(const SpaceSpec& space) {
  switch (space.kind) {
    case SpaceKind::sphere:
      return sesi::Sphere<Eigen::Dynamic>(space.radius, space.dim);
    case SpaceKind::hyperbolic:
      return sesi::Hyperbolic<Eigen::Dynamic>(space.radius, space.dim);
    case SpaceKind::euclidean:
      break;
  }
  return sesi::Euclidean<Eigen::Dynamic>(space.dim);
}

/// Minkowski product (time-like coordinate last) or Euclidean dot product of two columns.
double inner(const SpaceSpec& space, const double* u, const double* w, int a) {
  double s = 0.0;
  for (int k = 0; k < a; ++k) s += u[k] * w[k];
  if (space.kind == SpaceKind::hyperbolic) s -= 2.0 * u[a - 1] * w[a - 1];
  return s;
}

/// The distance of two embedding points given as arrays of a coordinates.
double distance_of(const SpaceSpec& space, const double* x, const double* y, int a) {
  const double r = space.radius;
  switch (space.kind) {
    case SpaceKind::sphere: {
      // 2R atan2(|x - y|, |x + y|): accurate at all angles (sphere.hpp).
      double minus = 0.0, plus = 0.0;
      for (int k = 0; k < a; ++k) {
        minus += (x[k] - y[k]) * (x[k] - y[k]);
        plus += (x[k] + y[k]) * (x[k] + y[k]);
      }
      return 2.0 * r * std::atan2(std::sqrt(minus), std::sqrt(plus));
    }
    case SpaceKind::hyperbolic: {
      // By radii and directions (Hyperbolic::polar_distance): eps sinh(rho) far out, where the
      // chord would lose eps e^{2 rho}.
      const int n = a - 1;
      double sx = 0.0, sy = 0.0;
      for (int k = 0; k < n; ++k) {
        sx += x[k] * x[k];
        sy += y[k] * y[k];
      }
      sx = std::sqrt(sx) / r;
      sy = std::sqrt(sy) / r;
      double h = 0.0;
      if (sx > 0.0 && sy > 0.0) {
        for (int k = 0; k < n; ++k) {
          const double u = x[k] / (r * sx) - y[k] / (r * sy);
          h += u * u;
        }
        h /= 2.0;
      }
      const double half = std::sinh((std::asinh(sx) - std::asinh(sy)) / 2.0);
      return 2.0 * r * std::asinh(std::sqrt(half * half + sx * sy * h / 2.0));
    }
    case SpaceKind::euclidean:
      break;
  }
  double s = 0.0;
  for (int k = 0; k < a; ++k) s += (x[k] - y[k]) * (x[k] - y[k]);
  return std::sqrt(s);
}

double transported_dot_of(const SpaceSpec& space, const double* x, const double* v, const double* y, const double* w,
                          int a) {
  const double vw = inner(space, v, w, a);
  if (space.kind == SpaceKind::euclidean) return vw;
  const double r = space.radius;
  // With unit points x^ = x/R, y^ = y/R the transport along the geodesic from x to y is
  //   S^n: P v = v - (y^.v) / (1 + x^.y^) (x^ + y^),   H^n: P v = v + <y^,v> / (1 - <x^,y^>) (x^ + y^)
  // (it keeps <P v, y> = 0 and |P v| = |v|, and is the rotation or boost in the plane of x and
  // y that takes x to y: Levi-Civita transport along their geodesic); as w is tangent at y,
  // <P v, w> = <v, w> -+ (y^.v)(x^.w) / (1 +- x^.y^). The denominators without cancellation:
  // S^n: 1 + x^.y^ = |x^ + y^|^2 / 2, zero only at antipodes; H^n: 1 - <x^,y^> = 2 + |x^ - y^|_L^2 / 2 >= 2.
  const double yv = inner(space, y, v, a) / r, xw = inner(space, x, w, a) / r;
  double chord = 0.0;
  if (space.kind == SpaceKind::sphere) {
    for (int k = 0; k < a; ++k) chord += (x[k] + y[k]) * (x[k] + y[k]);
    const double denominator = chord / (2.0 * r * r);
    if (!(denominator > 0.0)) return nan;  // antipodes: no unique geodesic
    return vw - yv * xw / denominator;
  }
  for (int k = 0; k < a; ++k) chord += (x[k] - y[k]) * (x[k] - y[k]);
  chord -= 2.0 * (x[a - 1] - y[a - 1]) * (x[a - 1] - y[a - 1]);
  return vw + yv * xw / (2.0 + chord / (2.0 * r * r));
}

std::string number(double v) { return program::format_number(v); }

}  // namespace

// ---- the space's measure ---------------------------------------------------------------------

double unit_sphere_area(int k) {
  const double half = (k + 1) / 2.0;
  return 2.0 * std::pow(pi, half) / std::tgamma(half);
}

double shell_volume(const SpaceSpec& space, double a, double b) {
  a = std::max(a, 0.0);
  if (space.kind == SpaceKind::sphere) b = std::min(b, pi * space.radius);
  if (!(b > a)) return 0.0;
  const double omega = unit_sphere_area(space.dim - 1);
  if (space.kind == SpaceKind::euclidean) {
    const int n = space.dim;
    return omega * (std::pow(b, n) - std::pow(a, n)) / n;
  }
  return omega * radial_integral(space, a, b, [](double) { return 1.0; });
}

double total_volume(const SpaceSpec& space, double ball_radius) {
  if (space.kind == SpaceKind::sphere) return unit_sphere_area(space.dim) * std::pow(space.radius, space.dim);
  return shell_volume(space, 0.0, ball_radius);
}

double msd_saturation(const SpaceSpec& space) {
  if (space.kind != SpaceKind::sphere) return nan;
  const double end = pi * space.radius;
  return radial_integral(space, 0.0, end, [](double s) { return s * s; }) /
         radial_integral(space, 0.0, end, [](double) { return 1.0; });
}

double distance(const SpaceSpec& space, const Eigen::Ref<const Eigen::VectorXd>& x,
                const Eigen::Ref<const Eigen::VectorXd>& y) {
  const Eigen::VectorXd xc = x, yc = y;
  return distance_of(space, xc.data(), yc.data(), static_cast<int>(xc.size()));
}

double transported_dot(const SpaceSpec& space, const Eigen::Ref<const Eigen::VectorXd>& x,
                       const Eigen::Ref<const Eigen::VectorXd>& v, const Eigen::Ref<const Eigen::VectorXd>& y,
                       const Eigen::Ref<const Eigen::VectorXd>& w) {
  const Eigen::VectorXd xc = x, vc = v, yc = y, wc = w;
  return transported_dot_of(space, xc.data(), vc.data(), yc.data(), wc.data(), static_cast<int>(xc.size()));
}

// ---- g(r) ----------------------------------------------------------------------------------------

Region bounding_region(const SpaceSpec& space, const Eigen::MatrixXd& X) {
  Region region;
  const int a = static_cast<int>(X.rows());
  const int n = static_cast<int>(X.cols());
  if (n == 0) return region;
  Eigen::VectorXd sum = X.rowwise().sum();
  if (space.kind == SpaceKind::hyperbolic) {
    // The Minkowski sum of points on the upper sheet is time-like; scaled onto the hyperboloid
    // it is the centre of mass of the bodies seen from the space's symmetries.
    const double norm2 = -inner(space, sum.data(), sum.data(), a);
    region.center = sum * (space.radius / std::sqrt(norm2));
  } else {
    region.center = sum / static_cast<double>(n);
  }
  for (int b = 0; b < n; ++b) {
    region.radius = std::max(region.radius, distance_of(space, region.center.data(), X.col(b).data(), a));
  }
  return region;
}

double default_rdf_max(const SpaceSpec& space, const Eigen::MatrixXd& first_frame) {
  double top = pi * space.radius, volume = total_volume(space);
  if (space.kind != SpaceKind::sphere) {
    const double extent = bounding_region(space, first_frame).radius;
    top = extent / 4;
    volume = total_volume(space, extent);
  }
  if (!(top > 0.0)) {
    throw program::InputError(program::Origin{}, "--rdf-max", "the bodies have no extent to take a default from: give a distance");
  }
  // Ten mean spacings (V/N)^{1/n} at most: the shells hold O(1) bodies each, so a frame costs
  // O(N) through the cells however many bodies there are.
  const double n = static_cast<double>(std::max<Eigen::Index>(first_frame.cols(), 1));
  return std::min(top, 10.0 * std::pow(volume / n, 1.0 / space.dim));
}

struct Rdf::Frame {
  Eigen::MatrixXd points;    ///< the bodies (on H^n far out: in a frame at the first body)
  std::vector<char> centre;  ///< body i's shell lies in the region
  int centres = 0;
  double volume = 0.0;       ///< the region's volume
};

Rdf::Rdf(SpaceSpec space, double r_max, int bins) : space_(space), r_max_(r_max), bins_(bins) {
  const double top = space.kind == SpaceKind::sphere ? pi * space.radius : std::numeric_limits<double>::infinity();
  if (!(r_max > 0.0 && r_max <= top)) {
    throw program::InputError(program::Origin{}, "--rdf-max",
                              "expected a distance in (0, " +
                                  (space.kind == SpaceKind::sphere ? "pi R = " + number(top) : std::string("inf")) +
                                  "], got " + number(r_max));
  }
  if (bins < 1 || bins > 1000000) {
    throw program::InputError(program::Origin{}, "--bins", "expected 1 to 1000000 bins, got " + std::to_string(bins));
  }
  const std::vector<double> e = edges();
  for (int k = 0; k < bins; ++k) shell_.push_back(shell_volume(space, e[static_cast<std::size_t>(k)], e[static_cast<std::size_t>(k) + 1]));
  counts_.assign(static_cast<std::size_t>(bins), 0);
  expected_.assign(static_cast<std::size_t>(bins), 0.0);
}

std::vector<double> Rdf::edges() const {
  std::vector<double> e(static_cast<std::size_t>(bins_) + 1);
  for (int k = 0; k <= bins_; ++k) e[static_cast<std::size_t>(k)] = r_max_ * k / bins_;
  return e;
}

std::vector<double> Rdf::centers() const {
  const std::vector<double> e = edges();
  std::vector<double> c(static_cast<std::size_t>(bins_));
  for (std::size_t k = 0; k < c.size(); ++k) c[k] = (e[k] + e[k + 1]) / 2;
  return c;
}

std::vector<double> Rdf::g() const {
  std::vector<double> out(static_cast<std::size_t>(bins_));
  for (std::size_t k = 0; k < out.size(); ++k) {
    out[k] = expected_[k] > 0.0 ? static_cast<double>(counts_[k]) / expected_[k] : nan;
  }
  return out;
}

Rdf::Frame Rdf::prepare(const Eigen::MatrixXd& X, const std::optional<Region>& given) const {
  Frame f;
  const int n = static_cast<int>(X.cols());
  f.centre.assign(static_cast<std::size_t>(n), 1);
  if (space_.kind == SpaceKind::sphere) {
    f.points = X;
    f.centres = n;
    f.volume = total_volume(space_);
    return f;
  }
  std::optional<Region> region = given;
  if (space_.kind == SpaceKind::hyperbolic && n > 0 && X(X.rows() - 1, 0) / space_.radius > std::cosh(2.0)) {
    // Far out: the bodies (and a given centre) read into a frame at the first body (to_frame,
    // no cancellation), so that distances and the index see a cluster near the origin.
    const sesi::Hyperbolic<Eigen::Dynamic> chart(space_.radius, space_.dim);
    Eigen::MatrixXd frame;
    Eigen::VectorXd point;
    chart.boost_to(Eigen::VectorXd(X.col(0)), frame);
    f.points.resize(X.rows(), n);
    for (int b = 0; b < n; ++b) {
      chart.to_frame(frame, Eigen::VectorXd(X.col(b)), point);
      f.points.col(b) = point;
    }
    if (region) {
      chart.to_frame(frame, Eigen::VectorXd(region->center), point);
      region->center = point;
    }
  } else {
    f.points = X;
  }
  if (!region) region = bounding_region(space_, f.points);
  const int a = static_cast<int>(X.rows());
  f.volume = total_volume(space_, region->radius);
  f.centres = 0;
  for (int b = 0; b < n; ++b) {
    const double d = distance_of(space_, region->center.data(), f.points.col(b).data(), a);
    f.centre[static_cast<std::size_t>(b)] = d <= region->radius - r_max_;
    f.centres += f.centre[static_cast<std::size_t>(b)];
  }
  return f;
}

void Rdf::add(double d) {
  if (!(d < r_max_)) return;
  const auto k = std::min(static_cast<std::size_t>(d / r_max_ * bins_), static_cast<std::size_t>(bins_) - 1);
  ++counts_[k];
}

void Rdf::accumulate(const Eigen::MatrixXd& X, const std::optional<Region>& region) {
  const Frame f = prepare(X, region);
  const int n = static_cast<int>(X.cols());
  const int a = static_cast<int>(X.rows());
  if (n >= 2 && f.centres > 0) {
    NeighbourLists lists;
    std::visit(
        [&](const auto& chart) {
          using Chart = std::remove_cvref_t<decltype(chart)>;
          NeighbourIndex<Chart> index;
          // Every pair closer than r_max is a candidate: the index's chord test is exact up to
          // rounding, so its reach is widened by 1e-6 relative and the distance decides.
          index.build(chart, f.points, r_max_ * (1 + 1e-6), lists);
        },
        chart_of(space_));
    for (int i = 0; i < n; ++i) {
      if (!f.centre[static_cast<std::size_t>(i)]) continue;
      for (int k = lists.begin(i); k < lists.end(i); ++k) {
        const int j = lists.index[static_cast<std::size_t>(k)];
        add(distance_of(space_, f.points.col(i).data(), f.points.col(j).data(), a));
      }
    }
  }
  for (int k = 0; k < bins_; ++k) {
    if (n >= 2) expected_[static_cast<std::size_t>(k)] += f.centres * (n - 1.0) * shell_[static_cast<std::size_t>(k)] / f.volume;
  }
  ++frames_;
  centres_ += f.centres;
}

void Rdf::accumulate_all_pairs(const Eigen::MatrixXd& X, const std::optional<Region>& region) {
  const Frame f = prepare(X, region);
  const int n = static_cast<int>(X.cols());
  const int a = static_cast<int>(X.rows());
  for (int i = 0; i < n; ++i) {
    if (!f.centre[static_cast<std::size_t>(i)]) continue;
    for (int j = 0; j < n; ++j) {
      if (j != i) add(distance_of(space_, f.points.col(i).data(), f.points.col(j).data(), a));
    }
  }
  for (int k = 0; k < bins_; ++k) {
    if (n >= 2) expected_[static_cast<std::size_t>(k)] += f.centres * (n - 1.0) * shell_[static_cast<std::size_t>(k)] / f.volume;
  }
  ++frames_;
  centres_ += f.centres;
}

// ---- dynamics ----------------------------------------------------------------------------------

namespace {

/// <f(frame o, frame o + lag, body b)> over origins o and bodies b, for each lag; each lag's sum
/// runs in one fixed order (origins, then bodies), so the result does not depend on threads.
template <class F>
Correlation correlate(const Frames& frames, long max_lag, F&& f) {
  Correlation out;
  const long count = static_cast<long>(frames.x.size());
  const int n = frames.bodies();
  if (count == 0) return out;
  if (max_lag < 0) max_lag = count / 2;
  max_lag = std::min(max_lag, count - 1);
  const auto lags = static_cast<std::size_t>(max_lag) + 1;
  out.lag_time.resize(lags);
  out.value.assign(lags, 0.0);
  out.samples.assign(lags, 0);
  out.per_body_last.assign(static_cast<std::size_t>(n), 0.0);
  sesi::parallel::for_each(static_cast<int>(lags), [&](int lag) {
    double sum = 0.0;
    long samples = 0;
    for (long o = 0; o + lag < count; ++o) {
      for (int b = 0; b < n; ++b) {
        const double value = f(o, o + lag, b);
        if (std::isnan(value)) continue;  // S^n transport at exact antipodes
        sum += value;
        ++samples;
      }
    }
    out.lag_time[static_cast<std::size_t>(lag)] = frames.t[static_cast<std::size_t>(lag)] - frames.t.front();
    out.value[static_cast<std::size_t>(lag)] = samples > 0 ? sum / static_cast<double>(samples) : nan;
    out.samples[static_cast<std::size_t>(lag)] = samples;
  });
  for (int b = 0; b < n; ++b) {
    double sum = 0.0;
    long samples = 0;
    for (long o = 0; o + max_lag < count; ++o) {
      const double value = f(o, o + max_lag, b);
      if (std::isnan(value)) continue;
      sum += value;
      ++samples;
    }
    out.per_body_last[static_cast<std::size_t>(b)] = samples > 0 ? sum / static_cast<double>(samples) : nan;
  }
  return out;
}

}  // namespace

Correlation msd(const Frames& frames, long max_lag) {
  const int a = frames.x.empty() ? 0 : static_cast<int>(frames.x.front().rows());
  return correlate(frames, max_lag, [&](long o, long p, int b) {
    const double d = distance_of(frames.space, frames.x[static_cast<std::size_t>(o)].col(b).data(),
                                 frames.x[static_cast<std::size_t>(p)].col(b).data(), a);
    return d * d;
  });
}

Correlation vacf(const Frames& frames, long max_lag) {
  if (frames.v.size() != frames.x.size()) {
    throw program::InputError("the velocity autocorrelation needs the velocities (the bodies' masses are unknown)");
  }
  const int a = frames.x.empty() ? 0 : static_cast<int>(frames.x.front().rows());
  return correlate(frames, max_lag, [&](long o, long p, int b) {
    const auto so = static_cast<std::size_t>(o), sp = static_cast<std::size_t>(p);
    return transported_dot_of(frames.space, frames.x[so].col(b).data(), frames.v[so].col(b).data(),
                              frames.x[sp].col(b).data(), frames.v[sp].col(b).data(), a);
  });
}

}  // namespace sesi::analysis
