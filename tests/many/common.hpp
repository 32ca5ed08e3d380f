// Many-body scenes of the neighbour-index and thread tests (tests/many/*.cpp): bodies at a fixed
// density on S^n, H^n (near the chart's origin or far from it) and E^n, with random tangent
// velocities, built from a seeded generator so that every run sees the same scene.
#pragma once

#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>
#include <stdexcept>
#include <string>

#include <Eigen/Core>

#include <sesi/config.hpp>
#include <sesi/parallel.hpp>
#include <sesi/potentials.hpp>
#include <sesi/spaces/euclidean.hpp>
#include <sesi/spaces/hyperbolic.hpp>
#include <sesi/spaces/sphere.hpp>
#include <sesi/state.hpp>
#include <sesi/system.hpp>

namespace manytest {

struct CheckFailure : std::runtime_error {
  using std::runtime_error::runtime_error;
};
[[noreturn]] inline void throwing_handler(const char* expr, const char* what, const char* file, int line) {
  throw CheckFailure(std::string(what) + " (" + expr + ") at " + file + ":" + std::to_string(line));
}
inline const bool check_handler_installed = (sesi::set_check_handler(&throwing_handler), true);

/// A uniform number in [0, 1) from the generator's bits (std::uniform_real_distribution differs
/// between standard libraries).
inline double uniform(std::mt19937_64& rng) { return static_cast<double>(rng() >> 11) * 0x1.0p-53; }
inline double normal(std::mt19937_64& rng) {
  const double u = 1.0 - uniform(rng), v = uniform(rng);
  return std::sqrt(-2.0 * std::log(u)) * std::cos(2.0 * std::numbers::pi * v);
}

/// The radius of a space of `bodies` bodies at density 1/2 (area or volume per body 2): S^2 of
/// area 4 pi R^2, S^3 of volume 2 pi^2 R^3; H^n and E^n get the S^n radius of the same count.
inline double radius_for(int dim, int bodies) {
  const double volume = 2.0 * bodies;
  return dim == 3 ? std::cbrt(volume / (2.0 * std::numbers::pi * std::numbers::pi))
                  : std::pow(volume / (4.0 * std::numbers::pi), 1.0 / dim);
}

/// N bodies at random on the chart's space (S^n: uniform on the sphere; H^n: within geodesic
/// distance `spread` of the point at distance `far` from the origin along the first axis;
/// E^n: uniform in a cube of side `spread`), their chart coordinates with random momenta of
/// size ~ `speed`. Points come from embedding coordinates through the chart's own chart().
template <class Chart>
sesi::State<Chart> random_state(const Chart& chart, int n, double spread, double far, double speed,
                                std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  const int a = chart.ambient_dim();
  sesi::State<Chart> s(chart.dim(), n);
  typename Chart::Ambient x(a), v(a);
  typename Chart::Point q(chart.dim()), p(chart.dim());
  for (int b = 0; b < n; ++b) {
    for (int k = 0; k < a; ++k) v[k] = normal(rng);
    if constexpr (!requires { chart.radius(); }) {
      for (int k = 0; k < a; ++k) x[k] = spread * uniform(rng);
      static_cast<void>(far);
    } else if (chart.curvature() > 0) {
      for (int k = 0; k < a; ++k) x[k] = normal(rng);
      x *= chart.radius() / x.norm();
      v -= (v.dot(x) / x.squaredNorm()) * x;
    } else {
      // A point at distance r <= spread in a random direction, then boosted by `far`.
      const double R = chart.radius();
      Eigen::VectorXd dir(a - 1);
      for (int k = 0; k < a - 1; ++k) dir[k] = normal(rng);
      dir.normalize();
      const double r = spread * std::pow(uniform(rng), 1.0 / (a - 1));
      Eigen::VectorXd y(a);
      y.head(a - 1) = R * std::sinh(r / R) * dir;
      y[a - 1] = R * std::cosh(r / R);
      Eigen::VectorXd w = Eigen::VectorXd::Zero(a);
      w.head(a - 1) = v.head(a - 1);
      w -= (w.head(a - 1).dot(y.head(a - 1)) - w[a - 1] * y[a - 1]) / (-R * R) * y;  // tangent at y
      const double ch = std::cosh(far / R), sh = std::sinh(far / R);
      const auto boost = [&](const Eigen::VectorXd& u) {
        Eigen::VectorXd out = u;
        out[0] = ch * u[0] + sh * u[a - 1];
        out[a - 1] = sh * u[0] + ch * u[a - 1];
        return out;
      };
      x = boost(y);
      v = boost(w);
    }
    chart.chart(x, q);
    chart.momentum(q, v, 1.0, p);
    s.q.col(b) = q;
    s.p.col(b) = speed * p;
  }
  return s;
}

/// The embedding points of s (ambient x bodies), each body in the chart (no frames).
template <class Chart>
Eigen::MatrixXd points_of(const Chart& chart, const sesi::State<Chart>& s) {
  Eigen::MatrixXd X(chart.ambient_dim(), s.bodies());
  typename Chart::Point q(chart.dim());
  typename Chart::Ambient x(chart.ambient_dim());
  for (int b = 0; b < s.bodies(); ++b) {
    q = s.q.col(b);
    chart.embed(q, x);
    X.col(b) = x;
  }
  return X;
}

/// N bodies on a Fibonacci lattice of S^2 (nearest neighbours ~ sqrt(4 pi R^2 / N) apart, so
/// at density 1/2 no pair starts in Lennard-Jones' repulsive core), with random tangent
/// momenta of size ~ speed.
inline sesi::State<sesi::Sphere<2, double>> lattice_state(const sesi::Sphere<2, double>& chart, int n, double speed,
                                                          std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  sesi::State<sesi::Sphere<2, double>> s(2, n);
  const double golden = std::numbers::pi * (3.0 - std::sqrt(5.0)), R = chart.radius();
  Eigen::Vector3d x, v;
  Eigen::Vector2d q, p;
  for (int b = 0; b < n; ++b) {
    const double z = 1.0 - (2.0 * b + 1.0) / n, r = std::sqrt(1.0 - z * z);
    x << R * r * std::cos(golden * b), R * r * std::sin(golden * b), R * z;
    for (int k = 0; k < 3; ++k) v[k] = speed * normal(rng);
    v -= (v.dot(x) / (R * R)) * x;
    chart.chart(x, q);
    chart.momentum(q, v, 1.0, p);
    s.q.col(b) = q;
    s.p.col(b) = p;
  }
  return s;
}

}  // namespace manytest
