#pragma once
/// @file bench_scenes.hpp
/// The scenes of `sesi bench` (issue #4), one translation unit each (bench_scene_*.cpp).

#include <string>

#include "bench_types.hpp"
#include "scene.hpp"

namespace sesi::program::bench {

/// Default length of the built-in scenes' runs (full, quick).
inline constexpr double paper_t_end = 800.0, kepler_t_end = 200.0, quick_t_end = 20.0;

/// The seed's scene (shared/paper-scene.md) against its exact solution.
Result bench_paper(const Settings& settings);
/// The curved Kepler problem on S^2 and H^2 against a reference run.
Result bench_kepler_s2(const Settings& settings);
Result bench_kepler_h2(const Settings& settings);
/// Any scene file of the program (S^n, H^n of dimension 2 or 3) against its exact solution
/// (the seed's scene) or a reference run.
Result bench_file_sphere(const Scene& scene, const Settings& settings);
Result bench_file_hyperbolic(const Scene& scene, const Settings& settings);

/// The seed's Fig. 1 data (dopri5, implicit midpoint, SESI 2, SESI 4 at tau = 0.1 to T):
/// writes dir/seed_fig1.csv and dir/seed_fig1_times.csv.
void paper_fig1(const std::string& dir, double t_end, int repeats);
/// The seed's convergence figure data (state at t = 10 between neighbouring steps, every
/// composition): writes dir/convergence.csv.
void paper_convergence(const std::string& dir);

}  // namespace sesi::program::bench
