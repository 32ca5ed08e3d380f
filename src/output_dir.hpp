#pragma once
/// @file output_dir.hpp
/// Atomic outputs: a run writes into a fresh staging directory next to the output directory
/// (".NAME.sesi-XXXXXX" in the same parent) and, when it ends, the staging directory replaces
/// the output directory in one rename (an atomic exchange where the file system supports it).
/// Until then an existing output directory is untouched; a run killed outright leaves only the
/// hidden staging directory, never a file that looks finished.
///
/// An existing output directory is replaced only if it holds nothing but sesi outputs
/// (trajectory.csv, trajectory.h5, diagnostics.csv, exact.csv, summary.json and plots *.png,
/// *.pdf, *.svg), so a mistyped --out never deletes other files.

#include <filesystem>
#include <string>

#include "errors.hpp"

namespace sesi::program {

class StagingDir {
 public:
  /// Check that target can be written (or replaced) and create the staging directory.
  /// @throws InputError (exit status 2) naming `option` when target is unusable
  StagingDir(std::filesystem::path target, const std::string& option);
  /// Removes the staging directory unless it was published.
  ~StagingDir();
  StagingDir(const StagingDir&) = delete;
  StagingDir& operator=(const StagingDir&) = delete;

  const std::filesystem::path& path() const { return staging_; }
  const std::filesystem::path& target() const { return target_; }
  /// Move the staging directory into place as the target (replacing an earlier one).
  void publish();

 private:
  std::filesystem::path target_, staging_;
  bool published_ = false;
};

}  // namespace sesi::program
