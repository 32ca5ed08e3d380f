#pragma once
/// @file bench_scaling_scenes.hpp
/// The many-body scenes of `sesi bench --scaling` (issue #11, docs/benchmarks.md), made in
/// memory and reproducibly (a fixed seed, std::mt19937_64 and our own normal deviates, so the
/// bodies do not depend on the standard library): bodies at density 1/2 (one per area or volume
/// 2 sigma^n) with random tangent velocities, and the flat reference, a plain 3-D Lennard-Jones
/// cell-list loop.

#include <cstdint>
#include <optional>
#include <string>

#include "scene.hpp"

namespace sesi::program::bench {

/// What a scaling point runs.
struct ScalingPoint {
  SpaceKind space = SpaceKind::sphere;
  int dim = 2;
  std::string potential = "lennard-jones";  ///< lennard-jones | cotangent-gravity
  std::string method = "sesi2";
  int bodies = 1000;
  double center_distance = 0;  ///< H^n: the cluster's centre this many radii from the origin
  long check_every = 0;        ///< the run's check cadence (0: sesi run's default)
  double neighbour_skin = sesi::default_skin_fraction;
  /// Topologies (issue #26). E^n: a periodic box of edge (N / density)^(1/n) (SpaceSpec::box);
  /// H^2: genus g >= 2, the compact surface of area N / density, R = (N / (4 pi (g - 1) density))^(1/2).
  bool box = false;
  int genus = 0;
};

/// Lennard-Jones of the scaling scenes: epsilon = sigma = 1, cutoff 2.5 sigma, dt 0.002.
inline constexpr double lj_cutoff = 2.5, lj_dt = 0.002;
/// Cotangent gravity: G = 1/N, speeds ~0.1, dt 0.01.
inline constexpr double gravity_dt = 0.01;

/// The radius of S^n holding `bodies` at density 1/2; the scaling scenes on H^n use it too.
double scaling_radius(int dim, int bodies);
/// The edge of the periodic box of E^n holding `bodies` at density 1/2.
double box_edge(int dim, int bodies);
/// The radius R of the genus-g surface holding `bodies` at density 1/2: area 4 pi (g - 1) R^2.
double surface_radius(int genus, int bodies);

/// The scene of a point. S^2: a Fibonacci lattice; H^2: the same spiral on a geodesic disc
/// (equal areas), moved center_distance radii away by a boost; other S^n, H^n (a geodesic ball)
/// and E^n (a cube): random sequential addition, uniform points each kept when no kept point
/// is within 1 sigma; a periodic box or a compact surface: the same in the fundamental domain,
/// with the minimum-image distance. Velocities: normal deviates projected on the tangent
/// space, unit temperature for Lennard-Jones, 0.1 for gravity. t_end = 0: the caller sets it.
Scene scaling_scene(const ScalingPoint& point, std::uint64_t seed = 1);

/// Pairs of bodies closer than `cutoff` at the scene's initial state (through the neighbour
/// index), or all pairs for cutoff = infinity.
long pairs_within(const Scene& scene, double cutoff);

/// The plain flat reference: N bodies in a periodic cube at density 1/2, Lennard-Jones (cutoff
/// 2.5, truncated), velocity Verlet with dt 0.002, a cell list rebuilt every step, each pair once
/// (half of the neighbour cells), one thread. Returns the seconds per step over `steps` steps
/// and sets `pairs` to the pairs within the cutoff at the end.
double flat_cell_list_seconds_per_step(int bodies, long steps, long& pairs);

/// The first executable `name` on PATH, or "".
std::string on_path(const std::string& name);

/// LAMMPS (the program `lmp`, issue #26) on the bodies of a scene in a periodic box of E^2 or E^3
/// (scaling_scene with box): the same Lennard-Jones (lj/cut 2.5, pair_modify shift yes), skin
/// (neighbor bin, cutoff x neighbour_skin; neigh_modify every 1 delay 0 check yes) and velocity
/// Verlet step (fix nve, dt), on `ranks` MPI ranks (mpirun -np ranks when ranks > 1). Seconds per
/// step: LAMMPS' own "Loop time" of a run of `steps` steps after a run of `warm` steps, with
/// thermo output only at the ends. Returns nothing, with `why` set, when lmp (or mpirun) is not
/// found or the run fails.
/// Why LAMMPS cannot run on `ranks` ranks here ("" when it can): lmp, or for ranks > 1 mpirun, not
/// on PATH.
std::string lammps_unavailable(int ranks);
std::optional<double> lammps_seconds_per_step(const Scene& scene, int ranks, long warm, long steps, std::string& why);

}  // namespace sesi::program::bench
