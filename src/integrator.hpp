#pragma once
/// @file integrator.hpp
/// A scene's state with its system and stepper, behind virtual calls: all that the run loop
/// (run_loop.cpp, compiled once) needs from the compile-time world. make_integrator dispatches
/// the scene's runtime space and dimension to a compile-time chart (dispatch.cpp).

#include <memory>

#include <Eigen/Core>

#include "scene.hpp"

namespace sesi::program {

class Integrator {
 public:
  virtual ~Integrator() = default;
  /// Advance the state from t by h (h may be negative).
  virtual void step(double t, double h) = 0;
  /// The current chart coordinates and momenta (dim x bodies).
  virtual void read(Eigen::MatrixXd& q, Eigen::MatrixXd& p) const = 0;
};

/// The integrator of scene (its space, dimension, bodies, potentials and method), at the
/// scene's initial state.
std::unique_ptr<Integrator> make_integrator(const Scene& scene);

}  // namespace sesi::program
