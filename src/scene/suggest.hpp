#pragma once
/// @file suggest.hpp
/// "Did you mean ...?" for unknown keys, kinds and method names (Levenshtein distance).

#include <span>
#include <string>
#include <string_view>

namespace sesi::program {

/// Edit distance (insertions, deletions, substitutions; case-sensitive).
std::size_t edit_distance(std::string_view a, std::string_view b);

/// The candidate nearest to word, if it is near enough to be a plausible typo (at most a third
/// of the word's length away, and at least 2 edits allowed); empty otherwise.
std::string nearest(std::string_view word, std::span<const std::string_view> candidates);

/// "; did you mean 'X'?" or "" (ready to append to a message).
std::string did_you_mean(std::string_view word, std::span<const std::string_view> candidates);

/// "'a', 'b' or 'c'" for messages.
std::string one_of(std::span<const std::string_view> candidates);

}  // namespace sesi::program
