// Many-body scenes on quotients (issue #26) for tests/many/topology*.cpp: an E^2 periodic box and
// compact hyperbolic surfaces of genus g (Sausset & Tarjus, J. Phys. A 40, 12873 (2007)), with
// bodies uniform in the domain (or in the domain widened by a margin, as between wraps), or at
// least a distance apart (random sequential addition), and Maxwell velocities.
#pragma once

#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>
#include <stdexcept>
#include <type_traits>
#include <vector>

#include <Eigen/Core>

#include <sesi/spaces/euclidean.hpp>
#include <sesi/spaces/hyperbolic.hpp>
#include <sesi/state.hpp>
#include <sesi/topologies/hyperbolic_surface.hpp>
#include <sesi/topologies/periodic_box.hpp>
#include <sesi/topology.hpp>

#include "common.hpp"

namespace topotest {

using Box2 = sesi::Quotient<sesi::Euclidean<2, double>, sesi::PeriodicBox<double, 2>>;
using Surface = sesi::Quotient<sesi::Hyperbolic<2, double>, sesi::HyperbolicSurface<double>>;

inline Box2 box2(double L1, double L2) {
  return Box2(sesi::Euclidean<2, double>(), sesi::PeriodicBox<double, 2>(Eigen::Vector2d(L1, L2)));
}
inline Surface surface(int genus, double R) {
  return Surface(sesi::Hyperbolic<2, double>(R), sesi::HyperbolicSurface<double>(genus, R));
}
/// The radius of a genus-g surface holding n bodies at density rho: area 4 pi (g - 1) R^2 = n / rho.
inline double surface_radius(int genus, int n, double rho) {
  return std::sqrt(n / (rho * 4.0 * std::numbers::pi * (genus - 1)));
}

/// A point uniform in the domain widened by `margin` (points outside by at most margin).
inline Eigen::Vector2d box_point(const Box2& chart, double margin, std::mt19937_64& rng) {
  const Eigen::Vector2d& L = chart.topology().edges();
  return Eigen::Vector2d(-margin + manytest::uniform(rng) * (L[0] + 2 * margin),
                         -margin + manytest::uniform(rng) * (L[1] + 2 * margin));
}
/// A point uniform (in the hyperbolic area) in the polygon widened by `margin`: rejection from the
/// disc of radius circumradius + margin about the centre, whose area measure is R sinh(r/R) dr dtheta.
inline Eigen::Vector3d surface_point(const Surface& chart, double margin, std::mt19937_64& rng) {
  const auto& t = chart.topology();
  const double R = t.radius();
  const double top = std::cosh((t.circumradius() + margin) / R) - 1.0;
  while (true) {
    const double r = R * std::acosh(1.0 + manytest::uniform(rng) * top);
    const double th = 2.0 * std::numbers::pi * manytest::uniform(rng);
    const Eigen::Vector3d x(R * std::sinh(r / R) * std::cos(th), R * std::sinh(r / R) * std::sin(th),
                            R * std::cosh(r / R));
    if (t.outside(x) <= margin) return x;
  }
}

/// Minimum-image geodesic distance (a tool of the tests: the topology's nearest image).
inline double min_image_distance(const Box2& chart, const Eigen::Vector2d& x, Eigen::Vector2d y) {
  chart.topology().nearest_image(x, y);
  return (x - y).norm();
}
inline double min_image_distance(const Surface& chart, const Eigen::Vector3d& x, Eigen::Vector3d y) {
  chart.topology().nearest_image(x, y);
  return chart.distance(x, y);
}

/// A unit tangent basis at x: the box's axes, or on the hyperboloid the Lorentz Gram-Schmidt of
/// the spatial axes projected onto the tangent plane (<v, x>_L = 0).
inline void tangent_basis(const Box2&, const Eigen::Vector2d&, Eigen::Vector2d& e1, Eigen::Vector2d& e2) {
  e1 = Eigen::Vector2d(1, 0);
  e2 = Eigen::Vector2d(0, 1);
}
inline void tangent_basis(const Surface& chart, const Eigen::Vector3d& x, Eigen::Vector3d& e1, Eigen::Vector3d& e2) {
  const auto L = [](const Eigen::Vector3d& a, const Eigen::Vector3d& b) { return a[0] * b[0] + a[1] * b[1] - a[2] * b[2]; };
  const double R2 = chart.radius() * chart.radius();
  e1 = Eigen::Vector3d(1, 0, 0);
  e1 += L(e1, x) / R2 * x;
  e1 /= std::sqrt(L(e1, e1));
  e2 = Eigen::Vector3d(0, 1, 0);
  e2 += L(e2, x) / R2 * x;
  e2 -= L(e2, e1) * e1;
  e2 /= std::sqrt(L(e2, e2));
}

/// n bodies of unit mass from points and Maxwell velocities at temperature T (no frames).
template <class Chart, class Point>
sesi::State<Chart> state_from(const Chart& chart, const std::vector<Point>& points, double T, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  const int n = static_cast<int>(points.size());
  sesi::State<Chart> s(chart.dim(), n);
  typename Chart::Point q(chart.dim()), p(chart.dim());
  Point e1, e2;
  for (int b = 0; b < n; ++b) {
    const Point& x = points[static_cast<std::size_t>(b)];
    tangent_basis(chart, x, e1, e2);
    const Point v = std::sqrt(T) * (manytest::normal(rng) * e1 + manytest::normal(rng) * e2);
    chart.chart(x, q);
    chart.momentum(q, v, 1.0, p);
    s.q.col(b) = q;
    s.p.col(b) = p;
  }
  return s;
}

/// n points uniform in the domain widened by margin.
template <class Chart>
auto uniform_points(const Chart& chart, int n, double margin, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  if constexpr (std::is_same_v<Chart, Box2>) {
    std::vector<Eigen::Vector2d> out;
    for (int b = 0; b < n; ++b) out.push_back(box_point(chart, margin, rng));
    return out;
  } else {
    std::vector<Eigen::Vector3d> out;
    for (int b = 0; b < n; ++b) out.push_back(surface_point(chart, margin, rng));
    return out;
  }
}

/// n points in the domain, every two at least `gap` apart on the minimum image (random sequential
/// addition; below the jamming coverage it ends).
template <class Chart>
auto spaced_points(const Chart& chart, int n, double gap, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  auto draw = [&] {
    if constexpr (std::is_same_v<Chart, Box2>) {
      return box_point(chart, 0.0, rng);
    } else {
      return surface_point(chart, 0.0, rng);
    }
  };
  std::vector<decltype(draw())> out;
  for (long tries = 0; static_cast<int>(out.size()) < n; ++tries) {
    if (tries > 1000L * n) throw std::runtime_error("spaced_points: too dense");
    const auto x = draw();
    bool free = true;
    for (const auto& y : out) {
      if (min_image_distance(chart, x, y) < gap) {
        free = false;
        break;
      }
    }
    if (free) out.push_back(x);
  }
  return out;
}

}  // namespace topotest
