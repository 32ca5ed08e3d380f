#pragma once
/// @file hyperspherical.hpp
/// Hyperspherical angles on a unit sphere S^m, shared by Sphere<N> (all levels) and
/// Hyperbolic<N> (levels 1..n-1). The convention (issue #2, as in the seed's S^2 chart):
///   u_0 = (1),  u_1(q) = (cos q, sin q),  u_m(q_1..q_m) = (sin q_1 u_{m-1}(q_2..q_m), cos q_1).
/// Angles q[a..n-1] of a chart vector map to m = n - a and ambient entries x[0..m].
///
/// Everything here works from cached sines and cosines (Trig): a level flow changes one
/// coordinate, so a step needs one sine and cosine per level and body, shared by the flows, the
/// embedding and the pull-back (issue #4: reuse what a stage already computed).

#include <cmath>
#include <math.h>
#include <numbers>
#include <type_traits>
#include <Eigen/Core>
#include <Eigen/QR>

#include "sesi/chart.hpp"
#include "sesi/special_functions.hpp"

namespace sesi {

/// Sines and cosines of one body's chart coordinates (on H^n, entry 0 holds sinh and cosh of the
/// radius). Kept in sync with q by the charts' cached level flows.
template <class Scalar, int N>
struct Trig {
  Eigen::Matrix<Scalar, N, 1> s, c;
  Trig() {
    if constexpr (N != Eigen::Dynamic) {
      s.setZero();
      c.setZero();
    }
  }
  void resize(int n) {
    s.resize(n);
    c.resize(n);
  }
};

namespace detail {

/// s = sin x, c = cos x: special::sincos_fast in double (the same bits as its vector lanes,
/// special::sincos_many, which the kick-drift-kick engine's K-flows use for blocks of bodies:
/// glibc's sincos was 12 % of a 10^5-body step, issue #27), else the C library's sincos where
/// there is one (one argument reduction for both; GCC does not fuse separate sin and cos calls
/// under -fmath-errno).
template <class Scalar>
inline void sin_cos(Scalar x, Scalar& s, Scalar& c) {
  if constexpr (std::is_same_v<Scalar, double>) {
    special::sincos_fast(x, s, c);
  }
#if defined(__GLIBC__) && defined(_GNU_SOURCE)
  else if constexpr (std::is_same_v<Scalar, float>) {
    ::sincosf(x, &s, &c);
  } else if constexpr (std::is_same_v<Scalar, long double>) {
    ::sincosl(x, &s, &c);
  }
#endif
  else {
    using std::cos;
    using std::sin;
    s = sin(x);
    c = cos(x);
  }
}

/// Sines and cosines of q[a..n-1] into t.
template <class Q, class T>
void angle_trig(const Q& q, int a, int n, T& t) {
  for (int j = a; j < n; ++j) sin_cos(q[j], t.s[j], t.c[j]);
}

/// x[0..m] = scale * u_m(angles a..n-1).
template <class T, class X, class Scalar>
void unit_sphere_embed(const T& t, int a, int n, Scalar scale, X& x) {
  const int m = n - a;
  if (m == 0) {
    x[0] = scale;
    return;
  }
  Scalar prefix = scale;
  for (int j = a; j < n - 1; ++j) {
    x[m - (j - a)] = prefix * t.c[j];
    prefix *= t.s[j];
  }
  x[0] = prefix * t.c[n - 1];
  x[1] = prefix * t.s[n - 1];
}

/// out[a..n-1] = (d/dq[a..n-1] of scale * u_m)^T g[0..m], by reverse mode over the recursion:
/// a backward pass accumulates D_j = g . u(q_j..) and the bracket of each derivative, a forward
/// pass multiplies in the prefix products of sines. Free of cotangents: finite at poles.
/// Returns g[0..m] . u_m (needed by the hyperbolic radius).
template <class T, class G, class Out, class Scalar>
Scalar unit_sphere_pullback(const T& t, int a, int n, Scalar scale, const G& g, Out& out) {
  const int m = n - a;
  if (m == 0) return g[0];
  Scalar d = g[0] * t.c[n - 1] + g[1] * t.s[n - 1];
  out[n - 1] = -g[0] * t.s[n - 1] + g[1] * t.c[n - 1];
  for (int j = n - 2; j >= a; --j) {
    const Scalar gj = g[m - (j - a)];
    out[j] = t.c[j] * d - t.s[j] * gj;
    d = t.s[j] * d + t.c[j] * gj;
  }
  Scalar prefix = scale;
  for (int j = a; j < n; ++j) {
    out[j] *= prefix;
    prefix *= t.s[j];
  }
  return d;
}

/// xd[0..m] = d/dt (scale * u_m(q)) for angle rates qd[a..n-1] and scale rate dscale (forward mode).
template <class T, class Q, class X, class Scalar>
void unit_sphere_push(const T& t, const Q& qd, int a, int n, Scalar scale, Scalar dscale, X& xd) {
  const int m = n - a;
  if (m == 0) {
    xd[0] = dscale;
    return;
  }
  Scalar prefix = scale, dprefix = dscale;
  for (int j = a; j < n - 1; ++j) {
    xd[m - (j - a)] = dprefix * t.c[j] - prefix * t.s[j] * qd[j];
    dprefix = dprefix * t.s[j] + prefix * t.c[j] * qd[j];
    prefix *= t.s[j];
  }
  xd[0] = dprefix * t.c[n - 1] - prefix * t.s[n - 1] * qd[n - 1];
  xd[1] = dprefix * t.s[n - 1] + prefix * t.c[n - 1] * qd[n - 1];
}

/// Inverse of unit_sphere_embed for angles q[a..n-1] from x[0..m] (any positive multiple of a
/// unit vector): polar angles in [0, pi], the last angle in (-pi, pi].
template <class X, class Q>
void unit_sphere_angles(const X& x, int a, int n, Q& q) {
  using std::atan2;
  using std::sqrt;
  using Scalar = typename Q::Scalar;
  const int m = n - a;
  if (m == 0) return;
  // tail2 = x[0]^2 + ... + x[k]^2, grown upwards so that it is available for each level.
  Scalar tail2 = x[0] * x[0] + x[1] * x[1];
  q[n - 1] = atan2(x[1], x[0]);
  for (int j = n - 2; j >= a; --j) {
    const Scalar top = x[m - (j - a)];
    q[j] = atan2(sqrt(tail2), top);
    tail2 += top * top;
  }
}

/// Q, an orthogonal matrix whose leading columns are the orthonormal columns of lead (a
/// Householder QR completes them; the leading columns are then set exactly).
template <class Lead, class Q>
void complete_orthonormal(const Lead& lead, Q& q) {
  using Square = Eigen::Matrix<typename Lead::Scalar, Lead::RowsAtCompileTime, Lead::RowsAtCompileTime>;
  const Eigen::Index a = lead.rows();
  if (lead.cols() == 0) {
    q = Square::Identity(a, a);
    return;
  }
  Eigen::HouseholderQR<Eigen::Matrix<typename Lead::Scalar, Lead::RowsAtCompileTime, Eigen::Dynamic>>
      qr(lead);
  q = qr.householderQ() * Square::Identity(a, a);
  q.leftCols(lead.cols()) = lead;
}

/// Where a body stands with respect to the chart's singular sets, gathered over its coordinates
/// (recharting.hpp): in a danger zone and moving deeper (approaching), in one and moving out
/// (receding), or so deep that only a homing helps.
struct DangerFlags {
  bool approaching = false;
  bool receding = false;
  bool deep = false;

  /// Turn a body that approaches a danger zone and recedes from none (after the turn, which
  /// reverses its motion in the chart, it recedes from all); home it when it is deep, or when a
  /// turn would leave it approaching another zone.
  RechartAction action() const {
    if (deep || (approaching && receding)) return RechartAction::home;
    return approaching ? RechartAction::turn : RechartAction::none;
  }
  /// A coordinate in a danger zone whose distance to the singular set changes at the signed
  /// rate `rate` (negative: approaching), deep when `deep_here`.
  void add(bool deep_here, auto rate) {
    deep = deep || deep_here;
    if (rate < 0) approaching = true;
    if (rate > 0) receding = true;
  }
};

/// The polar angles q[a..b) with |sin q_k| < min_sine (deep below min_sine / 2). |sin q_k|
/// changes at the rate sin q_k cos q_k dq_k/dt / |sin q_k|, and dq_k/dt has the sign of p_k
/// (the kinetic energy is diagonal in p with positive coefficients).
/// With three or more angles also their product P = prod |sin q_k|: the levels below them move
/// with the factor 1 / P^2 of the kinetic energy, which the angles one by one bound only by
/// min_sine^-2(b-a) (4^8 on S^9, where a step of dt turns the deepest level by dt v / (R P) and
/// an order-8 method was 8e-3 off at dt = 0.01). P is in danger below min_sine^2 (two angles at
/// the threshold; with two angles one of them is already in danger then: S^2, S^3, H^2..H^4 are
/// unchanged), deep below half of it, and changes at the
/// rate P sum_k cot q_k dq_k/dt, dq_k/dt = p_k / (m R^2 prod_{a<=j<k} sin^2 q_j) up to a factor
/// common to every k (m R^2, and sinh^2 q_1 on H^n).
template <class Q, class Scalar>
void polar_angle_danger(const Q& q, const Q& p, int a, int b, Scalar min_sine, DangerFlags& f) {
  using std::abs;
  if (b - a < 3) {
    // With fewer than three angles only the angles' own zones count, and most bodies are far
    // from every pole: |sin q| >= (2/pi) dist(q, pi Z), so an angle in (-1, pi + 1) that is
    // 1.6 min_sine or more from 0 and from pi is in no zone, and needs no sine (one a body
    // and step was 4 % of a 10^5-body step on S^2). Others (a NaN too) take the test below.
    constexpr Scalar pi = std::numbers::pi_v<Scalar>;
    const Scalar near = Scalar(1.6) * min_sine;
    bool maybe = false;
    for (int k = a; k < b; ++k) {
      const Scalar x = q[k];
      maybe = maybe || !(x > Scalar(-1) && x < pi + Scalar(1)) || abs(x) < near || abs(pi - x) < near;
    }
    if (!maybe) return;
  }
  Scalar product(1), rate(0), level(1);  // P, its rate's sign, 1 / prod_{a<=j<k} sin^2 q_j
  for (int k = a; k < b; ++k) {
    Scalar s, c;
    sin_cos(q[k], s, c);
    if (abs(s) < min_sine) f.add(abs(s) < min_sine / Scalar(2), s * c * p[k]);
    product *= abs(s);
    rate += c / s * p[k] * level;
    level /= s * s;
  }
  const Scalar min_product = min_sine * min_sine;
  if (b - a >= 3 && product < min_product) f.add(product < min_product / Scalar(2), rate);
}

/// The turn's frame change T = 2 y y^T G / <y, y> - I (G the ambient metric, <y, y> = y^T G y):
/// T y = y and T w = -w for every w with <y, w> = 0, an isometry of the space that fixes the body
/// and reverses its tangent space. Its cotangent lift keeps q and negates p.
template <class Y, class GY, class Frame>
void half_turn(const Y& y, const GY& g_y, Frame& change) {
  change = (y * (g_y.transpose() * (typename Y::Scalar(2) / g_y.dot(y)))).eval();
  change.diagonal().array() -= typename Y::Scalar(1);
}

}  // namespace detail
}  // namespace sesi
