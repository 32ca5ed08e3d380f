// `sesi bench --scene kepler-s2`: the curved Kepler problem on S^2 (bench_kepler.hpp).
#include <sesi/spaces/sphere.hpp>

#include "bench_kepler.hpp"
#include "bench_scenes.hpp"

namespace sesi::program::bench {

Result bench_kepler_s2(const Settings& settings) {
  return bench_kepler<sesi::Sphere<2, double>>(settings, "kepler-s2", 0.7);
}

}  // namespace sesi::program::bench
