#pragma once
// A user-defined manifold: the torus of revolution with tube radius r around a circle of radius a,
//   x = ((a + r cos q1) cos q2, (a + r cos q1) sin q2, r sin q1),
//   metric r^2 dq1^2 + (a + r cos q1)^2 dq2^2.
// Its kinetic energy has the hierarchy K_1(p_1) + K_2(q_1, p_2), so sesi's steppers integrate it
// explicitly and symplectically. BareTorus gives only the concept's minimum, Torus adds an
// embedding for potentials on points of R^3; the library derives each level's exact flow.

#include <cmath>

#include <Eigen/Core>
#include <sesi/potentials.hpp>

// The chart alone: the concept's minimum (sesi::HierarchicalChart), enough for potentials on the
// chart's coordinates (sesi::make_chart_potential).
struct BareTorus {
  using Scalar = double;
  static constexpr int dimension = 2;
  using Point = Eigen::Vector2d;

  double a = 2.0;  // distance from the axis to the tube centre
  double r = 0.5;  // tube radius

  // Level 1: K_1 = p1^2 / (2 m r^2). Level 2: K_2 = p2^2 / (2 m (a + r cos q1)^2).
  double kinetic(int i, const Point& q, double pi, double m) const {
    return pi * pi / (2 * m * metric(i, q));
  }
  double kinetic_dp(int i, const Point& q, double pi, double m) const {
    return pi / (m * metric(i, q));
  }
  // dK_2/dq1 = p2^2 r sin q1 / (m (a + r cos q1)^3); K_1 depends on no coordinate.
  double kinetic_dq(int i, int /*k*/, const Point& q, double pi, double m) const {
    if (i == 0) return 0.0;
    const double rho = a + r * std::cos(q[0]);
    return pi * pi * r * std::sin(q[0]) / (m * rho * rho * rho);
  }

 private:
  // Diagonal metric coefficient g_ii.
  double metric(int i, const Point& q) const {
    if (i == 0) return r * r;
    const double rho = a + r * std::cos(q[0]);
    return rho * rho;
  }
};

// The chart with its embedding in R^3 (sesi::EmbeddedChart), for potentials on embedding points.
struct Torus : BareTorus {
  static constexpr int ambient_dimension = 3;
  using Ambient = Eigen::Vector3d;

  void embed(const Point& q, Ambient& x) const {
    const double rho = a + r * std::cos(q[0]);
    x << rho * std::cos(q[1]), rho * std::sin(q[1]), r * std::sin(q[0]);
  }
  // out = J^T g with J = dx/dq.
  void pullback(const Point& q, const Ambient& g, Point& out) const {
    const double s1 = std::sin(q[0]), c1 = std::cos(q[0]), s2 = std::sin(q[1]), c2 = std::cos(q[1]);
    const double rho = a + r * c1;
    out << r * (-s1 * c2 * g[0] - s1 * s2 * g[1] + c1 * g[2]), rho * (-s2 * g[0] + c2 * g[1]);
  }
};

// Uniform gravity along -z on the chart's coordinates: V = m g r sin q1, dV/dq = (m g r cos q1, 0).
inline auto chart_gravity(const BareTorus& torus, double g = 1.0) {
  const double r = torus.r;
  return sesi::make_chart_potential(
      [g, r](const BareTorus::Point& q, double m) { return m * g * r * std::sin(q[0]); },
      [g, r](const BareTorus::Point& q, double m) { return BareTorus::Point(m * g * r * std::cos(q[0]), 0.0); });
}

// Uniform gravity along -z on embedding points: V = m g z.
struct Gravity {
  double g = 1.0;
  double value(const Torus&, const Torus::Ambient& x, double m) const { return m * g * x[2]; }
  void gradient(const Torus&, const Torus::Ambient&, double m, Torus::Ambient& out) const {
    out << 0.0, 0.0, m * g;
  }
};
