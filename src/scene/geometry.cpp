#include "geometry.hpp"

#include <type_traits>

#include <sesi/neighbours.hpp>

#include <cmath>
#include <numbers>

#include <sesi/chart.hpp>

namespace sesi::program {

Geometry::Geometry(const SpaceSpec& space)
    : space_(space),
      chart_([&]() -> Charts {
        switch (space.kind) {
          case SpaceKind::sphere:
            return sesi::Sphere<Eigen::Dynamic>(space.radius, space.dim);
          case SpaceKind::hyperbolic:
            return sesi::Hyperbolic<Eigen::Dynamic>(space.radius, space.dim);
          case SpaceKind::euclidean:
            break;
        }
        return sesi::Euclidean<Eigen::Dynamic>(space.dim);
      }()) {}

int Geometry::ambient_dim() const {
  return std::visit([](const auto& c) { return c.ambient_dim(); }, chart_);
}

double Geometry::length_scale() const {
  return space_.kind == SpaceKind::euclidean ? 1.0 : space_.radius;
}

double Geometry::constraint_residual(const Vector& x) const {
  const double c = std::abs(std::visit([&](const auto& chart) { return chart.constraint(x); }, chart_));
  switch (space_.kind) {
    case SpaceKind::sphere:
      return c / (space_.radius * space_.radius);
    case SpaceKind::hyperbolic:
      return c / x.squaredNorm();
    case SpaceKind::euclidean:
      break;
  }
  return 0.0;
}

double Geometry::tangency_residual(const Vector& x, const Vector& v) const {
  const double scale = x.norm() * v.norm();
  if (scale == 0.0) return 0.0;
  const double t = std::visit([&](const auto& chart) { return chart.tangency(x, v); }, chart_);
  return std::abs(t) / scale;
}

bool Geometry::on_upper_sheet(const Vector& x) const {
  return space_.kind != SpaceKind::hyperbolic || x[x.size() - 1] > 0.0;
}

void Geometry::to_chart(const Vector& x, const Vector& v, double m, Vector& q, Vector& p) const {
  std::visit(
      [&](const auto& chart) {
        chart.chart(x, q);
        chart.momentum(q, v, m, p);
      },
      chart_);
}

Geometry::Vector Geometry::embed(const Vector& q) const {
  Vector x(ambient_dim());
  std::visit([&](const auto& chart) { chart.embed(q, x); }, chart_);
  return x;
}

Geometry::Vector Geometry::velocity(const Vector& q, const Vector& p, double m) const {
  Vector v(ambient_dim());
  std::visit([&](const auto& chart) { chart.velocity(q, p, m, v); }, chart_);
  return v;
}

double Geometry::kinetic_energy(const Vector& q, const Vector& p, double m) const {
  return std::visit([&](const auto& chart) { return sesi::kinetic_energy(chart, q, p, m); }, chart_);
}

double Geometry::distance(const Vector& x, const Vector& y) const {
  return std::visit(
      [&](const auto& chart) {
        // H^n: by radii and directions, so a scene's bodies far out are not measured with the
        // chord's cancellation of e^{2r} (docs/charts.md, "The cluster frame").
        if constexpr (requires { chart.polar_distance(x, y); }) {
          return chart.polar_distance(x, y);
        } else {
          return chart.distance(x, y);
        }
      },
      chart_);
}

double Geometry::radii_from_origin(const Vector& x) const {
  if (space_.kind != SpaceKind::hyperbolic) return 0.0;
  return std::asinh(x.head(space_.dim).norm() / space_.radius);
}

std::vector<std::pair<int, int>> Geometry::close_pairs(const Eigen::MatrixXd& X, double reach, bool antipodal) const {
  std::vector<std::pair<int, int>> out;
  const int n = static_cast<int>(X.cols());
  if (n < 2 && !antipodal) return out;
  std::visit(
      [&](const auto& chart) {
        using Chart = std::remove_cvref_t<decltype(chart)>;
        sesi::NeighbourIndex<Chart> index;
        sesi::NeighbourLists lists;
        if (!antipodal) {
          if constexpr (requires { chart.polar_distance(X.col(0), X.col(0)); }) {
            // H^n with the first body far out: the index sees the points read into a frame at
            // that body (to_frame, no cancellation), so a compact cluster far from the origin is
            // searched as one near it; world chords there would lose eps e^{2r}.
            const Eigen::Index t = X.rows() - 1;
            if (X(t, 0) / space_.radius > std::cosh(2.0)) {
              Eigen::MatrixXd frame, local(X.rows(), n);
              Eigen::VectorXd point;
              chart.boost_to(X.col(0), frame);
              for (int b = 0; b < n; ++b) {
                chart.to_frame(frame, Eigen::VectorXd(X.col(b)), point);
                local.col(b) = point;
              }
              index.build(chart, local, reach, lists);
            } else {
              index.build(chart, X, reach, lists);
            }
          } else {
            index.build(chart, X, reach, lists);
          }
          for (int i = 0; i < n; ++i) {
            for (int k = lists.begin(i); k < lists.end(i); ++k) {
              if (lists.index[static_cast<std::size_t>(k)] > i) out.emplace_back(i, lists.index[static_cast<std::size_t>(k)]);
            }
          }
          return;
        }
        // Body j near the antipode of body i is near -x_j: search the points and their negatives.
        Eigen::MatrixXd both(X.rows(), 2 * n);
        both << X, -X;
        index.build(chart, both, reach, lists);
        for (int i = 0; i < n; ++i) {
          for (int k = lists.begin(i); k < lists.end(i); ++k) {
            const int j = lists.index[static_cast<std::size_t>(k)] - n;
            if (j > i) out.emplace_back(i, j);
          }
        }
      },
      chart_);
  return out;
}

std::optional<std::pair<int, std::string>> Geometry::outside_domain(const Vector& q) const {
  const int n = space_.dim;
  const double pi = std::numbers::pi;
  int first_angle = 0;  // polar angles in [0, pi]: indices first_angle..n-2
  if (space_.kind == SpaceKind::euclidean) return std::nullopt;
  if (space_.kind == SpaceKind::hyperbolic) {
    if (n == 1) return std::nullopt;
    if (q[0] < 0.0) return std::pair{0, std::string(">= 0 (the geodesic radius)")};
    first_angle = 1;
  }
  for (int k = first_angle; k + 1 < n; ++k) {
    if (q[k] < 0.0 || q[k] > pi) return std::pair{k, std::string("in [0, pi] (a polar angle)")};
  }
  return std::nullopt;
}

}  // namespace sesi::program
