#pragma once
/// @file geometry.hpp
/// The space of a scene at run time (dimension not known at compile time), for reading and
/// checking initial conditions: membership and tangency, embedding <-> chart conversions,
/// distances, the chart's domain. Built on the library's Eigen::Dynamic charts; the run itself
/// uses the fixed-size instantiations (dispatch.hpp).

#include <optional>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include <Eigen/Core>

#include <sesi/spaces/euclidean.hpp>
#include <sesi/spaces/hyperbolic.hpp>
#include <sesi/spaces/sphere.hpp>
#include <sesi/topologies/hyperbolic_surface.hpp>
#include <sesi/topologies/periodic_box.hpp>

#include "scene.hpp"

namespace sesi::program {

class Geometry {
 public:
  using Vector = Eigen::VectorXd;

  explicit Geometry(const SpaceSpec& space);

  int dim() const { return space_.dim; }
  /// n + 1 on S^n and H^n, n on E^n.
  int ambient_dim() const;
  /// R on S^n and H^n, 1 on E^n: the unit of length of tolerances.
  double length_scale() const;

  /// How far x is off the space, relative to its size (0 on E^n):
  /// | |x|^2 - R^2 | / R^2 on S^n, | <x,x>_L + R^2 | / |x|^2 on H^n.
  double constraint_residual(const Vector& x) const;
  /// How far v is off the tangent space at x, relative: |x.v| / (|x||v|) on S^n,
  /// |<x,v>_L| / (|x||v|) on H^n, 0 on E^n (and 0 for v = 0).
  double tangency_residual(const Vector& x, const Vector& v) const;
  /// On H^n, points lie on the upper sheet (last coordinate > 0); true elsewhere.
  bool on_upper_sheet(const Vector& x) const;

  /// Chart coordinates and conjugate momenta of a point x and tangent velocity v of a body of
  /// mass m (the library's chart() and momentum()).
  void to_chart(const Vector& x, const Vector& v, double m, Vector& q, Vector& p) const;
  Vector embed(const Vector& q) const;
  Vector velocity(const Vector& q, const Vector& p, double m) const;
  double kinetic_energy(const Vector& q, const Vector& p, double m) const;
  double distance(const Vector& x, const Vector& y) const;
  /// The chord of a geodesic distance d in the ambient metric (Minkowski on H^n), monotone in d:
  /// the chart's chord_of_distance.
  double chord_of_distance(double d) const;
  /// H^n: the distance of x from the origin in radii, asinh(|x_1..x_n| / R) (no cancellation);
  /// 0 on S^n and E^n.
  double radii_from_origin(const Vector& x) const;

  /// The pairs (i, j), i < j, of columns of X (embedding points) at distance < reach, in
  /// O(N log N) through the library's neighbour index; with antipodal (S^n only), the pairs
  /// whose distance is > pi R - reach instead (within reach of each other's antipode).
  /// With a topology, distances on the minimum image (distance below), found among the points
  /// reduced into the domain and their images within reach of it (ghosts).
  std::vector<std::pair<int, int>> close_pairs(const Eigen::MatrixXd& X, double reach, bool antipodal = false) const;

  // A topology (SpaceSpec::box or genus; docs/topology.md). distance() is then the distance of
  // the minimum image: of x and the image of y nearest to it, both reduced into the domain first.

  bool has_topology() const { return box_.has_value() || surface_.has_value(); }
  /// x <- its image in the domain (an isometry: a point of the same body); nothing without a topology.
  void reduce(Vector& x) const;
  /// The topology's largest allowed pair cutoff (+inf without one; max_cutoff, validate.hpp).
  double max_cutoff() const;
  /// The compact surface of SpaceSpec::genus, or null.
  const sesi::HyperbolicSurface<double>* surface() const { return surface_ ? &*surface_ : nullptr; }

  /// The first chart coordinate of q outside the chart's domain (0-based), with the domain
  /// ("[0, pi]", ">= 0"), or nothing. S^n: q_1..q_{n-1} in [0, pi]; H^n, n >= 2: q_1 >= 0,
  /// q_2..q_{n-1} in [0, pi]; the last coordinate (and everything on E^n) is free.
  std::optional<std::pair<int, std::string>> outside_domain(const Vector& q) const;

 private:
  using Charts = std::variant<sesi::Sphere<Eigen::Dynamic>, sesi::Hyperbolic<Eigen::Dynamic>,
                              sesi::Euclidean<Eigen::Dynamic>>;
  /// close_pairs on a topology: ghosts of the reduced points, pairs of the real bodies.
  std::vector<std::pair<int, int>> topology_close_pairs(const Eigen::MatrixXd& X, double reach) const;

  SpaceSpec space_;
  Charts chart_;
  std::optional<sesi::PeriodicBox<double, Eigen::Dynamic>> box_;
  std::optional<sesi::HyperbolicSurface<double>> surface_;
};

}  // namespace sesi::program
