#pragma once
/// @file checkpoint.hpp
/// Checkpoints: what a run needs to go on exactly as if it had not stopped (docs/scene-format.md,
/// "Checkpoints and resume"). A checkpoint holds the scene model as read and the integrator
/// settings in force (not the scene file, which may have changed since), the energy guard's
/// reference, the framed state as stepped (integrator.hpp), the step, the outputs' lengths at
/// that step and the running statistics of the summary. Doubles are written as hex floats
/// (exact). The first line names the format and its version, the length of what follows and
/// its checksum (FNV-1a, 64 bits), so that a truncated, corrupted or foreign file is refused; the
/// file is replaced atomically (written beside, flushed to disk, renamed).

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "integrator.hpp"
#include "run_types.hpp"
#include "scene.hpp"
#include "summary.hpp"

namespace sesi::program {

/// The name of the checkpoint file in an output directory.
inline constexpr const char* checkpoint_file_name = "checkpoint";

/// The outputs at the checkpoint's step: the byte length of each file with the rows that an
/// uninterrupted run has written by then (a stop row written after it is cut on resume), and the
/// frames of trajectory.h5.
struct OutputCursor {
  std::uint64_t trajectory_bytes = 0;   ///< trajectory.csv (trajectory_format csv)
  std::uint64_t diagnostics_bytes = 0;  ///< diagnostics.csv
  std::uint64_t exact_bytes = 0;        ///< exact.csv (scenes with an exact solution)
  std::uint64_t trajectory_frames = 0;  ///< trajectory.h5 (trajectory_format h5md)
};

/// The running statistics of the recorder (recorder.hpp) and of the exact track.
struct RecorderState {
  bool tracking = false;
  InvariantStats stats;  ///< without momentum_names (the recorder knows them)
  std::vector<double> exact_max_error, exact_last_error;
};

struct Checkpoint {
  /// The format's versions: 1 holds a chart method's state (q, p, frames, cluster), 2 the same
  /// but for a geodesic method's embedded state (x, v) in their place, 3 a thermostatted run's:
  /// version 1's with the scene's [thermostat], the thermostat's saved state (its step counter,
  /// heat and chain variables: nothing random but the seed and the step) and the summary's
  /// thermostat statistics. 4 a run on a topology (an E^n box or an H^2 surface; chart methods
  /// only): version 1's, or 3's with a thermostat, with the space's box or genus and the bodies'
  /// image record (FramedState::image_counts, words) after the state. A chart method's NVE
  /// checkpoint is still written as version 1 (what an older sesi reads), a geodesic method's as
  /// version 2, a thermostatted one as version 3 and one on a topology as version 4 (which an
  /// older sesi refuses as a version it does not read).
  static constexpr int version = 2;
  static constexpr int chart_version = 1;
  static constexpr int thermostat_version = 3;
  static constexpr int topology_version = 4;
  /// The version that holds this checkpoint's state.
  int file_version() const {
    if (scene.space.has_topology()) return topology_version;
    return state.embedded ? version : scene.thermostat ? thermostat_version : chart_version;
  }
  Scene scene;  ///< the scene model with the settings in force; bodies' q, p unused (see state)
  double guard_energy = 0.0, guard_scale = 0.0;  ///< the energy guard's E0 and K0 + |V0|
  long step = 0;  ///< the state is the one after this step
  FramedState state;
  OutputCursor outputs;
  RecorderState recorder;
};

/// Write c to dir/checkpoint atomically. Throws std::runtime_error naming shown_dir (the
/// directory the user knows) on a write error.
void write_checkpoint(const Checkpoint& c, const std::filesystem::path& dir,
                      const std::filesystem::path& shown_dir);

/// Read and check the checkpoint file at path. Throws InputError (one line naming path) when it
/// is missing, truncated, corrupted (checksum), of another format or version, or inconsistent.
Checkpoint read_checkpoint(const std::filesystem::path& path);

}  // namespace sesi::program
