// `sesi bench --scene kepler-h2`: the curved Kepler problem on H^2 (bench_kepler.hpp).
#include <sesi/spaces/hyperbolic.hpp>

#include "bench_kepler.hpp"
#include "bench_scenes.hpp"

namespace sesi::program::bench {

Result bench_kepler_h2(const Settings& settings) {
  return bench_kepler<sesi::Hyperbolic<2, double>>(settings, "kepler-h2", 0.6);
}

}  // namespace sesi::program::bench
