#pragma once
/// @file summary.hpp
/// The content of summary.json (docs/scene-format.md, Outputs, lists the fields).

#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "run_types.hpp"
#include "scene.hpp"

namespace sesi::program {

/// Statistics of the conserved quantities over the checked steps of a run (run_loop.hpp).
struct InvariantStats {
  double energy_initial = 0.0, energy_final = 0.0;
  double max_abs_energy_error = 0.0, max_rel_energy_error = 0.0;
  std::vector<std::string> momentum_names;
  Eigen::VectorXd momentum_initial, momentum_final;
  double max_momentum_drift = 0.0;
  /// H^n: the largest distance of a body from the scene chart's origin over the output rows,
  /// where the q, p columns (the scene's chart) are read (scene_chart_p_error).
  double max_distance = 0.0;
  /// A thermostatted run: the conserved quantity E + conserved_offset() over the checked steps
  /// (NaN for brownian), and sums over the output rows, each added in row order (the same bits
  /// for any thread count and across a resume): rows, kinetic temperatures, the configurational
  /// sums {|grad V|^2, Laplacian V} of the rows that have them; the heat at the last row.
  bool conserved_tracking = false;
  double conserved_initial = 0.0, conserved_final = 0.0, max_abs_conserved_drift = 0.0;
  long thermostat_rows = 0;
  double sum_kinetic_temperature = 0.0, sum_grad_squared = 0.0, sum_laplacian = 0.0, heat = 0.0;
};

/// H^n: the relative error to expect of momenta p read in the scene's polar chart at distance d
/// from its origin (radius R): eps e^{2 d / R}. The chart's p is recomputed from world points of
/// size e^{d/R} whose O(1) differences cancel (docs/stability.md, "Far from the origin").
double scene_chart_p_error(double distance, double radius);

/// Distances from an exact solution (empty when the scene has none).
struct ExactStats {
  std::string solution;
  std::vector<double> max_position_error, final_position_error;
};

struct SummaryData {
  const Scene& scene;
  const RunOutcome& outcome;
  long planned_steps;
  double wall_seconds;
  const InvariantStats& invariants;
  const Snapshot& final_state;
  const ExactStats& exact;
  int ranks = 1;  ///< the MPI ranks that ran the steps (`mpirun -np K sesi run`), 1 for one process
};

/// summary.json written into path (whole or absent: write_file_atomically), streamed: its final
/// state is never held as one string. Throws std::runtime_error on a write error.
void write_summary(const SummaryData& data, const std::filesystem::path& path);

}  // namespace sesi::program
