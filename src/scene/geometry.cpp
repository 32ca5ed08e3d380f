#include "geometry.hpp"

#include <type_traits>

#include <sesi/neighbours.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
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
      }()) {
  if (!space.box.empty()) {
    box_.emplace(Eigen::Map<const Eigen::VectorXd>(space.box.data(), static_cast<Eigen::Index>(space.box.size())));
  }
  if (space.genus != 0) surface_.emplace(space.genus, space.radius);
}

void Geometry::reduce(Vector& x) const {
  if (box_) {
    // x - L floor(x / L) per axis, into [0, L) (the box's own reduction, as the run's wrap).
    Eigen::Matrix<std::int64_t, Eigen::Dynamic, 1> counts = Eigen::Matrix<std::int64_t, Eigen::Dynamic, 1>::Zero(x.size());
    box_->reduce(x, counts);
  } else if (surface_) {
    typename sesi::HyperbolicSurface<double>::Vector y = x;
    typename sesi::HyperbolicSurface<double>::Word applied;
    surface_->reduce(y, applied);
    x = y;
  }
}

double Geometry::max_cutoff() const {
  if (box_) return box_->max_cutoff();
  if (surface_) return surface_->max_cutoff();
  return std::numeric_limits<double>::infinity();
}

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

double Geometry::chord_of_distance(double d) const {
  return std::visit([d](const auto& chart) { return chart.chord_of_distance(d); }, chart_);
}

double Geometry::distance(const Vector& x0, const Vector& y0) const {
  // The minimum image (Allen & Tildesley 1.5.2; Sausset & Tarjus 2007 on the surfaces): both
  // reduced into the domain, y moved to its image nearest to x.
  Vector x = x0, y = y0;
  if (box_) {
    reduce(x);
    reduce(y);
    Vector image = y;
    box_->nearest_image(x, image);
    y = image;
  } else if (surface_) {
    reduce(x);
    reduce(y);
    typename sesi::HyperbolicSurface<double>::Vector a = x, b = y;
    surface_->nearest_image(a, b);
    y = b;
  }
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

std::vector<std::pair<int, int>> Geometry::topology_close_pairs(const Eigen::MatrixXd& X, double reach) const {
  std::vector<std::pair<int, int>> out;
  const int n = static_cast<int>(X.cols());
  if (n < 2) return out;
  // The points reduced into the domain, then the images of each within reach of the domain
  // (ghosts): a pair within reach on the minimum image is then a pair of the index of those
  // points (Allen & Tildesley 5.3.2 for the box's cells; images_near on the surface's polygon).
  std::vector<Vector> points;
  std::vector<int> owner;
  points.reserve(static_cast<std::size_t>(n));
  for (int b = 0; b < n; ++b) {
    Vector x = X.col(b);
    reduce(x);
    points.push_back(x);
    owner.push_back(b);
  }
  const bool all_pairs = !(reach < max_cutoff());  // (a reach past the largest cutoff: every pair, exactly)
  if (all_pairs) {
    for (int j = 1; j < n; ++j) {
      for (int i = 0; i < j; ++i) {
        if (distance(points[static_cast<std::size_t>(i)], points[static_cast<std::size_t>(j)]) < reach) out.emplace_back(i, j);
      }
    }
    return out;
  }
  if (box_) {
    const Vector& L = box_->edges();
    const int dim = static_cast<int>(L.size());
    std::vector<double> shifts;
    for (int b = 0; b < n; ++b) {
      const Vector x = points[static_cast<std::size_t>(b)];
      // Every combination of a shift per axis: 0, and +L or -L where x is within reach of a face.
      std::vector<Vector> images{x};
      for (int k = 0; k < dim; ++k) {
        shifts.assign(1, 0.0);
        if (x[k] < reach) shifts.push_back(L[k]);
        if (x[k] > L[k] - reach) shifts.push_back(-L[k]);
        const std::size_t before = images.size();
        for (std::size_t s = 1; s < shifts.size(); ++s) {
          for (std::size_t m = 0; m < before; ++m) {
            Vector y = images[m];
            y[k] += shifts[s];
            images.push_back(y);
          }
        }
      }
      for (std::size_t m = 1; m < images.size(); ++m) {
        points.push_back(images[m]);
        owner.push_back(b);
      }
    }
  } else {
    std::vector<int> near;
    for (int b = 0; b < n; ++b) {
      const typename sesi::HyperbolicSurface<double>::Vector x = points[static_cast<std::size_t>(b)];
      near.clear();
      surface_->images_near(x, reach, near);
      for (const int k : near) {
        if (k == 0) continue;  // the identity: the point itself
        typename sesi::HyperbolicSurface<double>::Vector y = x;
        surface_->apply(k, y);
        points.push_back(y);
        owner.push_back(b);
      }
    }
  }
  Eigen::MatrixXd all(ambient_dim(), static_cast<Eigen::Index>(points.size()));
  for (std::size_t m = 0; m < points.size(); ++m) all.col(static_cast<Eigen::Index>(m)) = points[m];
  std::visit(
      [&](const auto& chart) {
        using Chart = std::remove_cvref_t<decltype(chart)>;
        sesi::NeighbourIndex<Chart> index;
        sesi::NeighbourLists lists;
        index.build(chart, all, reach, lists);
        for (int i = 0; i < n; ++i) {
          for (int k = lists.begin(i); k < lists.end(i); ++k) {
            const int j = owner[static_cast<std::size_t>(lists.index[static_cast<std::size_t>(k)])];
            if (j != i) out.emplace_back(std::min(i, j), std::max(i, j));
          }
        }
      },
      chart_);
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  // The index's test is on the chord to a ghost; keep the pairs within reach on the minimum image.
  std::erase_if(out, [&](const std::pair<int, int>& pair) {
    return !(distance(points[static_cast<std::size_t>(pair.first)], points[static_cast<std::size_t>(pair.second)]) < reach);
  });
  return out;
}

std::vector<std::pair<int, int>> Geometry::close_pairs(const Eigen::MatrixXd& X, double reach, bool antipodal) const {
  if (has_topology() && !antipodal) return topology_close_pairs(X, reach);
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
