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

  State() = default;
  State(int dim, int bodies) : q(Matrix::Zero(dim, bodies)), p(Matrix::Zero(dim, bodies)) {}

  int bodies() const { return static_cast<int>(q.cols()); }
  bool framed() const { return !frames.empty(); }
  /// Give every body the identity frame (re-charting then changes them one by one).
  void enable_frames(int ambient_dim) {
    frames.assign(static_cast<std::size_t>(bodies()), Frame::Identity(ambient_dim, ambient_dim));
  }
};

}  // namespace sesi
