#pragma once
/// @file simulation.hpp
/// The compiled core of the Python package (docs/python.md): a scene read from a TOML document
/// (the same reader, checks and messages as `sesi run`), its integrator (make_integrator) and
/// runs of the program's step loop (run_loop), whose rows are kept in memory. The Python layer
/// (sesi/__init__.py) builds the document and turns a run's report into exceptions.

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <pybind11/pybind11.h>
#include <toml++/toml.h>

#include "integrator.hpp"
#include "run_loop.hpp"
#include "scene.hpp"

namespace sesi::python {

namespace py = pybind11;

/// A Python potential (sesi.Simulation.add_potential(value=f, gradient=g)): f(x, m) -> float and
/// g(x, m) -> dV/dx, called with the GIL held.
class PythonFunctions final : public program::FunctionExternalSpec::Functions {
 public:
  PythonFunctions(py::function value, py::function gradient);
  ~PythonFunctions() override;
  double value(const Eigen::VectorXd& x, double m) const override;
  void gradient(const Eigen::VectorXd& x, double m, Eigen::VectorXd& g) const override;

 private:
  py::function value_, gradient_;
};

/// Integer image counts, bodies x dim (a periodic box's record, transposed).
using ImageCounts = Eigen::Matrix<std::int64_t, Eigen::Dynamic, Eigen::Dynamic>;

/// The rows of a run (Simulation.run), one per output row, bodies along the second axis.
struct Rows {
  std::vector<double> t, energy;
  std::vector<Eigen::MatrixXd> x, v, q, p;  ///< bodies x coordinates each
  std::vector<Eigen::VectorXd> momentum;
  // A space with a topology (SpaceSpec::has_topology) only, as trajectory.csv's columns:
  std::vector<Eigen::MatrixXd> unwrapped;          ///< bodies x ambient: the points in the covering space
  std::vector<ImageCounts> image_counts;           ///< a box: bodies x dim
  std::vector<std::vector<std::string>> words;     ///< a surface: per body, its word's text (program::word_text)
};

/// How a run ended (program::RunOutcome, for the Python layer).
struct Report {
  bool complete = true;
  std::string reason;  ///< "completed", "non-finite state", "energy error exceeded", ...
  std::string detail;
  long failed_step = 0;
  double failed_t = 0.0;
  int failed_body = 0;
  bool interrupted = false;  ///< Ctrl-C: a KeyboardInterrupt is pending
};

class Simulation {
 public:
  /// Read the document (TOML's keys: space, bodies, potential, integrator, name); source names
  /// it in messages. functions: Python potentials, after the document's. Throws InputError.
  Simulation(const toml::table& doc, const std::string& source,
             std::vector<std::shared_ptr<const program::FunctionExternalSpec::Functions>> functions);
  /// A scene already read (a scene file, as `sesi run` reads it).
  explicit Simulation(program::Scene scene);

  double t() const { return t_; }
  long step() const { return step_; }
  int bodies() const { return scene_.body_count(); }
  const program::Scene& scene() const { return scene_; }

  /// Bodies x coordinates: chart coordinates and momenta (scene chart), world points and velocities.
  Eigen::MatrixXd q() const;
  Eigen::MatrixXd p() const;
  Eigen::MatrixXd x() const;
  Eigen::MatrixXd v() const;
  Eigen::VectorXd masses() const;
  /// A space with a topology: the image record and the unwrapped points (bodies along the rows);
  /// q(), x() are the bodies in the domain. Without a box / a surface, image_counts() / words()
  /// are empty; without a topology unwrapped_points() is x().
  ImageCounts image_counts() const;
  std::vector<std::string> words() const;
  Eigen::MatrixXd unwrapped_points() const;
  double energy() const;
  Eigen::VectorXd momentum_map() const;
  std::vector<std::string> momentum_names() const;

  // Settings that may change between runs (checked as the scene file's keys are).
  void set_method(const std::string& method);
  void set_dt(double dt);
  void set_energy_guard(double threshold);  ///< 0: off
  void set_threads(long threads);
  void set_check_every(long check_every);  ///< 0: the default cadence
  /// A thermostat (none: constant energy) from the next step on, at the current state; checked
  /// with the method (sesi2 only) as a scene file's [thermostat] is. The energy guard's reference
  /// becomes the current state (a new thermostat's conserved quantity starts there).
  void set_thermostat(std::optional<program::ThermostatSpec> thermostat);

  /// Step to time `target` on the grid t + k dt (the last step shortened), keeping a row every
  /// output_every steps in rows when rows is given. The GIL is released while stepping; Ctrl-C
  /// stops between steps. On failure the state goes back to the last state known good.
  Report advance(double target, long output_every, Rows* rows);

 private:
  void rebuild();  ///< a new integrator for the scene's method, at the current state
  void first_row(Rows& rows) const;

  program::Scene scene_;
  std::unique_ptr<program::Integrator> integrator_;
  program::RunStart start_;  ///< the energy guard's reference (of the initial state)
  bool has_functions_ = false;
  long step_ = 0;
  double t_ = 0.0;
};

}  // namespace sesi::python
