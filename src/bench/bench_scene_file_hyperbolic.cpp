// `sesi bench --scene FILE` on H^2 and H^3 (bench_file.hpp).
#include "bench_file.hpp"
#include "bench_scenes.hpp"

namespace sesi::program::bench {

Result bench_file_hyperbolic(const Scene& scene, const Settings& settings) {
  if (scene.dim() == 2) return bench_scene_file<sesi::Hyperbolic<2, double>>(scene, settings);
  return bench_scene_file<sesi::Hyperbolic<3, double>>(scene, settings);
}

}  // namespace sesi::program::bench
