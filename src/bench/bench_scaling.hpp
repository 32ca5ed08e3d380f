#pragma once
/// @file bench_scaling.hpp
/// `sesi bench --scaling` (issue #11, docs/benchmarks.md): seconds per step of `sesi run`'s own
/// loop (default checks and cadence) against the number of bodies, with, in the same run, the
/// same bodies on flat E^3 through sesi's Euclidean path and a plain flat 3-D Lennard-Jones
/// cell-list loop, so that every figure can be read as a ratio; with --box (E^n) LAMMPS on the
/// same bodies, on S^2 and S^3 LAMMPS on the E^n box at the same N and density (issue #27; not
/// with --no-lammps), with --genus (H^2) the compact surfaces and the E^2 box at the same N (issue
/// #26). Each point runs in a child process, so that its peak resident memory is its own.
/// Writes DIR/scaling.csv. With --ranks (issue #27, docs/parallel.md) instead: `sesi run --threads T`
/// against `mpirun -np T sesi run --threads 1` on one S^2 scene file, as child processes timed by
/// their profile.csv, into DIR/ranks.csv.

#include "bench_command.hpp"

namespace sesi::program::bench {

/// Body counts of the default sweep.
inline constexpr const char* default_sizes = "1000,3000,10000,30000,100000";

/// Run the sweep of options (options.scaling set). @return the exit status.
int scaling_command(const BenchOptions& options);

}  // namespace sesi::program::bench
