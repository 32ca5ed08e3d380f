#pragma once
/// @file summary.hpp
/// The content of summary.json (docs/scene-format.md, Outputs, lists the fields).

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
};

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
};

/// summary.json as text.
std::string summary_json(const SummaryData& data);

}  // namespace sesi::program
