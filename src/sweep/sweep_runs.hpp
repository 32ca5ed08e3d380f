#pragma once
/// @file sweep_runs.hpp
/// The output directory of a sweep and the runs in it (docs/sweeps.md, "Outputs"):
///
///     DIR/sweep.csv          one row per run, rewritten atomically (temp file + rename)
///     DIR/runs/NNNN/         a run's outputs as `sesi run` writes them, with scene.toml (the
///                            variant's scene), log.txt (its stdout and stderr) and
///                            sweep-run.toml (its row: the marker of a finished run)
///     DIR/.sesi-sweep-lock   held while a sweep writes into DIR
///
/// A run is the `sesi` program itself (/proc/self/exe run scene.toml --out out), started in a
/// hidden staging directory DIR/runs/.NNNN.sweep-XXXXXX; when it ends, its outputs and the
/// marker are put in place as DIR/runs/NNNN in one rename. So DIR/runs/NNNN is either absent or
/// a finished run, and a rerun of the sweep skips it when its marker and scene match. While the
/// run goes, its staging directory holds .sesi-sweep-staging (the run's pid, locked by the
/// sweep and the run): a rerun after the sweep was killed refuses while such a run still goes,
/// and removes the staging directories of runs that ended.

#include <chrono>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <sys/types.h>

#include "output_dir.hpp"
#include "sweep_file.hpp"

namespace sesi::program {

/// A run's row of sweep.csv (less the varied values, which the sweep file gives).
struct RunResult {
  long index = 0;
  /// "ok" (exit 0), "failed" (exit 3), "error" (any other end), "interrupted" (stopped by a
  /// signal: not kept, redone by a rerun), "pending" (not run yet)
  std::string status = "pending";
  int exit_status = -1;
  std::string final_energy_error, max_energy_error, max_rel_energy_error;  ///< as numbers print; empty if unknown
  double wall_seconds = 0.0;
  int rank = -1;
  std::string host;
  std::string message;  ///< the run's error line, if any
};

/// The marker file's text (TOML), and back; nothing if the text is not a marker.
std::string marker_text(const RunResult& result);
std::optional<RunResult> parse_marker(const std::string& text);

/// The sweep's exit status for these results: 0 if all ran fine, 3 if some failed with 3 and
/// none worse, 1 if some ended otherwise, 130 if some was interrupted (docs/sweeps.md).
int sweep_status(const std::vector<RunResult>& results);

/// The output directory, held by the process that hands out the runs (rank 0).
class SweepDir {
 public:
  /// Check that DIR can take the sweep's outputs (a new directory, or one with an earlier
  /// sweep's outputs and nothing foreign where this sweep writes), lock it, remove the staging
  /// directories of killed sweeps, and find the runs already done.
  /// @throws InputError (exit status 2) when DIR is unusable
  SweepDir(std::filesystem::path dir, const Sweep& sweep);

  /// Runs already done by an earlier sweep into DIR with the same scene: their results.
  const std::vector<std::optional<RunResult>>& done() const { return done_; }
  /// Write sweep.csv for these results (one per variant), atomically.
  void write_csv(const std::vector<RunResult>& results) const;
  const std::filesystem::path& path() const { return dir_; }

 private:
  std::filesystem::path dir_;
  const Sweep& sweep_;
  DirLock lock_;
  std::vector<std::optional<RunResult>> done_;
};

/// One run as a child process of this one.
class RunProcess {
 public:
  /// Make the run's staging directory, write its scene and start `sesi run` there.
  /// @param one_thread pass --threads 1 (the scene does not set threads)
  RunProcess(const std::filesystem::path& dir, const Sweep& sweep, const Variant& variant, bool one_thread);
  RunProcess(RunProcess&&) noexcept;
  RunProcess& operator=(RunProcess&&) noexcept;
  RunProcess(const RunProcess&) = delete;
  RunProcess& operator=(const RunProcess&) = delete;
  ~RunProcess();

  long index() const { return index_; }
  /// Whether the run has ended (does not wait).
  bool poll();
  /// Wait for the end of the run.
  void wait();
  /// Ask the run to stop (SIGTERM): it ends as interrupted.
  void stop();
  /// After the end: put its outputs in place as DIR/runs/NNNN with its marker, and return its
  /// row; an interrupted run's staging directory is removed instead.
  RunResult finish(int rank, const std::string& host);

 private:
  long index_ = 0;
  std::string name_;
  std::filesystem::path runs_, staging_;
  bool trajectory_ = false;
  pid_t pid_ = -1;
  int marker_fd_ = -1;  ///< the staging marker, locked while the run goes
  int wait_status_ = 0;
  bool ended_ = false, stopped_ = false;
  std::chrono::steady_clock::time_point start_;
};

/// The host name (for sweep.csv).
std::string host_name();

}  // namespace sesi::program
