// `sesi bench --scene FILE` on S^2 and S^3 (bench_file.hpp).
#include "bench_file.hpp"
#include "bench_scenes.hpp"

namespace sesi::program::bench {

Result bench_file_sphere(const Scene& scene, const Settings& settings) {
  if (scene.dim() == 2) return bench_scene_file<sesi::Sphere<2, double>>(scene, settings);
  return bench_scene_file<sesi::Sphere<3, double>>(scene, settings);
}

}  // namespace sesi::program::bench
