#pragma once
/// @file bench_command.hpp
/// `sesi bench` (issue #4): work-precision sweeps of the SESI compositions against the
/// reference integrators, written to DIR/work_precision.csv (docs/benchmarks.md).

#include <string>

#include <sesi/neighbours.hpp>  // default_skin_fraction

namespace CLI {
class App;
}

namespace sesi::program {

struct BenchOptions {
  std::string scene = "paper";  ///< paper | kepler-s2 | kepler-h2 | a scene file
  std::string methods;          ///< comma-separated method names (empty: all)
  double t_end = 0;             ///< 0: the scene's default
  std::string out;              ///< empty: sesi-out/bench/<scene>
  bool quick = false;
  int repeats = 0;              ///< 0: 3 (1 with --quick)
  std::string figure;           ///< seed-fig1 | convergence (data of the seed's figures)
  std::string form;             ///< seed | program (empty: the scene's, docs/benchmarks.md)
  std::string dts;              ///< comma-separated fixed steps of every fixed-step method
  std::string tols;             ///< comma-separated tolerances of every adaptive method
  double budget = 0;            ///< seconds: finer runs stop after one this long (0: 20, quick 2)

  // --horizons (issue #15): least time to each max energy error level at each run length.
  std::string horizons;         ///< comma-separated run lengths (empty: no horizon sweep)
  std::string levels;           ///< comma-separated max energy error levels (empty: the default)

  // --scaling (issue #11): time per step against the number of bodies (bench_scaling.hpp).
  bool scaling = false;
  std::string space = "sphere";            ///< sphere | hyperbolic | euclidean
  int dim = 2;
  std::string potential = "lennard-jones";  ///< lennard-jones | cotangent-gravity
  std::string sizes;                       ///< comma-separated body counts (empty: the default)
  std::string threads;                     ///< comma-separated thread counts (empty: all cores)
  long steps = 0;                          ///< timed steps per point (0: the default)
  std::string center_distances;            ///< H^n: comma-separated centre distances in radii (empty: 0)
  long check_every = 0;                    ///< the runs' check cadence (0: sesi run's default)
  double skin = sesi::default_skin_fraction;  ///< the runs' neighbour_skin
  bool box = false;                        ///< E^n in a periodic box, with LAMMPS rows (issue #26)
  bool no_lammps = false;                  ///< leave out the LAMMPS rows (--box; S^2, S^3: issue #27)
  std::string genera;                      ///< H^2: comma-separated genera of compact surfaces (empty: none)
  /// S^2 Lennard-Jones: `sesi run --threads T` against `mpirun -np T sesi run --threads 1` for each T
  /// of threads (default 2), N default 10^5 (issue #27; bench_scaling.hpp).
  bool ranks = false;
};

/// Add the `bench` subcommand to app, parsing into options.
CLI::App* add_bench_subcommand(CLI::App& app, BenchOptions& options);

/// Run it. @return the exit status.
int bench_command(const BenchOptions& options);

}  // namespace sesi::program
