#pragma once
/// @file scene_reader.hpp
/// Scene files (TOML, docs/scene-format.md) to Scene: every key checked for its type and value,
/// unknown keys refused with the nearest valid key, initial conditions on the space and in the
/// chart's domain, no body where a pair potential is singular. Any failure throws InputError
/// naming the file, the line, the key and what was expected.

#include <string>
#include <string_view>

#include "scene.hpp"

namespace sesi::program {

/// Read and check the scene file at path.
Scene read_scene_file(const std::string& path);

/// Read and check scene text; path names it in messages and gives the default name (its stem).
Scene read_scene_text(std::string_view text, const std::string& path);

}  // namespace sesi::program
