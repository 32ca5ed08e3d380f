#pragma once
/// @file sphere.hpp
/// The sphere S^n of radius R in hyperspherical angles (issue #2; seed paper, Discussion).
///
/// Metric R^2 (dq_1^2 + sin^2 q_1 dq_2^2 + sin^2 q_1 sin^2 q_2 dq_3^2 + ...), so for a body of
/// mass m the kinetic energy splits into levels K_i = p_i^2 / (2 m R^2 prod_{k<i} sin^2 q_k).
/// Embedding x = R u_n(q) with u_1(q) = (cos q, sin q), u_n = (sin q_1 u_{n-1}(q_2..), cos q_1);
/// for n = 2 this is the seed's (sin th cos ph, sin th sin ph, cos th).
/// Chart domain: q_1..q_{n-1} in [0, pi], q_n any angle. Invariant: |x| = R.

#include <cmath>
#include <limits>
#include <numbers>
#include <Eigen/Core>

#include "sesi/chart.hpp"
#include "sesi/config.hpp"
#include "sesi/spaces/hyperspherical.hpp"
#include "sesi/special_functions.hpp"

namespace sesi {

/// S^N of radius R. N may be Eigen::Dynamic (pass the dimension to the constructor).
template <int N, class Scalar_ = double>
class Sphere {
 public:
  using Scalar = Scalar_;
  static constexpr int dimension = N;
  static constexpr int ambient_dimension = plus_one(N);
  using Point = Eigen::Matrix<Scalar, N, 1>;
  using Ambient = Eigen::Matrix<Scalar, ambient_dimension, 1>;
  static constexpr const char* name = "sphere";

  explicit Sphere(Scalar radius = Scalar(1), int dim = (N == Eigen::Dynamic ? 2 : N))
      : radius_(radius), inv_r2_(Scalar(1) / (radius * radius)), dim_(dim) {
    SESI_CHECK(radius > Scalar(0), "sphere radius must be positive");
    SESI_CHECK(dim >= 1 && (N == Eigen::Dynamic || dim == N), "sphere dimension mismatch");
  }

  int dim() const { return dim_; }
  int ambient_dim() const { return dim_ + 1; }
  Scalar radius() const { return radius_; }
  /// Sectional curvature 1/R^2.
  Scalar curvature() const { return inv_r2_; }

  /// Inverse metric coefficient of level i: 1 / (R^2 prod_{k<i} sin^2 q_k).
  Scalar inverse_metric(int i, const Point& q) const {
    Scalar g = inv_r2_;
    for (int k = 0; k < i; ++k) g *= special::inv_sin2(q[k]);
    return g;
  }

  Scalar kinetic(int i, const Point& q, Scalar pi, Scalar m) const {
    return pi * pi * inverse_metric(i, q) / (Scalar(2) * m);
  }
  Scalar kinetic_dp(int i, const Point& q, Scalar pi, Scalar m) const {
    return pi * inverse_metric(i, q) / m;
  }
  /// dK_i/dq_k = -2 cot(q_k) K_i for k < i.
  Scalar kinetic_dq(int i, int k, const Point& q, Scalar pi, Scalar m) const {
    if (k >= i) return Scalar(0);
    return -pi * pi * inverse_metric(i, q) * special::cot(q[k]) / m;
  }

  // ---- the cached fast path (HasTrigCache): flows, embedding and pull-back share sines ----
  using TrigType = Trig<Scalar, N>;
  /// Sines and cosines of all coordinates of q.
  void refresh(const Point& q, TrigType& t) const {
    t.resize(dim_);
    detail::angle_trig(q, 0, dim_, t);
  }
  /// Exact flow of K_i for time h; t must hold the trig of q_{<i} and is kept in sync, except
  /// that with own_trig = false entry i is left stale (the engine does so when no reader of
  /// entry i comes before the next flow of level i).
  void level_flow(int i, Point& q, Point& p, Scalar m, Scalar h, TrigType& t,
                  bool own_trig = true) const {
    Scalar g = inv_r2_;
    for (int k = 0; k < i; ++k) {
      const Scalar r = special::reciprocal_sine(t.s[k]);
      g *= r * r;
    }
    const Scalar pi = p[i];
    const Scalar rate = h * pi * g / m;  // h dK_i/dp_i
    if (i > 0) {
      const Scalar push = rate * pi;  // h * 2 K_i; dK_i/dq_k = -2 cot(q_k) K_i
      for (int k = 0; k < i; ++k) p[k] += push * t.c[k] * special::reciprocal_sine(t.s[k]);
    }
    q[i] += rate;
    if (own_trig) detail::sin_cos(q[i], t.s[i], t.c[i]);
  }
  /// Trig entry i of `count` bodies from their q_i (qi): what level_flow's own_trig computes,
  /// for a block of bodies at once (special::sincos_many: vector lanes, the same bits).
  void level_trig(int /*i*/, const Scalar* qi, Scalar* s, Scalar* c, int count) const {
    special::sincos_many(qi, s, c, count);
  }
  void embed(const TrigType& t, Ambient& x) const {
    x.resize(ambient_dim());
    detail::unit_sphere_embed(t, 0, dim_, radius_, x);
    // Invariant |x| = R, to round-off of the n products that build x.
    SESI_CHECK(abs_of(constraint(x)) <= invariant_tolerance() * radius_ * radius_,
               "embedding left the sphere: |x| != R");
  }
  void pullback(const TrigType& t, const Ambient& g, Point& out) const {
    out.resize(dim_);
    detail::unit_sphere_pullback(t, 0, dim_, radius_, g, out);
  }

  // ---- the same from q alone ----
  void level_flow(int i, Point& q, Point& p, Scalar m, Scalar h) const {
    TrigType t;
    refresh(q, t);
    level_flow(i, q, p, m, h, t);
  }
  void embed(const Point& q, Ambient& x) const {
    TrigType t;
    refresh(q, t);
    embed(t, x);
  }
  void pullback(const Point& q, const Ambient& g, Point& out) const {
    TrigType t;
    refresh(q, t);
    pullback(t, g, out);
  }
  /// Embedding velocity v = J(q) qdot with qdot_i = dK_i/dp_i.
  void velocity(const Point& q, const Point& p, Scalar m, Ambient& v) const {
    Point qd(dim_);
    for (int i = 0; i < dim_; ++i) qd[i] = kinetic_dp(i, q, p[i], m);
    TrigType t;
    refresh(q, t);
    v.resize(ambient_dim());
    detail::unit_sphere_push(t, qd, 0, dim_, radius_, Scalar(0), v);
  }
  /// Chart coordinates of an embedding point (|x| = R).
  void chart(const Ambient& x, Point& q) const {
    q.resize(dim_);
    detail::unit_sphere_angles(x, 0, dim_, q);
  }
  /// Conjugate momenta of an embedding velocity tangent at x = embed(q): p = m J^T v.
  void momentum(const Point& q, const Ambient& v, Scalar m, Point& p) const {
    pullback(q, v, p);
    p *= m;
  }

  // ---- re-charting (recharting.hpp, docs/charts.md) ----
  /// What rechart() does with a body at (q, p): the polar angles k < n-1 with |sin q_k| below
  /// policy.min_sine are its danger zones (DangerFlags::action; deep below min_sine / 2).
  template <class Policy>
  RechartAction rechart_action(const Point& q, const Point& p, const Policy& policy) const {
    detail::DangerFlags f;
    detail::polar_angle_danger(q, p, 0, dim_ - 1, policy.min_sine, f);
    return f.action();
  }
  /// The turn's chart change (orthogonal): the half-turn 2 y y^T / |y|^2 - I about y = embed(q).
  template <class Frame>
  void turn(const Point& q, Frame& change) const {
    Ambient y(ambient_dim());
    embed(q, y);
    detail::half_turn(y, y, change);
  }
  /// The chart change L (orthogonal) that puts the body at x = R e_1 of the new chart, moving
  /// along e_2: every polar angle pi/2, on the great circle of the last angle, where the chart is
  /// best conditioned and free motion never leaves. Returns the new q, p (cotangent lift).
  template <class Policy, class Frame>
  void home(const Ambient& x, const Ambient& v, Scalar m, const Policy&, Frame& change, Point& q,
            Point& p) const {
    const Ambient xh = x / x.norm();
    const Ambient tangent = v - xh.dot(v) * xh;  // v, cleaned of round-off off the tangent space
    const Scalar speed = tangent.norm();
    Eigen::Matrix<Scalar, ambient_dimension, Eigen::Dynamic> lead(ambient_dim(), speed > 0 ? 2 : 1);
    lead.col(0) = xh;
    if (speed > 0) lead.col(1) = tangent / speed;
    detail::complete_orthonormal(lead, change);
    const Ambient x_new = change.transpose() * x, v_new = change.transpose() * v;
    chart(x_new, q);
    momentum(q, v_new, m, p);
  }

  /// Constraint residual |x|^2 - R^2 (zero on the space).
  Scalar constraint(const Ambient& x) const { return x.squaredNorm() - radius_ * radius_; }
  /// Tangency residual x . v (zero for v tangent at x).
  Scalar tangency(const Ambient& x, const Ambient& v) const { return x.dot(v); }
  /// Inner product of two tangent vectors (Euclidean on the sphere).
  Scalar inner(const Ambient& u, const Ambient& v) const { return u.dot(v); }

  /// Geodesic distance R * angle, as 2 R atan2(|x - y|, |x + y|): accurate at all angles
  /// (atan2_fast, within 2 ulp: special_functions.hpp).
  Scalar distance(const Ambient& x, const Ambient& y) const {
    return Scalar(2) * radius_ * special::atan2_fast((x - y).norm(), (x + y).norm());
  }
  /// The chord 2R sin(d/2R) of geodesic distance d (2R from d = pi R on): monotone in d, so a
  /// distance cutoff is a chord cutoff (neighbours.hpp).
  Scalar chord_of_distance(Scalar d) const {
    using std::sin;
    return d >= std::numbers::pi_v<Scalar> * radius_ ? Scalar(2) * radius_
                                                     : Scalar(2) * radius_ * sin(d / (Scalar(2) * radius_));
  }
  /// The pair x, y with one square root (chart.hpp, PairGeometry): R sin(d/R) =
  /// |x - y| |x + y| / 2R and 1 - cos(d/R) = |x - y|^2 / 2R^2, both accurate at all angles.
  SESI_INLINE PairGeometry<Scalar> pair_geometry(const Ambient& x, const Ambient& y) const {
    using std::sqrt;
    PairGeometry<Scalar> g;
    g.chord2 = (x - y).squaredNorm();
    g.cochord2 = (x + y).squaredNorm();
    g.sn = sqrt(g.chord2 * g.cochord2) * (Scalar(0.5) / radius_);  // one division fewer per pair
    g.one_minus_cs = g.chord2 * inv_r2_ / Scalar(2);
    return g;
  }
  /// The geodesic distance of a pair_geometry: 2R atan2(|x - y|, |x + y|), as distance(), with
  /// one square root (atan2_sqrt_fast, within 3.5 ulp of the angle: special_functions.hpp).
  SESI_INLINE Scalar distance_of(const PairGeometry<Scalar>& g) const {
    return Scalar(2) * radius_ * special::atan2_sqrt_fast(g.chord2, g.cochord2);
  }
  /// Gradient of the distance in x, tangent at x: -(b - (a.b) a) / |b - (a.b) a|, a = x/R, b = y/R.
  void distance_gradient(const Ambient& x, const Ambient& y, Ambient& g) const {
    const Scalar inv_r = Scalar(1) / radius_;
    g = -(y * inv_r - (x.dot(y) * inv_r * inv_r * inv_r) * x);
    const Scalar norm = g.norm();
    SESI_CHECK(norm > Scalar(0), "distance gradient at coincident or antipodal points");
    g /= norm;
  }

 private:
  static Scalar abs_of(Scalar v) { return v < Scalar(0) ? -v : v; }
  Scalar invariant_tolerance() const {
    return Scalar(16 * (dim_ + 1)) * std::numeric_limits<Scalar>::epsilon();
  }

  Scalar radius_;
  Scalar inv_r2_;
  int dim_;
};

using Sphere1d = Sphere<1, double>;
using Sphere2d = Sphere<2, double>;
using Sphere3d = Sphere<3, double>;
using Sphere2f = Sphere<2, float>;
using SphereXd = Sphere<Eigen::Dynamic, double>;

}  // namespace sesi
