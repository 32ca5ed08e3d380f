#pragma once
/// @file recorder.hpp
/// The outputs of a run, written into the (staging) output directory:
///   trajectory.csv  t, then per body b: chart q, momenta p, embedding x (trajectory_format csv);
///                   on an E^n box then the image counts n, on an H^2 surface the unwrapped point
///                   u and the word (Snapshot::image_counts, words, unwrapped)
///   trajectory.h5   the same numbers as H5MD 1.1 (trajectory_format h5md; h5md_writer.hpp)
///   diagnostics.csv t, energy, energy error, momentum-map components; with a thermostat also
///                   temperature (the target), kinetic_temperature, configurational_temperature,
///                   heat, conserved (E + the thermostat's conserved offset)
///   exact.csv       t, then per body the exact embedding point (scenes with an exact solution)
///   summary.json    method, step, energy and momentum-map statistics, final state, ...
/// Rows are written every output_every steps (and at the first and last step); the energy and
/// momentum-map maxima of the summary are taken over the checked steps (every check_every steps
/// and every output row, run_loop.cpp), not over every step.

#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "checkpoint.hpp"
#include "csv_writer.hpp"
#include "run_sink.hpp"
#include "run_types.hpp"
#include "scene.hpp"
#include "summary.hpp"

namespace sesi::program {

class ExactTrack;
class H5mdWriter;

/// Names of the momentum-map components, in sesi::momentum_map's order: P1..Pn on E^n, then
/// M1_2, M1_3, ... (1-based ambient indices a < b) of M = sum m (x v^T - v x^T).
std::vector<std::string> momentum_names(int ambient_dim, bool translations);

class Recorder final : public RunSink {
 public:
  /// Opens the output files in dir and writes their headers.
  /// @param momentum_names names of the momentum-map components (sesi::momentum_map's order)
  Recorder(const Scene& scene, std::filesystem::path dir, std::vector<std::string> momentum_names);
  /// Go on from a checkpoint: the outputs in from_dir, cut to the checkpoint's lengths, are
  /// copied into dir and extended; the statistics are the checkpoint's.
  /// @throws InputError when an output in from_dir is missing or shorter than the checkpoint says
  Recorder(const Scene& scene, std::filesystem::path dir, std::vector<std::string> momentum_names,
           const Checkpoint& from, const std::filesystem::path& from_dir);
  ~Recorder();

  /// Every checked step, from the initial state on: conserved quantities for the summary's maxima.
  void track(double energy, const Eigen::VectorXd& momentum) override;
  void track_conserved(double conserved) override;
  /// One output row (trajectory, diagnostics, exact).
  void write_row(const Snapshot& s) override;
  /// The last finite state of the run, with velocities (for the summary's final state).
  void set_final(Snapshot last) override;
  /// Closes the trajectory and CSV files and writes summary.json (ranks: the MPI ranks that ran
  /// the steps, 1 for one process).
  void finish(const RunOutcome& outcome, double wall_seconds, int ranks = 1);
  /// Across ranks, where finish() was not reached: the other ranks stop serving the final state
  /// (they serve it from the run's end until finish() has written it or this is called).
  void release_final();

  const InvariantStats& invariants() const { return stats_; }
  /// For a checkpoint: the statistics so far, and the outputs' lengths (flushed to the files).
  RecorderState state() const override;
  OutputCursor cursor() override;
  /// Per body, the largest distance from the exact solution (empty without one).
  std::vector<double> max_exact_error() const;

 private:
  /// Throws std::logic_error unless s holds the images of the scene's topology.
  void check_topology(const Snapshot& s) const;
  const Scene& scene_;
  std::filesystem::path dir_;
  std::optional<CsvWriter> trajectory_csv_;  ///< trajectory_format csv
#ifdef SESI_HAVE_HDF5
  std::unique_ptr<H5mdWriter> trajectory_h5md_;  ///< trajectory_format h5md
#endif
  CsvWriter diagnostics_;
  std::unique_ptr<ExactTrack> exact_;
  std::uint64_t frames_ = 0;  ///< rows written (trajectory.h5's frames)
  std::vector<double> row_;
  bool tracking_ = false;
  InvariantStats stats_;
  Snapshot final_;
  bool final_released_ = false;
};

}  // namespace sesi::program
