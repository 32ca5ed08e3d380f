#pragma once
/// @file run_command.hpp
/// `sesi run` and `sesi resume`: read the scene (or take the default), apply the command-line overrides, run it
/// into a staging directory, publish the outputs, report. Returns the exit status
/// (errors.hpp); bad input throws InputError before anything is written.
///
/// Under `mpirun -np K` (K > 1, a build with MPI; docs/parallel.md) every rank runs the same
/// command on one simulation (src/domain/): each reads and checks the scene or checkpoint itself,
/// rank 0 alone writes the outputs and reports, and every rank returns rank 0's status. Errors
/// before any step are then printed once and returned, not thrown. --threads is per rank.

#include <optional>
#include <string>

namespace sesi::program {

struct RunOptions {
  std::string scene_path;  ///< empty: the embedded default (the seed's scene)
  std::string out;         ///< empty: ./sesi-out/<scene name>
  bool out_given = false;  ///< --out was given (an empty one is refused)
  std::optional<std::string> method;  ///< a method name or "auto"
  std::optional<double> tolerance;    ///< method auto's target max relative energy error
  std::optional<double> dt;
  std::optional<double> t_end;
  std::optional<long> output_every;
  std::optional<long> threads;
  std::optional<long> check_every;
  std::optional<long> checkpoint_every;
  std::optional<double> neighbour_skin;
  std::optional<std::string> trajectory_format;
  /// The thermostat's constant temperature kT (replaces the scene's, schedule too) and noise seed;
  /// both need the scene's [thermostat] table.
  std::optional<double> temperature;
  std::optional<std::string> seed;  ///< as given: an integer from 0 to 2^63 - 1 (checked here)
  bool quiet = false;
  bool profile = false;  ///< --profile: DIR/profile.csv and a table on stderr (sesi::profile)
};

int run_command(const RunOptions& options);

/// `sesi resume DIR`: go on from DIR's checkpoint (or from that of a killed run into DIR) to the
/// end of the run, or to a later end; the outputs are extended as if the run had not stopped.
struct ResumeOptions {
  std::string dir;
  std::optional<double> t_end;
  std::optional<long> threads;
  bool quiet = false;
  bool profile = false;  ///< --profile: the resumed steps' profile (DIR/profile.csv)
};

int resume_command(const ResumeOptions& options);

}  // namespace sesi::program
