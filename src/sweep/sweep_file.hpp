#pragma once
/// @file sweep_file.hpp
/// Sweep files (TOML, docs/sweeps.md) to the list of runs they describe: a base scene and
/// `[[vary]]` tables, each a list of values for one key of the scene or random perturbations of
/// it; several tables form the Cartesian product. Every variant's scene is written out as TOML
/// and read back by the scene reader, so a sweep is refused (InputError, exit status 2) before
/// anything runs when any of its variants is not a valid scene.

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace sesi::program {

/// One run of a sweep.
struct Variant {
  long index = 0;
  std::vector<std::string> values;  ///< the varied values, one per column of Sweep::columns
  std::string scene_text;           ///< the complete scene (TOML), as the run reads it
  bool sets_threads = false;        ///< the scene gives [integrator] threads
};

struct Sweep {
  std::filesystem::path file;        ///< the sweep file as given
  std::filesystem::path scene_path;  ///< the base scene, relative to the sweep file
  bool trajectory = false;           ///< keep each run's trajectory file
  std::vector<std::string> columns;  ///< names of the varied values ("integrator.dt", "bodies.0.x.1")
  std::vector<Variant> variants;     ///< in index order: the first [[vary]] varies slowest
};

/// At most this many runs in one sweep: every variant is built, checked (about 40 us each for a
/// small scene: 4 s for the cap) and held in memory before the first run, and each run is a
/// process, a folder in runs/ and a row of sweep.csv, which is rewritten as runs end.
inline constexpr long max_sweep_runs = 100'000;

/// The name of run `index` of `total`: its index with leading zeros, at least 4 digits ("0042").
std::string run_name(long index, long total);

/// Read the sweep file at path, build and check every variant.
/// @throws InputError naming the file, the line and the key when anything is wrong
Sweep read_sweep_file(const std::filesystem::path& path);

/// The reproducible uniform draws of a perturbation: component i of copy k of a `[[vary]]` table
/// with the given seed, in [-1, 1). std::mt19937_64 seeded with seed + k (mod 2^64), its 53 high
/// bits of each draw mapped to [0, 1) exactly, then 2u - 1: the same doubles on every platform.
std::vector<double> perturbation_draws(std::uint64_t seed, long copy, int count);

}  // namespace sesi::program
