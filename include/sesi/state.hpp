#pragma once
/// @file state.hpp
/// The phase-space state of N bodies on one chart: column b holds body b's coordinates/momenta.

#include <vector>

#include <Eigen/Core>

#include "sesi/chart.hpp"

namespace sesi {

template <HierarchicalChart Chart>
struct State {
  using Scalar = typename Chart::Scalar;
  using Matrix = Eigen::Matrix<Scalar, Chart::dimension, Eigen::Dynamic>;
  static constexpr int ambient_dimension = detail::ambient_dimension_of<Chart>();
  /// A body's chart frame: an isometry of the ambient space (orthogonal on S^n, Lorentz on
  /// H^n) with world point = frame * embed(q) (docs/charts.md).
  using Frame = Eigen::Matrix<Scalar, ambient_dimension, ambient_dimension>;

  Matrix q;  ///< chart coordinates, dim x bodies
  Matrix p;  ///< conjugate momenta, dim x bodies
  std::vector<Frame> frames;  ///< one per body, or empty: every frame is the identity
  /// The cluster frame C (H^n; docs/charts.md, "The cluster frame"): with `clustered`, a body's
  /// world point is C * frames[b] * embed(q_b). The system computes every potential on the
  /// cluster-local points frames[b] * embed(q_b), which stay O(1) for a compact cluster however
  /// far C has moved it from the world origin. Without `clustered`, C is ignored (the identity).
  /// Plain data: C and the flag are all a checkpoint needs of it.
  Frame cluster = identity_frame();
  bool clustered = false;

  State() = default;
  State(int dim, int bodies) : q(Matrix::Zero(dim, bodies)), p(Matrix::Zero(dim, bodies)) {}

  int bodies() const { return static_cast<int>(q.cols()); }
  bool framed() const { return !frames.empty(); }
  /// The identity of a fixed ambient dimension; empty (0 x 0) for a dynamic one.
  static Frame identity_frame() {
    if constexpr (ambient_dimension == Eigen::Dynamic) {
      return Frame();
    } else {
      return Frame::Identity();
    }
  }
  /// Turn the cluster frame on, at C (a Lorentz matrix; sesi::enter_cluster_frame builds one).
  void set_cluster(const Frame& c) {
    cluster = c;
    clustered = true;
  }
  /// Give every body the identity frame (re-charting then changes them one by one).
  void enable_frames(int ambient_dim) {
    frames.assign(static_cast<std::size_t>(bodies()), Frame::Identity(ambient_dim, ambient_dim));
  }
};

}  // namespace sesi
