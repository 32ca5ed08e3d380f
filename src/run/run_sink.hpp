#pragma once
/// @file run_sink.hpp
/// Where the run loop (run_loop.hpp) hands what it finds: the conserved quantities at the
/// checks, the output rows, the last state known good. The program's Recorder writes them to
/// files (recorder.hpp); the Python package keeps them in arrays (python/).

#include <Eigen/Core>

#include "checkpoint.hpp"
#include "run_types.hpp"

namespace sesi::program {

class RunSink {
 public:
  virtual ~RunSink() = default;
  /// Every checked step, from the initial state on (the integrator holds that state).
  virtual void track(double energy, const Eigen::VectorXd& momentum) = 0;
  /// A thermostatted run's conserved quantity at every checked step, after track (Snapshot::
  /// conserved; the summary's drift).
  virtual void track_conserved(double conserved) { static_cast<void>(conserved); }
  /// One output row (every output_every steps, the first and the last).
  virtual void write_row(const Snapshot& s) = 0;
  /// The last state known good, with velocities.
  virtual void set_final(Snapshot last) = 0;
  /// For a checkpoint (taken only when RunControl::checkpoint is set): the outputs' lengths and
  /// the statistics so far.
  virtual OutputCursor cursor() { return {}; }
  virtual RecorderState state() const { return {}; }
};

}  // namespace sesi::program
