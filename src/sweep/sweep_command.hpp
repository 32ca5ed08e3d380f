#pragma once
/// @file sweep_command.hpp
/// `sesi sweep SWEEP.toml --out DIR` (docs/sweeps.md): every variant of a base scene that the
/// sweep file describes, each run exactly as `sesi run` runs its scene, on this machine's cores
/// and, under mpirun or srun, on every rank (handed out one at a time by rank 0).

#include <optional>
#include <string>

#include <CLI/CLI.hpp>

namespace sesi::program {

struct SweepOptions {
  std::string file;
  std::string out;          ///< empty: ./sesi-out/<sweep file name>
  std::optional<long> jobs;  ///< runs at a time in this process (rank 0)
  bool quiet = false;
  bool check = false;  ///< check the sweep and every variant, run nothing
};

/// Add the `sweep` subcommand to app; its values go to options.
CLI::App* add_sweep_subcommand(CLI::App& app, SweepOptions& options);

/// Run the sweep; returns the exit status (the worst run's, docs/sweeps.md).
int sweep_command(const SweepOptions& options);

}  // namespace sesi::program
