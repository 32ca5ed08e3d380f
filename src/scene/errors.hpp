#pragma once
/// @file errors.hpp
/// How the program fails. Every failure ends in one line on stderr and an exit status:
///   2  bad input (a scene file, an argument, the output directory): nothing is written;
///   3  a run that went wrong (non-finite state, energy guard, close encounter): the outputs so
///      far are kept, marked incomplete;
///   130 interrupted (SIGINT/SIGTERM): as 3, with the reason "interrupted".

#include <cstddef>
#include <stdexcept>
#include <string>
#include <string_view>

namespace sesi::program {

/// Exit statuses of `sesi`.
enum ExitStatus : int {
  exit_ok = 0,
  exit_internal = 1,
  exit_bad_input = 2,
  exit_run_failed = 3,
  exit_interrupted = 130,
};

/// Where an input value comes from: a scene file with the line (and column) where known, or a
/// command-line option (file empty, option set).
struct Origin {
  std::string file;  ///< scene file as given, "<default scene>", or empty for an option
  int line = 0;      ///< 1-based, 0 if unknown
  int column = 0;    ///< 1-based, 0 if unknown
  /// "file:line:column", "file:line", "file" or "" (an option).
  std::string describe() const;
};

/// Bad input (exit status 2). what() is the whole one-line message (without the "sesi: error: "
/// prefix): "FILE:LINE: KEY: WHAT WAS EXPECTED".
class InputError : public std::runtime_error {
 public:
  /// @param origin file and line of the offending value
  /// @param key    the key path in the scene ("bodies[2].mass"), or the option ("--dt")
  /// @param message what was expected, and what was found
  InputError(const Origin& origin, std::string_view key, std::string_view message);
  /// An error with a ready-made message (e.g. from the argument parser).
  explicit InputError(const std::string& message);
};

/// An invariant of the library failed during a run (SESI_CHECK with checks on); the program
/// installs a handler that throws this instead of aborting, and reports it like a non-finite
/// state.
class InvariantFailure : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Route SESI_CHECK failures to InvariantFailure.
void install_check_handler();

/// How much of a piece of the user's input a message quotes (cut_input).
inline constexpr std::size_t max_quoted_bytes = 80;
/// How long a printed error line may be (print_error): a message and a few quoted pieces fit.
inline constexpr std::size_t max_message_bytes = 2000;

/// A piece of the user's input (a key, a string, a value) as a message quotes it: itself when it
/// has at most `limit` bytes, else its first `limit` bytes (not splitting a UTF-8 character)
/// and "... (N bytes)", so that a 10 MB key never comes back whole on stderr.
std::string cut_input(std::string_view text, std::size_t limit = max_quoted_bytes);

/// A message from a library (toml++) that quotes input between single quotes: what lies
/// between its first and its last quote (or after its only one) cut with cut_input.
std::string cut_quoted(std::string_view message);

/// Print "sesi: error: MESSAGE" as one line (newlines in MESSAGE become spaces), cut with
/// cut_input to max_message_bytes should a message quote input uncut.
void print_error(std::string_view message);

/// Format a double for messages: the shortest form that reads back exactly.
std::string format_number(double value);
/// Format a double for messages with 3 significant digits (residuals, tolerances).
std::string format_short(double value);

}  // namespace sesi::program
