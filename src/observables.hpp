#pragma once
/// @file observables.hpp
/// What the outputs observe in a state: energy, the momentum map (sesi::momentum_map),
/// embedding points and velocities. Computed on the scene's system over the Eigen::Dynamic chart
/// of its space, so compiled once per space rather than once per dimension (the stepping itself
/// runs on the fixed-size charts, integrator.hpp).

#include <memory>

#include <Eigen/Core>

#include "scene.hpp"

namespace sesi::program {

class Observables {
 public:
  explicit Observables(const Scene& scene);
  ~Observables();
  Observables(const Observables&) = delete;
  Observables& operator=(const Observables&) = delete;

  /// The state to observe (dim x bodies each); the accessors below refer to it.
  void set_state(const Eigen::MatrixXd& q, const Eigen::MatrixXd& p);

  double energy();
  Eigen::VectorXd momentum_map();
  Eigen::MatrixXd points();      ///< ambient x bodies
  Eigen::MatrixXd velocities();  ///< ambient x bodies
  /// With a non-finite energy: the first body (1-based) whose kinetic energy or potential
  /// gradient is not finite, or 0.
  int body_with_non_finite_energy();

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

}  // namespace sesi::program
