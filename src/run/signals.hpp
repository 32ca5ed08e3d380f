#pragma once
/// @file signals.hpp
/// SIGINT, SIGTERM and SIGHUP, handled from the start of the program (docs/scene-format.md,
/// "Signals"):
///  - before a run starts (reading and checking the scene, nothing written yet), a signal ends
///    the program at once with exit status 130 and one line;
///  - during a run, the first signal asks the run to stop between steps (it writes a checkpoint
///    and its outputs so far); a second one ends the program at once, after removing a
///    checkpoint that was being written (the last complete one stays).
/// The handlers use only async-signal-safe calls (write, unlink, _exit).

#include <atomic>

namespace sesi::program::signals {

/// Install the handlers (in main, before anything else).
void install();
/// From now on the first signal only sets stop_requested().
void begin_run();
/// Set by the first signal during a run.
const std::atomic<bool>& stop_requested();
/// A file being written that a second signal removes before ending the program (nullptr: none).
/// The string must outlive the call that clears it.
void set_unfinished_file(const char* path);

}  // namespace sesi::program::signals
