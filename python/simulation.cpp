#include "simulation.hpp"

#include <chrono>
#include <cmath>
#include <limits>
#include <utility>

#include <pybind11/eigen.h>
#include <sesi/parallel.hpp>

#include "auto_method.hpp"
#include "errors.hpp"
#include "recorder.hpp"  // momentum_names
#include "run_sink.hpp"
#include "scene_table.hpp"
#include "validate.hpp"

namespace sesi::python {

using program::InputError;
using program::Origin;

// ---- Python potentials ------------------------------------------------------------------------

PythonFunctions::PythonFunctions(py::function value, py::function gradient)
    : value_(std::move(value)), gradient_(std::move(gradient)) {}

PythonFunctions::~PythonFunctions() {
  // The last copy may go in a thread without the GIL (a system's terms, after a run).
  py::gil_scoped_acquire gil;
  value_ = py::function();
  gradient_ = py::function();
}

double PythonFunctions::value(const Eigen::VectorXd& x, double m) const {
  py::gil_scoped_acquire gil;
  return value_(x, m).cast<double>();
}

void PythonFunctions::gradient(const Eigen::VectorXd& x, double m, Eigen::VectorXd& g) const {
  py::gil_scoped_acquire gil;
  const auto out = gradient_(x, m).cast<Eigen::VectorXd>();
  if (out.size() != x.size()) {
    throw InputError("add_potential: gradient(x, m) returned " + std::to_string(out.size()) +
                     " values for a point of " + std::to_string(x.size()) + " coordinates");
  }
  g = out;
}

// ---- the run's sink: rows in memory, the last state known good ------------------------------

namespace {

/// A topology's columns of a row (Rows::unwrapped, image_counts, words), from the run's snapshot
/// (its image record, filled by the run loop; trajectory.csv's numbers).
void topology_row(const program::Scene& scene, const program::Snapshot& s, Rows& rows) {
  if (!scene.space.has_topology()) return;
  if (!scene.space.box.empty()) {
    rows.image_counts.push_back(s.image_counts.transpose());
    // Unwrapped x + L .* n: exact in the counts (Integrator::unwrapped_points, the same arithmetic).
    Eigen::MatrixXd u = s.x;
    for (Eigen::Index b = 0; b < u.cols(); ++b) {
      for (Eigen::Index k = 0; k < u.rows(); ++k) {
        u(k, b) += scene.space.box[static_cast<std::size_t>(k)] * static_cast<double>(s.image_counts(k, b));
      }
    }
    rows.unwrapped.push_back(u.transpose());
  } else {
    rows.unwrapped.push_back(s.unwrapped.transpose());
    std::vector<std::string> words;
    for (const auto& w : s.words) words.push_back(program::word_text(w));
    rows.words.push_back(std::move(words));
  }
}

class ArraySink final : public program::RunSink {
 public:
  ArraySink(const program::Scene& scene, program::Integrator& integrator, Rows* rows)
      : scene_(scene), integrator_(integrator), rows_(rows) {
    good_ = integrator.framed_state();
  }
  void track(double, const Eigen::VectorXd&) override { good_ = integrator_.framed_state(); }
  void write_row(const program::Snapshot& s) override {
    if (!rows_) return;
    rows_->t.push_back(s.t);
    rows_->energy.push_back(s.energy);
    rows_->q.push_back(s.q.transpose());
    rows_->p.push_back(s.p.transpose());
    rows_->x.push_back(s.x.transpose());
    rows_->v.push_back(s.v.transpose());
    rows_->momentum.push_back(s.momentum);
    topology_row(scene_, s, *rows_);
  }
  void set_final(program::Snapshot last) override { final_ = std::move(last); }

  const program::FramedState& good() const { return good_; }
  const program::Snapshot& final() const { return final_; }

 private:
  const program::Scene& scene_;
  program::Integrator& integrator_;
  Rows* rows_;
  program::FramedState good_;
  program::Snapshot final_;
};

const Origin option{};  // a setting of the Python API: messages name the key alone

}  // namespace

// ---- Simulation ---------------------------------------------------------------------------------

Simulation::Simulation(const toml::table& doc, const std::string& source,
                       std::vector<std::shared_ptr<const program::FunctionExternalSpec::Functions>> functions)
    : scene_(program::read_scene_table(doc, source)) {
  for (auto& f : functions) {
    scene_.potentials.emplace_back(program::FunctionExternalSpec{std::move(f)});
    has_functions_ = true;
    // An external term on a box or a surface: refused as a scene's (numbered after its tables).
    const std::string term = "potential[" + std::to_string(scene_.potentials.size()) + "].";
    program::check_topology_potential(scene_.potentials.back(), scene_.space, [&](std::string_view key) {
      return std::pair{Origin{source}, term + std::string(key)};
    });
  }
  program::resolve_auto(scene_);  // method = "auto": pilot runs, then the method and step
  rebuild();
  start_ = program::guard_reference(scene_, *integrator_);
}

Simulation::Simulation(program::Scene scene) : scene_(std::move(scene)) {
  program::resolve_auto(scene_);
  rebuild();
  start_ = program::guard_reference(scene_, *integrator_);
}

void Simulation::rebuild() {
  // At the current state as the outputs show it (a processed method's post-processed state, not
  // its kernel's variables); between a chart method and a geodesic method (whose states are of
  // different kinds) through the scene's chart.
  integrator_ = integrator_ ? program::make_integrator(scene_, *integrator_) : program::make_integrator(scene_);
}

Eigen::MatrixXd Simulation::q() const {
  Eigen::MatrixXd q, p;
  integrator_->read(q, p);
  return q.transpose();
}
Eigen::MatrixXd Simulation::p() const {
  Eigen::MatrixXd q, p;
  integrator_->read(q, p);
  return p.transpose();
}
Eigen::MatrixXd Simulation::x() const { return integrator_->points().transpose(); }
Eigen::MatrixXd Simulation::v() const { return integrator_->velocities().transpose(); }
Eigen::VectorXd Simulation::masses() const {
  Eigen::VectorXd m(scene_.body_count());
  for (int b = 0; b < scene_.body_count(); ++b) m(b) = scene_.bodies[static_cast<std::size_t>(b)].mass;
  return m;
}
ImageCounts Simulation::image_counts() const { return integrator_->image_counts().transpose(); }
std::vector<std::string> Simulation::words() const {
  std::vector<std::string> out;
  for (const auto& w : integrator_->words()) out.push_back(program::word_text(w));
  return out;
}
Eigen::MatrixXd Simulation::unwrapped_points() const { return integrator_->unwrapped_points().transpose(); }
double Simulation::energy() const { return integrator_->energy(); }
Eigen::VectorXd Simulation::momentum_map() const { return integrator_->momentum_map(); }
std::vector<std::string> Simulation::momentum_names() const {
  const bool euclidean = scene_.space.kind == program::SpaceKind::euclidean;
  return program::momentum_names(euclidean ? scene_.dim() : scene_.dim() + 1, euclidean);
}

void Simulation::set_method(const std::string& method) {
  if (method == "auto") {
    throw program::InputError(option, "method",
                              "\"auto\" is chosen once, from a scene with [integrator] method = \"auto\", "
                              "tolerance and t_end (Simulation.from_toml or from_dict); name a method here");
  }
  program::check_method(method, option, "method");
  if (method == scene_.integrator.method) return;  // the same method goes on as it was, bit for bit
  const std::string before = scene_.integrator.method;
  scene_.integrator.method = method;
  try {
    program::check_thermostat_method(scene_, option, "method");  // a thermostat: sesi2 only
    program::check_topology_method(scene_, option, "method");    // a topology: chart compositions
    rebuild();  // refuses a geodesic method on E^n
  } catch (...) {
    scene_.integrator.method = before;
    throw;
  }
}
void Simulation::set_dt(double dt) {
  program::check_dt(dt, option, "dt");
  scene_.integrator.dt = dt;
}
void Simulation::set_energy_guard(double threshold) {
  if (threshold == 0.0) {
    scene_.integrator.energy_guard = 0.0;  // off
    return;
  }
  program::check_energy_guard(threshold, option, "energy_guard");
  scene_.integrator.energy_guard = threshold;
}
void Simulation::set_threads(long threads) {
  program::check_threads(threads, option, "threads");
  scene_.integrator.threads = static_cast<int>(threads);
}
void Simulation::set_check_every(long check_every) {
  if (check_every != 0) program::check_check_every(check_every, option, "check_every");
  scene_.integrator.check_every = check_every;
}

void Simulation::set_thermostat(std::optional<program::ThermostatSpec> thermostat) {
  std::optional<program::ThermostatSpec> before = std::move(scene_.thermostat);
  scene_.thermostat = std::move(thermostat);
  try {
    program::check_thermostat_method(scene_, option, "method");
    rebuild();
  } catch (...) {
    scene_.thermostat = std::move(before);
    throw;
  }
  start_ = program::guard_reference(scene_, *integrator_);
}

void Simulation::first_row(Rows& rows) const {
  program::Snapshot s;
  s.t = t_;
  integrator_->read(s.q, s.p);
  s.x = integrator_->points();
  s.v = integrator_->velocities();
  s.energy = integrator_->energy();
  s.momentum = integrator_->momentum_map();
  if (!scene_.space.box.empty()) s.image_counts = integrator_->image_counts();
  if (scene_.space.genus != 0) {
    s.words = integrator_->words();
    s.unwrapped = integrator_->unwrapped_points();
  }
  rows.t.push_back(s.t);
  rows.energy.push_back(s.energy);
  rows.q.push_back(s.q.transpose());
  rows.p.push_back(s.p.transpose());
  rows.x.push_back(s.x.transpose());
  rows.v.push_back(s.v.transpose());
  rows.momentum.push_back(s.momentum);
  topology_row(scene_, s, rows);
}

Report Simulation::advance(double target, long output_every, Rows* rows) {
  if (!std::isfinite(target)) throw InputError(option, "t", "expected a finite time, got " + program::format_number(target));
  if (!scene_.integrator.dt) throw InputError(option, "dt", "no step size: set dt before integrating");
  const double dt = *scene_.integrator.dt;
  const double sign = dt > 0 ? 1.0 : -1.0;
  if (sign * (target - t_) < 0.0) {
    throw InputError(option, "t",
                     "t = " + program::format_number(target) + " is " + (dt > 0 ? "before" : "after") +
                         " the simulation's time " + program::format_number(t_) + " with dt = " +
                         program::format_number(dt) + "; give dt the other sign to go there");
  }
  if (output_every < 1) throw InputError(option, "output_every", "expected an integer >= 1");
  if (rows) first_row(*rows);
  if (target == t_) return {};
  program::check_step_count(std::abs(target - t_), dt, option, "t");

  scene_.integrator.t_end = sign * target;
  scene_.integrator.output_every = output_every;
  program::RunStart start = start_;
  start.step = step_;
  start.t = t_;

  // Python potentials are called with the GIL: one thread, so that an exception they raise comes
  // back through the loop (never out of a parallel region).
  sesi::parallel::set_threads(has_functions_ ? 1 : scene_.integrator.threads);
  const program::FramedState before = integrator_->framed_state();
  ArraySink sink(scene_, *integrator_, rows);
  std::atomic<bool> stop{false};
  bool interrupted = false;
  auto last_poll = std::chrono::steady_clock::now();
  program::RunControl control;
  control.interrupted = &stop;
  control.after_step = [&](long) {
    // Ctrl-C: Python's handler only flags the signal; it runs (raising KeyboardInterrupt) when
    // asked with the GIL, here every 50 ms.
    const auto now = std::chrono::steady_clock::now();
    if (now - last_poll < std::chrono::milliseconds(50)) return;
    last_poll = now;
    py::gil_scoped_acquire gil;
    if (PyErr_CheckSignals() != 0) {
      interrupted = true;
      stop.store(true);
    }
  };

  program::RunOutcome outcome;
  try {
    py::gil_scoped_release release;
    outcome = program::run_loop(scene_, *integrator_, sink, control, start);
  } catch (...) {
    // An exception from a Python potential (or a library invariant): back to the start.
    integrator_->restore(before);
    throw;
  }
  Report report;
  report.complete = outcome.complete();
  report.reason = program::stop_reason_name(outcome.reason);
  report.detail = outcome.detail;
  report.failed_step = outcome.failed_step;
  report.failed_t = outcome.failed_t;
  report.failed_body = outcome.failed_body;
  report.interrupted = interrupted;
  if (outcome.complete()) {
    step_ = sink.final().step;
    t_ = sink.final().t;
  } else {
    integrator_->restore(sink.good());
    step_ = sink.final().step;
    t_ = sink.final().t;
  }
  return report;
}

}  // namespace sesi::python
