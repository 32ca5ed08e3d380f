#pragma once
/// @file scene_table.hpp
/// Reading a scene from a TOML document built in memory (the Python package's
/// Simulation.from_dict and its builder), with the checks and messages of a scene file.

#include <string>

#include <toml++/toml.h>

#include "scene.hpp"

namespace sesi::program {

/// Read and check the scene document root; source names it in messages ("<dict>") and gives
/// the default name. Nodes built in memory have no line, so messages name the key path only.
Scene read_scene_table(const toml::table& root, const std::string& source);

/// Read and check a [thermostat] table alone (the Python package's Simulation.thermostat), with
/// the scene reader's rules and messages (keys named "thermostat.KEY").
ThermostatSpec read_thermostat_table(const toml::table& table, const std::string& source);

}  // namespace sesi::program
