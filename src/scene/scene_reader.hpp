#pragma once
/// @file scene_reader.hpp
/// Scene files (TOML, docs/scene-format.md) to Scene: every key checked for its type and value,
/// unknown keys refused with the nearest valid key, initial conditions on the space and in the
/// chart's domain, no body where a pair potential is singular. Any failure throws InputError
/// naming the file, the line, the key and what was expected.

#include <span>
#include <string>
#include <string_view>

#include "scene.hpp"

namespace sesi::program {

/// Read and check the scene file at path.
Scene read_scene_file(const std::string& path);

/// Read and check scene text; path names it in messages and gives the default name (its stem).
Scene read_scene_text(std::string_view text, const std::string& path);

/// A potential kind of the scene format, for listings (the Python package's sesi.potentials()).
struct PotentialInfo {
  std::string_view kind;
  std::span<const std::string_view> keys;  ///< every key of its [[potential]] table, "kind" first
  std::string_view defaults;               ///< the keys' defaults, in words
  std::string_view energy;
};
/// Every potential kind a scene file may name, in the order of docs/scene-format.md.
std::span<const PotentialInfo> potential_catalogue();

}  // namespace sesi::program
