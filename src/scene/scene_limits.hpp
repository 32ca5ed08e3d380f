#pragma once
/// @file scene_limits.hpp
/// Limits on a scene file's size and shape, checked before the TOML parser sees the text.
/// toml++ 3.3 builds and walks its tables recursively (one stack frame per level of a dotted key
/// or table header, in the parser's table creation, in update_region_ends and in the node
/// destructors), so a key of some 35,000 dotted parts (an 80 KB file) overflowed the stack
/// (issue #12). A scene needs a handful of levels; these limits leave plenty of room.

#include <cstddef>
#include <string>
#include <string_view>

namespace sesi::program {

/// At most this many bytes in a scene file: 1 GiB, about 7 times the 154 MB of a 10^6-body scene
/// (tools/lattice_scene.py, docs/benchmarks.md); the reader holds the text twice in memory.
inline constexpr std::size_t max_scene_bytes = std::size_t{1} << 30;
/// At most this many parts in one dotted key (a.b.c = 1 has 3) or one table header ([a.b] has 2).
inline constexpr int max_key_parts = 64;
/// At most this many arrays and inline tables nested in each other (toml++'s own limit,
/// TOML_MAX_NESTED_VALUES, is 256).
inline constexpr int max_bracket_nesting = 64;
/// At most this many levels of tables and arrays above any value (header parts, dotted parts and
/// brackets together): with the two limits above alone, a tree could still be 64 x 65 deep. A
/// header part that passes through an array of tables ([[a]] then [a.b]) adds a level the count
/// does not see, so the tree is at most 2 x 64 + 128 deep; the parser crashed near 35,000.
inline constexpr int max_tree_depth = 128;

/// Throws InputError ("FILE:LINE: WHAT", exit 2) when text is larger than max_scene_bytes or a
/// key, a table header, or the nesting of arrays and inline tables passes its limit. One pass,
/// linear in the size of the text, no recursion; valid TOML within the limits always passes.
/// Text that is not valid TOML is checked as far as it can be read as TOML, which covers all that
/// the parser accepts before it reports the syntax error.
void check_scene_limits(std::string_view text, const std::string& path);

}  // namespace sesi::program
