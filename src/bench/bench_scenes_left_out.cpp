// The sanitizer job's program (SESI_SANITIZER_BUILD, tests/sanitizers.cmake) is built without the
// scenes of `sesi bench --scene` and --figure (bench_scene_*.cpp, src/CMakeLists.txt): their
// reference steppers took a fifth of that job's compile time, and their tests (tests/bench) run
// in the main build. Asked for one there, the program says so instead of running.
#include <string>

#include "bench_scenes.hpp"
#include "errors.hpp"

namespace sesi::program::bench {

namespace {
[[noreturn]] void left_out(const std::string& what) {
  throw InputError("sesi bench " + what +
                   ": not in this build (SESI_SANITIZER_BUILD leaves out the benchmark scenes)");
}
}  // namespace

Result bench_paper(const Settings&) { left_out("--scene paper"); }
Result bench_kepler_s2(const Settings&) { left_out("--scene kepler-s2"); }
Result bench_kepler_h2(const Settings&) { left_out("--scene kepler-h2"); }
Result bench_file_sphere(const Scene&, const Settings&) { left_out("--scene FILE"); }
Result bench_file_hyperbolic(const Scene&, const Settings&) { left_out("--scene FILE"); }
void paper_fig1(const std::string&, double, int) { left_out("--figure seed-fig1"); }
void paper_convergence(const std::string&) { left_out("--figure convergence"); }

}  // namespace sesi::program::bench
