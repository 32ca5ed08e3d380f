#pragma once
/// @file hyperspherical.hpp
/// Hyperspherical angles on a unit sphere S^m, shared by Sphere<N> (all levels) and
/// Hyperbolic<N> (levels 1..n-1). The convention (issue #2, as in the seed's S^2 chart):
///   u_0 = (1),  u_1(q) = (cos q, sin q),  u_m(q_1..q_m) = (sin q_1 u_{m-1}(q_2..q_m), cos q_1).
/// Angles q[a..n-1] of a chart vector map to m = n - a and ambient entries x[0..m].

#include <cmath>
#include <Eigen/Core>

#include "sesi/special_functions.hpp"

namespace sesi::detail {

/// Per-thread scratch for sines and cosines (fixed-size: no allocation; Dynamic: resized once).
template <class Scalar, int N>
struct TrigScratch {
  using Vec = Eigen::Matrix<Scalar, N, 1>;
  /// Buffer number Which (0, 1, 2, ...), at least n long.
  template <int Which>
  static Vec& buffer(int n) {
    thread_local Vec v;
    if constexpr (N == Eigen::Dynamic) {
      if (v.size() < n) v.resize(n);
    }
    return v;
  }
};

/// x[0..m] = scale * u_m(q[a..n-1]).
template <class Q, class X, class Scalar>
void unit_sphere_embed(const Q& q, int a, int n, Scalar scale, X& x) {
  using std::cos;
  using std::sin;
  const int m = n - a;
  if (m == 0) {
    x[0] = scale;
    return;
  }
  Scalar prefix = scale;
  for (int j = a; j < n - 1; ++j) {
    x[m - (j - a)] = prefix * cos(q[j]);
    prefix *= sin(q[j]);
  }
  x[0] = prefix * cos(q[n - 1]);
  x[1] = prefix * sin(q[n - 1]);
}

/// out[a..n-1] = (d/dq[a..n-1] of scale * u_m)^T g[0..m]: reverse mode over the recursion.
/// Free of cotangents: the derivative of each factor is taken directly, so it is finite at poles.
template <int N, class Q, class G, class Out, class Scalar>
void unit_sphere_pullback(const Q& q, int a, int n, Scalar scale, const G& g, Out& out) {
  using std::cos;
  using std::sin;
  const int m = n - a;
  if (m == 0) return;
  auto& s = TrigScratch<Scalar, N>::template buffer<0>(n);
  auto& c = TrigScratch<Scalar, N>::template buffer<1>(n);
  auto& prefixes = TrigScratch<Scalar, N>::template buffer<2>(n);
  Scalar prefix = scale;  // P_j = scale * prod_{a<=k<j} sin q_k
  for (int j = a; j < n; ++j) {
    s[j] = sin(q[j]);
    c[j] = cos(q[j]);
    prefixes[j] = prefix;
    prefix *= s[j];
  }
  // d = g[0..m-(j-a)] . u(q[j..]) accumulated from the innermost level outwards.
  Scalar d = g[0] * c[n - 1] + g[1] * s[n - 1];
  Scalar dd = -g[0] * s[n - 1] + g[1] * c[n - 1];  // derivative wrt the innermost angle
  out[n - 1] = prefixes[n - 1] * dd;
  for (int j = n - 2; j >= a; --j) {
    const Scalar gj = g[m - (j - a)];
    out[j] = prefixes[j] * (c[j] * d - s[j] * gj);
    d = s[j] * d + gj * c[j];
  }
}

/// xdot[0..m] = d/dt (scale * u_m(q)) for angle rates qd[a..n-1]: forward mode over the recursion.
template <class Q, class X, class Scalar>
void unit_sphere_push(const Q& q, const Q& qd, int a, int n, Scalar scale, Scalar dscale, X& xd) {
  using std::cos;
  using std::sin;
  const int m = n - a;
  if (m == 0) {
    xd[0] = dscale;
    return;
  }
  Scalar prefix = scale, dprefix = dscale;
  for (int j = a; j < n - 1; ++j) {
    const Scalar s = sin(q[j]), c = cos(q[j]);
    xd[m - (j - a)] = dprefix * c - prefix * s * qd[j];
    dprefix = dprefix * s + prefix * c * qd[j];
    prefix *= s;
  }
  const Scalar s = sin(q[n - 1]), c = cos(q[n - 1]);
  xd[0] = dprefix * c - prefix * s * qd[n - 1];
  xd[1] = dprefix * s + prefix * c * qd[n - 1];
}

/// Inverse of unit_sphere_embed for angles q[a..n-1] from u = x[0..m] / scale (any positive
/// multiple of a unit vector works): polar angles in [0, pi], the last angle in (-pi, pi].
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

}  // namespace sesi::detail
