#pragma once
/// @file euclidean.hpp
/// Flat E^n in Cartesian coordinates: K_i = p_i^2 / 2m, the chart is its own embedding, and the
/// hierarchical Strang step is the Stoermer-Verlet method (Hairer, Lubich, Wanner, GNI, I.1.4).

#include <cmath>

#include <Eigen/Core>

#include "sesi/chart.hpp"
#include "sesi/config.hpp"

namespace sesi {

template <int N, class Scalar_ = double>
class Euclidean {
 public:
  using Scalar = Scalar_;
  static constexpr int dimension = N;
  static constexpr int ambient_dimension = N;
  using Point = Eigen::Matrix<Scalar, N, 1>;
  using Ambient = Point;
  static constexpr const char* name = "euclidean";
  /// Translations are isometries: the momentum map includes linear momentum.
  static constexpr bool translation_invariant = true;

  explicit Euclidean(int dim = (N == Eigen::Dynamic ? 2 : N)) : dim_(dim) {
    SESI_CHECK(dim >= 1 && (N == Eigen::Dynamic || dim == N), "euclidean dimension mismatch");
  }

  int dim() const { return dim_; }
  int ambient_dim() const { return dim_; }
  /// Zero sectional curvature.
  Scalar curvature() const { return Scalar(0); }

  Scalar kinetic(int, const Point&, Scalar pi, Scalar m) const { return pi * pi / (Scalar(2) * m); }
  Scalar kinetic_dp(int, const Point&, Scalar pi, Scalar m) const { return pi / m; }
  Scalar kinetic_dq(int, int, const Point&, Scalar, Scalar) const { return Scalar(0); }
  void level_flow(int i, Point& q, Point& p, Scalar m, Scalar h) const { q[i] += h * p[i] / m; }

  void embed(const Point& q, Ambient& x) const { x = q; }
  void pullback(const Point&, const Ambient& g, Point& out) const { out = g; }
  void velocity(const Point&, const Point& p, Scalar m, Ambient& v) const { v = p / m; }
  void chart(const Ambient& x, Point& q) const { q = x; }
  void momentum(const Point&, const Ambient& v, Scalar m, Point& p) const { p = m * v; }

  Scalar constraint(const Ambient&) const { return Scalar(0); }
  Scalar tangency(const Ambient&, const Ambient&) const { return Scalar(0); }
  Scalar inner(const Ambient& u, const Ambient& v) const { return u.dot(v); }

  Scalar distance(const Ambient& x, const Ambient& y) const { return (x - y).norm(); }
  /// The chord is the distance (neighbours.hpp).
  Scalar chord_of_distance(Scalar d) const { return d; }
  /// The pair x, y (pairs in System): chord = sn = |x - y|, cs = 1.
  SESI_INLINE PairGeometry<Scalar> pair_geometry(const Ambient& x, const Ambient& y) const {
    using std::sqrt;
    PairGeometry<Scalar> g;
    g.chord2 = (x - y).squaredNorm();
    g.sn = sqrt(g.chord2);
    return g;
  }
  SESI_INLINE Scalar distance_of(const PairGeometry<Scalar>& g) const { return g.sn; }
  void distance_gradient(const Ambient& x, const Ambient& y, Ambient& g) const {
    g = x - y;
    const Scalar norm = g.norm();
    SESI_CHECK(norm > Scalar(0), "distance gradient at coincident points");
    g /= norm;
  }
  Scalar distance_gradients(const Ambient& x, const Ambient& y, Ambient& gx, Ambient& gy) const {
    gx = x - y;
    const Scalar norm = gx.norm();
    SESI_CHECK(norm > Scalar(0), "distance gradient at coincident points");
    gx /= norm;
    gy = -gx;
    return norm;
  }

 private:
  int dim_;
};

using Euclidean2d = Euclidean<2, double>;
using Euclidean3d = Euclidean<3, double>;

}  // namespace sesi
