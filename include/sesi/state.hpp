#pragma once
/// @file state.hpp
/// The phase-space state of N bodies on one chart: column b holds body b's coordinates/momenta.

#include <initializer_list>
#include <vector>

#include <Eigen/Core>

#include "sesi/chart.hpp"
#include "sesi/config.hpp"

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

  /// Body b's coordinates and momenta, each a column: a state filled body by body, e.g.
  /// x.set_body(0, {1.2, 0.0}, {0.0, 0.4}). (Eigen's comma initializer x.q << ... is row-wise:
  /// it lists coordinate 0 of every body first, which is easy to get wrong with several bodies.)
  void set_body(int b, std::initializer_list<Scalar> qb, std::initializer_list<Scalar> pb) {
    SESI_CHECK(b >= 0 && b < bodies(), "set_body: no such body");
    SESI_CHECK(static_cast<Eigen::Index>(qb.size()) == q.rows() &&
                   static_cast<Eigen::Index>(pb.size()) == p.rows(),
               "set_body: one coordinate and one momentum per dimension");
    if (b < 0 || b >= bodies()) return;  // checks off: leave the state as it is
    Eigen::Index i = 0;
    for (auto it = qb.begin(); it != qb.end() && i < q.rows(); ++it) q(i++, b) = *it;
    i = 0;
    for (auto it = pb.begin(); it != pb.end() && i < p.rows(); ++it) p(i++, b) = *it;
  }
  /// The same from Eigen vectors of the chart's dimension.
  template <class Q, class P>
  void set_body(int b, const Eigen::MatrixBase<Q>& qb, const Eigen::MatrixBase<P>& pb) {
    SESI_CHECK(b >= 0 && b < bodies(), "set_body: no such body");
    SESI_CHECK(qb.size() == q.rows() && pb.size() == p.rows(),
               "set_body: one coordinate and one momentum per dimension");
    if (b < 0 || b >= bodies() || qb.size() != q.rows() || pb.size() != p.rows()) return;
    q.col(b) = qb;
    p.col(b) = pb;
  }
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
