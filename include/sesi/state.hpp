#pragma once
/// @file state.hpp
/// The phase-space state of N bodies on one chart: column b holds body b's coordinates/momenta.

#include <Eigen/Core>

#include "sesi/chart.hpp"

namespace sesi {

template <HierarchicalChart Chart>
struct State {
  using Scalar = typename Chart::Scalar;
  using Matrix = Eigen::Matrix<Scalar, Chart::dimension, Eigen::Dynamic>;

  Matrix q;  ///< chart coordinates, dim x bodies
  Matrix p;  ///< conjugate momenta, dim x bodies

  State() = default;
  State(int dim, int bodies) : q(Matrix::Zero(dim, bodies)), p(Matrix::Zero(dim, bodies)) {}

  int bodies() const { return static_cast<int>(q.cols()); }
};

}  // namespace sesi
