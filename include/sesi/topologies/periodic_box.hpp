#pragma once
/// @file periodic_box.hpp
/// The orthorhombic periodic box of E^n (issue #26): the domain is [0, L_k) on axis k, the group
/// the translations by L .* n, n integer. A body keeps integer image counts n_b, so its unwrapped
/// position x_b + L .* n_b is exact in the counts (Allen & Tildesley, Computer Simulation of
/// Liquids, 2nd ed. 2017, 1.6: periodic boundaries and the minimum image convention).
/// A triclinic box would take the same with x = H s, H the box matrix, s fractional coordinates
/// in [0, 1): reduce and minimum image on s, the cutoff bound the least distance between
/// opposite faces over 2 (docs/topology.md).

#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <utility>

#include <Eigen/Core>

#include "sesi/config.hpp"

namespace sesi {

template <class Scalar_, int N>
class PeriodicBox {
 public:
  using Scalar = Scalar_;
  using Vector = Eigen::Matrix<Scalar, N, 1>;
  using Images = Eigen::Matrix<std::int64_t, N, Eigen::Dynamic>;  ///< image counts, dim x bodies

  /// @param edges L_k > 0 and finite on every axis (else std::invalid_argument).
  explicit PeriodicBox(Vector edges) : edges_(std::move(edges)) {
    if (edges_.size() < 1) throw std::invalid_argument("periodic box: at least one edge");
    for (Eigen::Index k = 0; k < edges_.size(); ++k) {
      if (!(std::isfinite(static_cast<double>(edges_[k])) && edges_[k] > Scalar(0)))
        throw std::invalid_argument("periodic box: every edge must be finite and > 0");
    }
    inverse_ = edges_.cwiseInverse();
  }

  const Vector& edges() const { return edges_; }
  int dim() const { return static_cast<int>(edges_.size()); }
  /// min_k L_k / 2: a pair farther apart on some axis than half the box would meet two images.
  Scalar max_cutoff() const { return edges_.minCoeff() / Scalar(2); }
  /// 0 inside [0, L) on every axis, else how far outside (max over axes).
  template <class X>
  Scalar outside(const X& x) const {
    Scalar d(0);
    for (int k = 0; k < dim(); ++k) {
      if (x[k] < Scalar(0)) d = std::max(d, -x[k]);
      else if (x[k] >= edges_[k]) d = std::max(d, x[k] - edges_[k]);
    }
    if (!(d == d)) return std::numeric_limits<Scalar>::infinity();  // NaN: outside by any margin
    return d;
  }
  /// y <- y + L .* n with n = nearbyint((x - y) / L): the image of y nearest to x (the minimum
  /// image for |x_k - y_k| <= L_k / 2 + L_k in each axis, ties to even, the same for every caller).
  template <class X, class Y>
  void nearest_image(const X& x, Y& y) const {
    using std::nearbyint;
    for (int k = 0; k < dim(); ++k) y[k] += edges_[k] * nearbyint((x[k] - y[k]) * inverse_[k]);
  }
  /// Reduce x into the box: x <- x - L floor(x / L) per axis, counts += floor. A result that
  /// rounds to L_k (a tiny negative x_k) is mapped to 0 with the count one higher, so that
  /// x + L .* counts stays the unwrapped point. Returns whether anything changed.
  template <class X, class C>
  bool reduce(X& x, C&& counts) const {
    using std::floor;
    bool moved = false;
    for (int k = 0; k < dim(); ++k) {
      if (x[k] >= Scalar(0) && x[k] < edges_[k]) continue;  // inside (0 is inside: no flip-flop)
      if (!std::isfinite(static_cast<double>(x[k]))) continue;  // left to the finiteness checks
      Scalar n = floor(x[k] * inverse_[k]);
      Scalar r = x[k] - edges_[k] * n;
      // x/L rounded: r may fall just outside [0, L); one correction each way suffices.
      if (r < Scalar(0)) {
        r += edges_[k];
        n -= Scalar(1);
      }
      if (r >= edges_[k]) {
        r -= edges_[k];
        n += Scalar(1);
      }
      if (r < Scalar(0) || r >= edges_[k]) r = Scalar(0);  // |r| below rounding of L: on the face
      if (n == Scalar(0) && r == x[k]) continue;
      x[k] = r;
      counts[k] += static_cast<std::int64_t>(n);
      moved = true;
    }
    return moved;
  }
  Images identity_images(int bodies) const { return Images::Zero(dim(), bodies); }

  /// Whether some body lies outside the box by more than margin: wrap()'s trigger, and a run
  /// across ranks' test of its own bodies (the whole run's wrap is then any rank's call).
  template <class Chart, class StateT>
  bool out_by_more(const Chart&, const StateT& s, Scalar margin) const {
    SESI_CHECK(!s.framed() && !s.clustered, "a periodic box needs bodies in the chart itself (no frames)");
    for (int b = 0; b < s.bodies(); ++b) {
      if (outside(s.q.col(b)) > margin) return true;
    }
    return false;
  }

  /// wrap() for a box (topology.hpp): the chart is its own embedding, q_b is the world point.
  template <class Chart, class StateT>
  int wrap(const Chart& chart, StateT& s, Images& images, Scalar margin) const {
    SESI_CHECK(images.rows() == dim() && images.cols() == s.bodies(), "wrap: one image count per axis and body");
    if (!out_by_more(chart, s, margin)) return 0;
    int moved = 0;
    for (int b = 0; b < s.bodies(); ++b) {
      auto q = s.q.col(b);
      if (reduce(q, images.col(b))) ++moved;
    }
    return moved;
  }

 private:
  Vector edges_;
  Vector inverse_;
};

}  // namespace sesi
