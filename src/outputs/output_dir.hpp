#pragma once
/// @file output_dir.hpp
/// Atomic outputs: a run writes into a fresh staging directory next to the output directory
/// (".NAME.sesi-XXXXXX" in the same parent) and, when it ends, the staging directory replaces
/// the output directory in one rename (an atomic exchange where the file system supports it).
/// Until then an existing output directory is untouched; a run killed outright leaves only the
/// hidden staging directory, never a file that looks finished.
///
/// A mount point cannot be renamed over: for one, the staging directory and the lock are inside
/// it (".sesi-XXXXXX", ".sesi-lock"), and the files are moved in one by one.
///
/// Nothing that sesi did not write is ever deleted:
/// - every output directory holds the run's manifest (sesi-manifest.txt), the files sesi wrote;
///   a run repeated into it replaces exactly those and keeps the rest, named on stderr;
/// - an existing output directory is accepted only if it holds nothing but those (without a
///   manifest, an older sesi's: trajectory.csv, trajectory.h5, diagnostics.csv, exact.csv,
///   summary.json, checkpoint) and pictures (*.png, *.pdf, *.svg: kept unless the manifest lists
///   them), so a mistyped --out never deletes other files;
/// - entries added to it during the run are moved into the new outputs, and named on stderr;
/// - a run that did not complete never replaces a complete earlier run: it goes to DIR.incomplete;
/// - a lock file in the parent (".NAME.sesi-lock", flock) keeps two runs out of one directory;
/// - holding the lock, a run removes the staging directories of killed runs into the same
///   directory (marked by sesi, holding only sesi outputs) and names any other such folder.

#include <cstdio>
#include <filesystem>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include <sys/types.h>

#include "errors.hpp"

namespace sesi::program {

/// An exclusive flock() on a lock file, held while this lives; the file is removed on release.
class DirLock {
 public:
  DirLock() = default;
  ~DirLock();
  DirLock(const DirLock&) = delete;
  DirLock& operator=(const DirLock&) = delete;

  /// Lock `file` (created if missing) and write this process's id into it.
  /// @throws InputError "KEY: is in use by another sesi run (pid N)" when another process holds it
  void acquire(const std::filesystem::path& file, const std::string& key);

 private:
  int fd_ = -1;
  std::filesystem::path file_;
};

class StagingDir {
 public:
  /// Check that target can be written (or replaced), lock it, clean up after killed runs, and
  /// create the staging directory.
  /// @throws InputError (exit status 2) naming `option` when target is unusable or in use
  /// @param resuming a killed run's staging directory that `sesi resume` goes on from: left
  ///        alone and not named
  StagingDir(std::filesystem::path target, const std::string& option, const std::filesystem::path& resuming = {});
  /// Removes the staging directory unless it was published; releases the lock.
  ~StagingDir();
  StagingDir(const StagingDir&) = delete;
  StagingDir& operator=(const StagingDir&) = delete;

  const std::filesystem::path& path() const { return staging_; }
  const std::filesystem::path& target() const { return target_; }
  /// Move the staging directory into place and return where the outputs now are: the target
  /// (replacing the earlier outputs there and keeping anything else found in it), or, when
  /// `complete` is false and the target holds a complete earlier run, "TARGET.incomplete",
  /// so that an interrupted or failed re-run never costs a finished one.
  std::filesystem::path publish(bool complete = true);

 private:
  using Entry = std::pair<std::string, std::pair<dev_t, ino_t>>;

  std::filesystem::path publish_to(const std::filesystem::path& dest, const std::vector<Entry>& earlier);
  /// The run's manifest (sesi-manifest.txt) in the staging directory: what it holds.
  void write_manifest();
  /// publish() for a target that is a mount point: the files moved in one by one.
  std::filesystem::path publish_inside(bool complete);
  /// Move the staged files into dest one by one, replacing the `earlier` files there.
  std::filesystem::path move_into(const std::filesystem::path& dest, const std::vector<Entry>& earlier);

  DirLock lock_;
  std::filesystem::path target_, staging_;
  std::vector<Entry> earlier_;  ///< the target's entries when the run started (sesi outputs)
  std::pair<dev_t, ino_t> earlier_dir_{};  ///< the target directory itself then, if it existed
  bool published_ = false;
  bool inside_ = false;  ///< the target is a mount point: staging, lock and publishing inside it
};

/// Remove `dir`, a stopped run's outputs that a resumed run has gone on from and published
/// elsewhere (a killed run's staging directory, or DIR.incomplete), file by file, if it holds
/// nothing but sesi outputs; otherwise leave it. Returns whether it was removed.
bool remove_superseded(const std::filesystem::path& dir);

/// For a tool that adds files to a finished run's outputs (`sesi analyze`): take the lock that a
/// run into `dir` takes (so no run replaces dir meanwhile), as DirLock::acquire does.
void lock_output_dir(DirLock& lock, const std::filesystem::path& dir, const std::string& key);
/// Whether dir's manifest (sesi-manifest.txt) lists `name` as a file sesi wrote there.
bool manifest_lists(const std::filesystem::path& dir, const std::string& name);
/// Whether dir has a manifest.
bool has_manifest(const std::filesystem::path& dir);
/// Add `names` to dir's manifest (replaced atomically), so that a run repeated into dir replaces
/// them like its other outputs. Throws std::runtime_error on a write error.
void add_to_manifest(const std::filesystem::path& dir, const std::vector<std::string>& names);

/// `path` as the user should see it in a message: a path inside a live staging directory is
/// shown inside its output directory (the --out the user gave), never the temporary name.
std::filesystem::path shown_path(const std::filesystem::path& path);

/// text into path through a temporary file beside it and a rename, so that the file is whole
/// or absent; a write error throws std::runtime_error naming path as shown_path shows it.
void write_file_atomically(const std::filesystem::path& path, const std::string& text);
/// As above, the file's bytes written by `write` to the open file (a document too large to hold
/// as one string: summary.json's final state at 10^6 bodies); `write` returns false on an error.
void write_file_atomically(const std::filesystem::path& path, const std::function<bool(std::FILE*)>& write);

}  // namespace sesi::program
