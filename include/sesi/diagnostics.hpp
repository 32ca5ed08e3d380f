#pragma once
/// @file diagnostics.hpp
/// Conserved quantities in the embedding: energy and the momentum map.
///
/// On S^n and H^n the momentum map of the isometry group (SO(n+1), SO(n,1)) is represented by
/// the antisymmetric matrix M = sum_b m_b (x_b v_b^T - v_b x_b^T), conserved by geodesic motion
/// (x'' is parallel to x on both) and by isometry-invariant potentials. On S^2 its entries
/// (M_12, M_13, M_23) are (L_z, -L_y, L_x) of L = sum m x cross v. On E^n the map is the linear
/// momentum P = sum m v followed by the same M (angular momentum).
/// The vector form lists P (E^n only), then M_ab for a < b in row-major order.
///
/// A state with a cluster frame C (State::cluster, H^n) has world points C x_local: points and
/// velocities are mapped by C last (relative accuracy eps whatever C's size), and the momentum
/// map, a sum of O(1) local terms, is formed in the cluster's frame and moved to the world as
/// M = C M_local C^T (the adjoint action of the isometry; no world point enters the sum).
///
/// The configurational temperature kT_conf = sum_b |grad_b V|^2 / sum_b Delta_b V (Rugh, PRL 78,
/// 772 (1997); Butler, Ayton, Jepps, Evans, J. Chem. Phys. 109, 6519 (1998)) with the space's
/// gradient and Laplace-Beltrami operator: the canonical measure's position marginal is
/// exp(-V/kT) dvol_g whatever the masses, so integration by parts gives
/// <|grad V|^2> = kT <Delta V>.

#include <array>

#include <Eigen/Core>

#include "sesi/chart.hpp"
#include "sesi/parallel.hpp"
#include "sesi/state.hpp"

namespace sesi {

/// Charts whose ambient space has translations among the isometries (E^n).
template <class Chart>
constexpr bool has_translations = requires { Chart::translation_invariant; };

/// Number of components of the momentum map vector.
template <EmbeddedChart Chart>
int momentum_map_size(const Chart& chart) {
  const int a = ambient_dim_of(chart);
  return a * (a - 1) / 2 + (has_translations<Chart> ? a : 0);
}

/// Embedding points (columns) of all bodies, in world coordinates (through their frames).
template <class Sys>
Eigen::Matrix<typename Sys::Scalar, Eigen::Dynamic, Eigen::Dynamic> embedding_points(
    const Sys& sys, const State<typename Sys::Chart>& s) {
  using Chart = typename Sys::Chart;
  Eigen::Matrix<typename Sys::Scalar, Eigen::Dynamic, Eigen::Dynamic> X(sys.ambient_dim(),
                                                                         sys.bodies());
  // Body by body on threads (each writes its own column; the same bits for any count).
  parallel::for_chunks(sys.bodies(), parallel::chunks_for(sys.bodies()), [&](int begin, int end, int) {
    typename Chart::Point q(sys.dim());
    typename Chart::Ambient x(sys.ambient_dim());
    for (int b = begin; b < end; ++b) {
      q = s.q.col(b);
      sys.chart().embed(q, x);
      X.col(b) = s.framed() ? (s.frames[static_cast<std::size_t>(b)] * x).eval() : x;
    }
  });
  if (s.clustered) X = (s.cluster * X).eval();
  return X;
}

/// Embedding velocities (columns) of all bodies, in world coordinates.
template <class Sys>
Eigen::Matrix<typename Sys::Scalar, Eigen::Dynamic, Eigen::Dynamic> embedding_velocities(
    const Sys& sys, const State<typename Sys::Chart>& s) {
  using Chart = typename Sys::Chart;
  Eigen::Matrix<typename Sys::Scalar, Eigen::Dynamic, Eigen::Dynamic> V(sys.ambient_dim(),
                                                                         sys.bodies());
  parallel::for_chunks(sys.bodies(), parallel::chunks_for(sys.bodies()), [&](int begin, int end, int) {
    typename Chart::Point q(sys.dim()), p(sys.dim());
    typename Chart::Ambient v(sys.ambient_dim());
    for (int b = begin; b < end; ++b) {
      q = s.q.col(b);
      p = s.p.col(b);
      sys.chart().velocity(q, p, sys.mass(b), v);
      V.col(b) = s.framed() ? (s.frames[static_cast<std::size_t>(b)] * v).eval() : v;
    }
  });
  if (s.clustered) V = (s.cluster * V).eval();
  return V;
}

/// A momentum map m of bodies in a cluster frame C (State::cluster; rotations only, H^n), taken
/// in that frame, in world coordinates: M = C M_local C^T (see the file comment).
template <class Scalar, class Frame>
Eigen::Matrix<Scalar, Eigen::Dynamic, 1> momentum_map_in_world(const Eigen::Matrix<Scalar, Eigen::Dynamic, 1>& m,
                                                              const Frame& cluster) {
  const int a = static_cast<int>(cluster.rows());
  Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic> ml = Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic>::Zero(a, a);
  int k = 0;
  for (int r = 0; r < a; ++r) {
    for (int c = r + 1; c < a; ++c, ++k) {
      ml(r, c) = m[k];
      ml(c, r) = -m[k];
    }
  }
  const Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic> mw = cluster * ml * cluster.transpose();
  Eigen::Matrix<Scalar, Eigen::Dynamic, 1> out(m.size());
  k = 0;
  for (int r = 0; r < a; ++r) {
    for (int c = r + 1; c < a; ++c, ++k) out[k] = mw(r, c);
  }
  return out;
}

/// The momentum map of bodies with world points X and world velocities V (ambient x bodies) and
/// masses mass(b): sum_b m_b v_b first where the space has translations (E^n), then for each r < c
/// sum_b m_b (x_r v_c - v_r x_c), each component summed in body order (momentum_map below; a
/// simulation across processes gathers the points and takes the same sums).
template <class Scalar, class Mass>
Eigen::Matrix<Scalar, Eigen::Dynamic, 1> momentum_map_of(const Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic>& X,
                                                         const Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic>& V,
                                                         Mass&& mass, bool translations) {
  const int a = static_cast<int>(X.rows());
  const int n = static_cast<int>(X.cols());
  Eigen::Matrix<Scalar, Eigen::Dynamic, 1> out =
      Eigen::Matrix<Scalar, Eigen::Dynamic, 1>::Zero(a * (a - 1) / 2 + (translations ? a : 0));
  int k = 0;
  if (translations) {
    for (int b = 0; b < n; ++b) out.head(a) += mass(b) * V.col(b);
    k = a;
  }
  for (int r = 0; r < a; ++r) {
    for (int c = r + 1; c < a; ++c, ++k) {
      for (int b = 0; b < n; ++b) {
        out[k] += mass(b) * (X(r, b) * V(c, b) - V(r, b) * X(c, b));
      }
    }
  }
  return out;
}

/// The momentum map as a vector (see the file comment for the layout).
template <class Sys>
Eigen::Matrix<typename Sys::Scalar, Eigen::Dynamic, 1> momentum_map(
    const Sys& sys, const State<typename Sys::Chart>& s) {
  using Chart = typename Sys::Chart;
  using Scalar = typename Sys::Scalar;
  if (!has_translations<Chart> && s.clustered) {
    // In the cluster's frame, then M = C M_local C^T (see the file comment).
    State<Chart> local = s;
    local.clustered = false;
    return momentum_map_in_world<Scalar>(momentum_map(sys, local), s.cluster);
  }
  return momentum_map_of(embedding_points(sys, s), embedding_velocities(sys, s),
                         [&](int b) { return sys.mass(b); }, has_translations<Chart>);
}

/// {sum_b |grad_b V|^2, sum_b Delta_b V} at x, in the space's metric (see the file comment), for
/// averaging over rows: kT_conf = <first> / <second>. |grad_b V|^2 = g^ij dV/dq_i dV/dq_j of
/// the total chart gradient of body b (through its frame, if any): the chart's kinetic energy
/// p^T g^-1 p / 2m at p = dV/dq and m = 1/2. The Laplacian is System::laplacian_sum: NaN where a
/// term has no Laplacian (a user's External, ChartPotential or make_pair term). Both sums in
/// body order: the same bits for any thread count.
template <class Sys>
std::array<typename Sys::Scalar, 2> configurational_sums(const Sys& sys, const typename Sys::StateType& x) {
  using Scalar = typename Sys::Scalar;
  auto w = sys.make_workspace();
  typename Sys::StateType::Matrix grad;
  sys.potential_gradient(x, w, grad);
  typename Sys::Chart::Point q(sys.dim()), g(sys.dim());
  std::vector<Scalar> rows(static_cast<std::size_t>(sys.bodies()));
  for (int b = 0; b < sys.bodies(); ++b) {
    q = x.q.col(b);
    g = grad.col(b);
    rows[static_cast<std::size_t>(b)] = kinetic_energy(sys.chart(), q, g, Scalar(0.5));
  }
  // (In body order; a domain's over the whole simulation: System::sum_rows.)
  return {sys.sum_rows(rows), sys.laplacian_sum(x, w)};
}

/// kT_conf = sum_b |grad_b V|^2 / sum_b Delta_b V at x (k_B = 1; configurational_sums). One
/// configuration's ratio is noisy: average the two sums over rows before dividing. NaN where a
/// term has no Laplacian, and without a potential (0 / 0).
template <class Sys>
typename Sys::Scalar configurational_temperature(const Sys& sys, const typename Sys::StateType& x) {
  const auto sums = configurational_sums(sys, x);
  return sums[0] / sums[1];
}

}  // namespace sesi
