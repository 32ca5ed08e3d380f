#pragma once
/// @file hyperbolic.hpp
/// Hyperbolic space H^n of radius R (curvature -1/R^2) in geodesic polar coordinates (issue #2).
///
/// Metric R^2 (dq_1^2 + sinh^2 q_1 dOmega_{n-1}^2), where dOmega is the hyperspherical metric of
/// sphere.hpp in q_2..q_n. Levels: K_1 = p_1^2 / (2 m R^2),
/// K_i = p_i^2 / (2 m R^2 sinh^2 q_1 prod_{1<k<i} sin^2 q_k) for i >= 2.
/// Embedding in the hyperboloid <x,x> = -R^2 of Minkowski space R^{n,1}, time-like coordinate
/// last: x = R (sinh q_1 u_{n-1}(q_2..q_n), cosh q_1), u_0 = (1), and
/// <x,y> = x_1 y_1 + ... + x_n y_n - x_{n+1} y_{n+1}.
/// Chart domain: n = 1, q_1 any real; n >= 2, q_1 >= 0, q_2..q_{n-1} in [0, pi], q_n any angle.
/// Invariant: <x,x> = -R^2 with x_{n+1} > 0.

#include <cmath>
#include <limits>
#include <Eigen/Core>

#include "sesi/chart.hpp"
#include "sesi/config.hpp"
#include "sesi/spaces/hyperspherical.hpp"
#include "sesi/special_functions.hpp"

namespace sesi {

/// Minkowski inner product with the time-like coordinate last.
template <class A, class B>
auto minkowski(const Eigen::MatrixBase<A>& x, const Eigen::MatrixBase<B>& y) {
  const Eigen::Index n = x.size() - 1;
  return x.head(n).dot(y.head(n)) - x[n] * y[n];
}

/// H^N of radius R. N may be Eigen::Dynamic (pass the dimension to the constructor).
template <int N, class Scalar_ = double>
class Hyperbolic {
 public:
  using Scalar = Scalar_;
  static constexpr int dimension = N;
  static constexpr int ambient_dimension = plus_one(N);
  using Point = Eigen::Matrix<Scalar, N, 1>;
  using Ambient = Eigen::Matrix<Scalar, ambient_dimension, 1>;
  static constexpr const char* name = "hyperbolic";

  explicit Hyperbolic(Scalar radius = Scalar(1), int dim = (N == Eigen::Dynamic ? 2 : N))
      : radius_(radius), inv_r2_(Scalar(1) / (radius * radius)), dim_(dim) {
    SESI_CHECK(radius > Scalar(0), "hyperbolic radius must be positive");
    SESI_CHECK(dim >= 1 && (N == Eigen::Dynamic || dim == N), "hyperbolic dimension mismatch");
  }

  int dim() const { return dim_; }
  int ambient_dim() const { return dim_ + 1; }
  Scalar radius() const { return radius_; }
  /// Sectional curvature -1/R^2.
  Scalar curvature() const { return -inv_r2_; }

  /// Inverse metric coefficient of level i: 1/R^2, then 1/(R^2 sinh^2 q_1 prod sin^2 q_k).
  Scalar inverse_metric(int i, const Point& q) const {
    Scalar g = inv_r2_;
    if (i >= 1) g *= special::inv_sinh2(q[0]);
    // k < N too (i < dim always): a compile-time bound keeps GCC 12 from a false
    // -Warray-bounds on H^1, where this loop never runs.
    constexpr int cap = N == Eigen::Dynamic ? std::numeric_limits<int>::max() : N;
    for (int k = 1; k < i && k < cap; ++k) g *= special::inv_sin2(q[k]);
    return g;
  }

  Scalar kinetic(int i, const Point& q, Scalar pi, Scalar m) const {
    return pi * pi * inverse_metric(i, q) / (Scalar(2) * m);
  }
  Scalar kinetic_dp(int i, const Point& q, Scalar pi, Scalar m) const {
    return pi * inverse_metric(i, q) / m;
  }
  /// dK_i/dq_1 = -2 coth(q_1) K_i, dK_i/dq_k = -2 cot(q_k) K_i for 1 < k < i.
  Scalar kinetic_dq(int i, int k, const Point& q, Scalar pi, Scalar m) const {
    if (k >= i) return Scalar(0);
    const Scalar two_k = pi * pi * inverse_metric(i, q) / m;
    return -two_k * (k == 0 ? special::coth(q[0]) : special::cot(q[k]));
  }

  // ---- the cached fast path (HasTrigCache): entry 0 holds sinh and cosh of the radius ----
  using TrigType = Trig<Scalar, N>;
  void refresh(const Point& q, TrigType& t) const {
    using std::cosh;
    using std::sinh;
    t.resize(dim_);
    t.s[0] = sinh(q[0]);
    t.c[0] = cosh(q[0]);
    detail::angle_trig(q, 1, dim_, t);
  }
  /// Exact flow of K_i for time h; t must hold the trig of q_{<i} and is kept in sync (entry i
  /// left stale with own_trig = false, as in Sphere::level_flow).
  void level_flow(int i, Point& q, Point& p, Scalar m, Scalar h, TrigType& t,
                  bool own_trig = true) const {
    using std::cosh;
    using std::sinh;
    const Scalar pi = p[i];
    if (i == 0) {
      q[0] += h * pi * inv_r2_ / m;
      if (own_trig) {
        t.s[0] = sinh(q[0]);
        t.c[0] = cosh(q[0]);
      }
      return;
    }
    Scalar g = inv_r2_;
    for (int k = 0; k < i; ++k) {
      const Scalar r = special::reciprocal_sine(t.s[k]);
      g *= r * r;
    }
    const Scalar rate = h * pi * g / m;
    const Scalar push = rate * pi;  // h * 2 K_i; dK_i/dq_1 = -2 coth(q_1) K_i, others -2 cot(q_k) K_i
    for (int k = 0; k < i; ++k) p[k] += push * t.c[k] * special::reciprocal_sine(t.s[k]);
    q[i] += rate;
    if (own_trig) detail::sin_cos(q[i], t.s[i], t.c[i]);
  }
  /// Trig entry i of `count` bodies from their q_i (qi), as level_flow's own_trig: sinh and
  /// cosh of the radius, else the angles' sines and cosines in vector lanes (the same bits).
  void level_trig(int i, const Scalar* qi, Scalar* s, Scalar* c, int count) const {
    using std::cosh;
    using std::sinh;
    if (i > 0) return special::sincos_many(qi, s, c, count);
    for (int k = 0; k < count; ++k) {
      s[k] = sinh(qi[k]);
      c[k] = cosh(qi[k]);
    }
  }
  void embed(const TrigType& t, Ambient& x) const {
    x.resize(ambient_dim());
    x[dim_] = radius_ * t.c[0];
    if constexpr (N == 1) {
      x[0] = radius_ * t.s[0];  // u_0 = (1); spelled out for GCC 12 (a false -Warray-bounds)
    } else {
      detail::unit_sphere_embed(t, 1, dim_, radius_ * t.s[0], x);
    }
    // Invariant <x,x> = -R^2, to round-off relative to x_{n+1}^2 (which grows like e^{2 q_1}).
    SESI_CHECK(abs_of(constraint(x)) <= invariant_tolerance() * x[dim_] * x[dim_],
               "embedding left the hyperboloid: <x,x> != -R^2");
  }
  /// d/dq_1 = R (cosh q_1 u . g_space + sinh q_1 g_time); angles: the sphere part scaled by
  /// R sinh q_1.
  void pullback(const TrigType& t, const Ambient& g, Point& out) const {
    out.resize(dim_);
    if constexpr (N == 1) {
      out[0] = radius_ * (t.c[0] * g[0] + t.s[0] * g[1]);  // u_0 = (1); spelled out for GCC 12
    } else {
      const Scalar gu = detail::unit_sphere_pullback(t, 1, dim_, radius_ * t.s[0], g, out);
      out[0] = radius_ * (t.c[0] * gu + t.s[0] * g[dim_]);
    }
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
  void velocity(const Point& q, const Point& p, Scalar m, Ambient& v) const {
    Point qd = Point::Zero(dim_);  // (zeroed: GCC 12 -O2 thinks qd[0] may be unset, dim_ >= 1 unseen)
    for (int i = 0; i < dim_; ++i) qd[i] = kinetic_dp(i, q, p[i], m);
    TrigType t;
    refresh(q, t);
    v.resize(ambient_dim());
    v[dim_] = radius_ * t.s[0] * qd[0];
    if constexpr (N == 1) {
      v[0] = radius_ * t.c[0] * qd[0];  // u_0 = (1); spelled out, GCC 12 misreads the general path
    } else {
      detail::unit_sphere_push(t, qd, 1, dim_, radius_ * t.s[0], radius_ * t.c[0] * qd[0], v);
    }
  }
  /// Chart coordinates of a hyperboloid point.
  void chart(const Ambient& x, Point& q) const {
    using std::asinh;
    q.resize(dim_);
    if (dim_ == 1) {
      q[0] = asinh(x[0] / radius_);
      return;
    }
    // |x_space| by a plain loop: Eigen's vectorised norm of x.head(dim_) on a fixed-size x
    // trips GCC 12's -Warray-bounds (a false positive) when inlined into home() at -O2.
    Scalar space2(0);
    for (int i = 0; i < dim_; ++i) space2 += x[i] * x[i];
    q[0] = asinh(std::sqrt(space2) / radius_);
    detail::unit_sphere_angles(x, 1, dim_, q);
  }
  /// Conjugate momenta of a tangent velocity: p = m J^T eta v (the metric is J^T eta J).
  /// Far out, p_1 = m R (cosh q_1 u.v_s - sinh q_1 v_t) cancels two terms of size e^{2 q_1};
  /// for a tangent v it equals m R v_t / sinh q_1 (<x,v> = 0 gives u.v_s = coth q_1 v_t),
  /// which has no cancellation, so that form is used where sinh q_1 > 1.
  void momentum(const Point& q, const Ambient& v, Scalar m, Point& p) const {
    Ambient eta_v = v;
    eta_v[dim_] = -v[dim_];
    pullback(q, eta_v, p);
    p *= m;
    using std::abs;
    using std::sinh;
    const Scalar s = sinh(q[0]);
    if (abs(s) > Scalar(1)) p[0] = m * radius_ * v[dim_] / s;
  }

  // ---- re-charting (recharting.hpp, docs/charts.md) ----
  /// What rechart() does with a body at (q, p) (DangerFlags::action). Danger zones: the radius
  /// |q_1| above policy.max_radius (deep 1 beyond it; sinh and cosh grow like e^{q_1}), below
  /// policy.min_radius for n >= 2 (the polar origin; deep below half of it), and the polar angles
  /// 1 <= k < n-1 with |sin q_k| < policy.min_sine (deep below half of it). A turn keeps the
  /// body's geodesic, whose closest approach b to the chart origin is unchanged, so a body
  /// leaving the far zone on a geodesic with b > max_radius / 2 is homed instead: its turned
  /// segment would be short (none at all for b > max_radius).
  template <class Policy>
  RechartAction rechart_action(const Point& q, const Point& p, const Policy& policy) const {
    using std::abs;
    detail::DangerFlags f;
    if constexpr (N != 1) {  // discarded for H^1 (no angles), where GCC 12 misreads the loop
      if (dim_ >= 2) {
        detail::polar_angle_danger(q, p, 1, dim_ - 1, policy.min_sine, f);
        if (q[0] < policy.min_radius) f.add(q[0] < policy.min_radius / Scalar(2), p[0]);
      }
    }
    if (f.deep) return RechartAction::home;
    if (abs(q[0]) > policy.max_radius) {
      const Scalar out = q[0] * p[0];  // > 0: moving outward
      const Scalar sinh_half = std::sinh(policy.max_radius / Scalar(2));
      const bool deep = abs(q[0]) > policy.max_radius + Scalar(1) ||
                        (out > 0 && dim_ >= 2 && closest_approach_sinh2(q, p) > sinh_half * sinh_half);
      f.add(deep, -out);
    }
    return f.action();
  }
  /// The turn's chart change (Lorentz): the half-turn 2 y (eta y)^T / <y, y>_L - I about
  /// y = embed(q) (<y, y>_L = -R^2).
  template <class Frame>
  void turn(const Point& q, Frame& change) const {
    Ambient y(ambient_dim());
    embed(q, y);
    Ambient eta_y = y;
    eta_y[dim_] = -y[dim_];
    detail::half_turn(y, eta_y, change);
  }
  /// sinh^2 b, b the closest approach to the chart origin of the geodesic through (q, p): the
  /// angular momentum sinh(q_1) |w| (w the tangential velocity over R) is conserved and equals
  /// sinh(b) |v| there, so sinh^2 b = sinh^2 q_1 (1 - radial share of the speed^2); the speed^2
  /// is sum_i p_i^2 g^i = 2 K at unit mass (g^i the inverse metric), its radial share p_1^2 g^1.
  Scalar closest_approach_sinh2(const Point& q, const Point& p) const {
    const Scalar speed2 = Scalar(2) * kinetic_energy(*this, q, p, Scalar(1));
    const Scalar sh = std::sinh(q[0]);
    if (!(speed2 > Scalar(0))) return sh * sh;
    const Scalar radial = p[0] * p[0] * inv_r2_;
    using std::max;
    return sh * sh * max(Scalar(0), Scalar(1) - radial / speed2);
  }
  /// The chart change L (Lorentz) that puts the body at radius policy.home_radius of the new
  /// chart (at its origin for n = 1), moving tangentially along the last angle with every other
  /// angle pi/2: its geodesic's closest approach to the new origin is home_radius, away from the
  /// polar singularity. Built with the standard boost B(u) to the body's rest frame, where the
  /// remaining choices are Euclidean (well conditioned). Returns the new q, p (cotangent lift).
  template <class Policy, class Frame>
  void home(const Ambient& x, const Ambient& v, Scalar m, const Policy& policy, Frame& change,
            Point& q, Point& p) const {
    using std::cosh;
    using std::sinh;
    using std::sqrt;
    const int n = dim_;
    const auto us = (x.head(n) / radius_).eval();    // spatial part of u = x / R
    const Scalar gamma = sqrt(Scalar(1) + us.squaredNorm());  // u_t, from <u,u> = -1
    const Scalar k = Scalar(1) / (Scalar(1) + gamma);
    // B(u) (a, 0) = (a + us (us.a) k, us.a): the boost that takes the origin's tangent
    // vectors to those at u. Its inverse on a tangent vector w: a = w_s - us w_t k.
    const auto to_u = [&](const auto& a) {
      Ambient w(n + 1);
      const Scalar ua = us.dot(a);
      w.head(n) = a + us * (ua * k);
      w[n] = ua;
      return w;
    };
    const Ambient vt = v + minkowski(x, v) / (radius_ * radius_) * x;  // tangent part of v
    const auto vs = (vt.head(n) - us * (vt[n] * k)).eval();            // v in the rest frame
    const Scalar speed = vs.norm();
    // Rest-frame spatial basis: [direction of v (n >= 2), then a completion]. For n >= 2 the
    // body is placed displaced along c_0 = -nhat so that it moves tangentially.
    Eigen::Matrix<Scalar, N, N> rest(n, n);
    Eigen::Matrix<Scalar, N, Eigen::Dynamic> lead(n, (n >= 2 && speed > 0) ? 1 : 0);
    if (lead.cols() == 1) lead.col(0) = vs / speed;
    detail::complete_orthonormal(lead, rest);
    const Ambient uu = x / radius_;
    change.resize(n + 1, n + 1);
    if (N == 1 || n == 1) {
      change.col(0) = to_u(rest.col(0));
      change.col(1) = uu;
    } else if constexpr (N != 1) {  // discarded for H^1, where GCC 12 misreads it (-Warray-bounds)
      const Scalar r0 = policy.home_radius;
      const Ambient nhat = to_u(rest.col(1));
      change.col(0) = -sinh(r0) * uu + cosh(r0) * nhat;
      change.col(n) = cosh(r0) * uu - sinh(r0) * nhat;
      change.col(1) = to_u(rest.col(0));
      for (int c = 2; c < n; ++c) change.col(c) = to_u(rest.col(c));
    }
    // L^{-1} = eta L^T eta.
    const auto inverse = [&](const Ambient& w) {
      Ambient e = w;
      e[n] = -e[n];
      Ambient r = change.transpose() * e;
      r[n] = -r[n];
      return r;
    };
    chart(inverse(x), q);
    momentum(q, inverse(v), m, p);
  }

  // ---- the cluster frame (State::cluster; docs/charts.md, "The cluster frame") ----

  /// The standard boost B(y) that takes the origin R e_{n+1} to the point y (<y,y>_L = -R^2):
  /// B = [[I + y_s y_s^T / (R (R + y_t)), y_s / R], [y_s^T / R, y_t / R]], Lorentz to rounding
  /// for any y (no cancellation: R + y_t >= 2R). Used with an O(1) y when a cluster re-centres.
  template <class Frame>
  void boost_to(const Ambient& y, Frame& b) const {
    const int n = dim_;
    const auto ys = (y.head(n) / radius_).eval();
    const Scalar yt = y[n] / radius_;
    b.resize(n + 1, n + 1);
    b.topLeftCorner(n, n) = ys * ys.transpose() / (Scalar(1) + yt);
    b.topLeftCorner(n, n).diagonal().array() += Scalar(1);
    b.topRightCorner(n, 1) = ys;
    b.bottomLeftCorner(1, n) = ys.transpose();
    b(n, n) = yt;
  }

  /// out = C^{-1} c for a Lorentz C and a point c of the space, without the cancellation of the
  /// matrix product (rows of C^{-1} and c both ~e^D far out would lose eps e^{2D}). With p = C o
  /// the frame's origin (o = R e_{n+1}) at radius r in direction u, and c at radius rho in
  /// direction w (polar readings, relative accuracy), C = B(p) Q with Q a rotation, and by the
  /// hyperbolic law of cosines in half-angle form (theta the angle between u and w,
  /// |w - u|^2 = 4 sin^2(theta/2)):
  ///   B(p)^{-1} c / R = (w_perp sinh rho + a u, t),  w_perp = (w - u) - ((w - u).u) u,
  ///   t = cosh(rho - r) + sinh r sinh rho |w - u|^2 / 2,
  ///   a = sinh(rho - r) - cosh r sinh rho |w - u|^2 / 2,
  /// and Q's columns Q e_k = B(p)^{-1} C e_k = C e_k - p_s (C e_k)_t / (R + p_t) on the tangent
  /// vectors C e_k at p. A point at the frame's origin (c = p) comes out as R e_{n+1} exactly;
  /// otherwise the error is that of reading c's direction, eps sinh(d(o, c)) in distance (what a
  /// world point far out can resolve at all).
  template <class Frame>
  void to_frame(const Frame& c_frame, const Ambient& c, Ambient& out) const {
    to_frame(c_frame, c, static_cast<const Ambient*>(nullptr), out, nullptr);
  }

  /// The same for a point x with a tangent velocity v there: out_x = C^{-1} x and
  /// out_v = C^{-1} v, the latter as the time derivative of the half-angle form above along
  /// x(t) = R (sinh rho w, cosh rho), read from v as rho' = v_t / (R sinh rho) and the
  /// transverse velocity S = sinh rho w' = (v_s - (v_s.w) w) / R (an O(1) vector):
  ///   b' = (S - (S.u) u) + w_perp cosh rho rho' + a' u,
  ///   a' = cosh(rho - r) rho' - cosh r (cosh rho rho' |w - u|^2 / 2 + (w - u).S),
  /// so the error is eps sinh d(o, x) again, where C^{-1} v as a matrix product would lose
  /// eps e^{2D}. For the bodies of a scene given far out in world coordinates
  /// (sesi::enter_cluster_frame). Near the world origin (sinh rho < 1) or with the frame there
  /// (sinh r < 1) the product loses no more than that and is used.
  template <class Frame>
  void to_frame(const Frame& c_frame, const Ambient& x, const Ambient& v, Ambient& out_x, Ambient& out_v) const {
    to_frame(c_frame, x, &v, out_x, &out_v);
  }

 private:
  template <class Frame>
  void to_frame(const Frame& c_frame, const Ambient& c, const Ambient* v, Ambient& out, Ambient* out_v) const {
    using std::asinh;
    using std::cosh;
    using std::sinh;
    using std::sqrt;
    const int n = dim_;
    // (c is read by its radius and direction only: a centre off the hyperboloid by rounding
    // lands on it.)
    out.resize(n + 1);
    // C is dimensionless: its last column is the frame's origin on the unit hyperboloid.
    const auto ps = c_frame.col(n).head(n).eval();
    const Scalar pt = c_frame(n, n);
    const auto cs = (c.head(n) / radius_).eval();
    const Scalar sr = ps.norm(), srho = cs.norm();
    if (v && (sr < Scalar(1) || srho < Scalar(1))) {
      // Near the world origin: C^{-1} = eta C^T eta, and the products lose eps e^{r + rho},
      // which is no more than the bound (one of the two is O(1)).
      Ambient y = c, u = *v;
      y[n] = -y[n];
      u[n] = -u[n];
      out.noalias() = c_frame.transpose() * y;
      out_v->resize(n + 1);
      out_v->noalias() = c_frame.transpose() * u;
      (*out_v)[n] = -(*out_v)[n];
      out[n] = -out[n];
      return;
    }
    const Scalar r = asinh(sr), rho = asinh(srho);
    Eigen::Matrix<Scalar, N, 1> u = Eigen::Matrix<Scalar, N, 1>::Zero(n), w(n);
    if (sr > Scalar(0)) u = ps / sr;
    if (srho > Scalar(0)) {
      w = cs / srho;
    } else {
      w = u;  // c at the world origin: any direction, sinh rho = 0
    }
    Eigen::Matrix<Scalar, N, 1> b(n), db = Eigen::Matrix<Scalar, N, 1>::Zero(n);
    Scalar half(0);
    Eigen::Matrix<Scalar, N, 1> dw = w - u;
    if (sr > Scalar(0)) {
      half = dw.squaredNorm() / Scalar(2);  // 2 sin^2(theta/2) = 1 - cos theta
      const Scalar a = sinh(rho - r) - cosh(r) * srho * half;
      b = (dw - dw.dot(u) * u) * srho + a * u;
    } else {
      b = cs;  // the frame's origin is the world origin: B(p) = I
    }
    if (v) {  // here sinh r, sinh rho >= 1
      const Scalar rd = (*v)[n] / radius_ / srho;  // rho'
      const auto vs = (v->head(n) / radius_).eval();
      const Eigen::Matrix<Scalar, N, 1> S = vs - vs.dot(w) * w;  // sinh rho w'
      const Scalar ad = cosh(rho - r) * rd - cosh(r) * (cosh(rho) * rd * half + dw.dot(S));
      db = (S - S.dot(u) * u) + (dw - dw.dot(u) * u) * (cosh(rho) * rd) + ad * u;
    }
    // Q^T b: Q's columns from C's spatial columns (tangent at p), O(1) after the subtraction.
    Eigen::Matrix<Scalar, N, N> q = Eigen::Matrix<Scalar, N, N>::Zero(n, n);  // (zeroed: GCC 12 misreads H^1)
    for (int k = 0; k < n; ++k) {
      q.col(k) = c_frame.col(k).head(n) - ps * (c_frame(n, k) / (Scalar(1) + pt));
    }
    const Eigen::Matrix<Scalar, N, 1> local = q.transpose() * b;
    out.head(n) = radius_ * local;
    // On the hyperboloid by construction: the time part from the spatial one,
    // cosh(d) = sqrt(1 + sinh^2 d) (no cancellation).
    const Scalar t = sqrt(Scalar(1) + local.squaredNorm());
    out[n] = radius_ * t;
    SESI_CHECK(abs_of(constraint(out)) <= invariant_tolerance() * out[n] * out[n],
               "to_frame: the point must be on the hyperboloid");
    if (v) {
      const Eigen::Matrix<Scalar, N, 1> dlocal = q.transpose() * db;
      out_v->resize(n + 1);
      out_v->head(n) = radius_ * dlocal;
      (*out_v)[n] = radius_ * local.dot(dlocal) / t;  // tangent by construction: d/dt sqrt(1 + |l|^2)
    }
  }

 public:

  /// Constraint residual <x,x> + R^2 (zero on the space).
  Scalar constraint(const Ambient& x) const { return minkowski(x, x) + radius_ * radius_; }
  /// Tangency residual <x, v> (zero for v tangent at x).
  Scalar tangency(const Ambient& x, const Ambient& v) const { return minkowski(x, v); }
  /// Inner product of tangent vectors (Minkowski, positive on tangent vectors).
  Scalar inner(const Ambient& u, const Ambient& v) const { return minkowski(u, v); }
  /// v -> eta v, the Minkowski metric applied to v (index lowering: <u, v>_L = u . eta v). The
  /// System uses it for chord terms: the gradient of sqrt(<u, u>_L) in u is eta u / chord.
  void lower(Ambient& v) const { v[dim_] = -v[dim_]; }

  /// The Minkowski chord 2R sinh(d/2R) of geodesic distance d: monotone in d, so a distance
  /// cutoff is a chord cutoff (neighbours.hpp).
  Scalar chord_of_distance(Scalar d) const {
    using std::sinh;
    return Scalar(2) * radius_ * sinh(d / (Scalar(2) * radius_));
  }
  /// The pair x, y with one square root (chart.hpp, PairGeometry): chord c = |x - y|_L,
  /// R sinh(d/R) = c sqrt(4R^2 + c^2) / 2R and 1 - cosh(d/R) = -c^2 / 2R^2 (no cancellation).
  SESI_INLINE PairGeometry<Scalar> pair_geometry(const Ambient& x, const Ambient& y) const {
    using std::sqrt;
    PairGeometry<Scalar> g;
    const Scalar c2 = minkowski(x - y, x - y);
    g.chord2 = c2 < Scalar(0) ? Scalar(0) : c2;  // round-off negatives only; NaN stays NaN
    g.cochord2 = Scalar(4) * radius_ * radius_ + g.chord2;
    g.sn = sqrt(g.chord2 * g.cochord2) * (Scalar(0.5) / radius_);  // one division fewer per pair
    g.one_minus_cs = -g.chord2 * inv_r2_ / Scalar(2);
    return g;
  }
  /// The geodesic distance of a pair_geometry: 2R asinh(c / 2R), as distance().
  SESI_INLINE Scalar distance_of(const PairGeometry<Scalar>& g) const {
    using std::asinh;
    using std::sqrt;
    return Scalar(2) * radius_ * asinh(sqrt(g.chord2) / (Scalar(2) * radius_));
  }
  /// Geodesic distance R acosh(-<x,y>/R^2), as 2 R asinh(|x - y|_L / 2R): accurate when small.
  Scalar distance(const Ambient& x, const Ambient& y) const {
    using std::asinh;
    using std::sqrt;
    const Scalar chord2 = minkowski(x - y, x - y);  // space-like, >= 0 up to round-off
    // Clamp round-off negatives only: a NaN chord stays NaN (a diverged state is not at distance 0).
    return Scalar(2) * radius_ * asinh(sqrt(chord2 < Scalar(0) ? Scalar(0) : chord2) /
                                       (Scalar(2) * radius_));
  }
  /// The same distance read by the points' radii rho and directions w (the hyperbolic law of
  /// cosines in half-angle form, as to_frame): with h = |w_x - w_y|^2 / 2 = 1 - cos theta,
  ///   sinh^2(d / 2R) = sinh^2((rho_x - rho_y) / 2) + sinh rho_x sinh rho_y h / 2,
  /// so two points far out at an O(1) distance lose eps sinh rho (what their coordinates
  /// resolve) where the chord of distance() loses eps e^{2 rho}. For checks of world points far
  /// out (a scene's initial conditions); the pair loops see cluster-local points and use the chord.
  Scalar polar_distance(const Ambient& x, const Ambient& y) const {
    using std::asinh;
    using std::sinh;
    using std::sqrt;
    const int n = dim_;
    const auto xs = (x.head(n) / radius_).eval();
    const auto ys = (y.head(n) / radius_).eval();
    const Scalar sx = xs.norm(), sy = ys.norm();
    Scalar h(0);
    if (sx > Scalar(0) && sy > Scalar(0)) h = (xs / sx - ys / sy).squaredNorm() / Scalar(2);
    const Scalar half = sinh((asinh(sx) - asinh(sy)) / Scalar(2));
    return Scalar(2) * radius_ * asinh(sqrt(half * half + sx * sy * h / Scalar(2)));
  }
  /// Euclidean gradient of the distance in x: -eta (b + <a,b> a) / sinh(d/R), a = x/R, b = y/R.
  /// The added multiple of eta a is normal, so the pull-back is unchanged and the vector small.
  void distance_gradient(const Ambient& x, const Ambient& y, Ambient& g) const {
    using std::sinh;
    const Scalar inv_r = Scalar(1) / radius_;
    const Scalar ab = minkowski(x, y) * inv_r * inv_r;
    g = -(y * inv_r + ab * inv_r * x);
    g[dim_] = -g[dim_];
    const Scalar sh = sinh(distance(x, y) * inv_r);
    SESI_CHECK(sh > Scalar(0), "distance gradient at coincident points");
    g /= sh;
  }
  /// The distance and its gradients at both ends at once (the pair loop's one call per pair).
  Scalar distance_gradients(const Ambient& x, const Ambient& y, Ambient& gx, Ambient& gy) const {
    using std::sinh;
    const Scalar inv_r = Scalar(1) / radius_;
    const Scalar ab = minkowski(x, y) * inv_r * inv_r;
    const Scalar d = distance(x, y);
    const Scalar sh = sinh(d * inv_r);
    SESI_CHECK(sh > Scalar(0), "distance gradient at coincident points");
    const Scalar k = -inv_r / sh;
    gx = k * (y + ab * x);
    gy = k * (x + ab * y);
    gx[dim_] = -gx[dim_];
    gy[dim_] = -gy[dim_];
    return d;
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

using Hyperbolic1d = Hyperbolic<1, double>;
using Hyperbolic2d = Hyperbolic<2, double>;
using Hyperbolic3d = Hyperbolic<3, double>;
using HyperbolicXd = Hyperbolic<Eigen::Dynamic, double>;

}  // namespace sesi
