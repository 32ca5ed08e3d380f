// libFuzzer target: scene text through the reader and validator (src/scene/scene_reader.cpp), as
// `sesi run scene.toml` reads it. Bad input must end in InputError (the program's exit 2);
// anything else that escapes -- another exception, a sanitizer report, a crash -- is a finding.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "errors.hpp"
#include "scene_reader.hpp"
#include "validate.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  try {
    const sesi::program::Scene scene = sesi::program::read_scene_text(text, "fuzz.toml");
    // What the program computes next from a valid scene before any step.
    if (scene.integrator.dt && scene.integrator.t_end) {
      static_cast<void>(sesi::program::step_count(*scene.integrator.t_end, *scene.integrator.dt));
    }
  } catch (const sesi::program::InputError&) {
    // Rejected with a message: the expected outcome for bad input.
  }
  return 0;
}
