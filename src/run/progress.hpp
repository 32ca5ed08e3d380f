#pragma once
/// @file progress.hpp
/// A progress bar on stderr for long runs: shown only when stderr is a terminal, --quiet is
/// off, and the run has lasted more than a second; redrawn at most ten times a second and
/// erased at the end.

#include <chrono>

namespace sesi::program {

class ProgressBar {
 public:
  /// @param enabled false disables the bar entirely (--quiet)
  ProgressBar(long total_steps, double t_end, bool enabled);
  ~ProgressBar();
  ProgressBar(const ProgressBar&) = delete;
  ProgressBar& operator=(const ProgressBar&) = delete;

  /// After step `step` (1-based), at time t.
  void update(long step, double t) {
    if (!enabled_ || --countdown_ > 0) return;
    countdown_ = check_every;
    redraw(step, t);
  }
  /// Erase the bar (if it was ever drawn).
  void finish();

  /// Would a bar be shown at all (stderr a terminal and not quiet)?
  static bool wanted(bool quiet);

 private:
  static constexpr int check_every = 16;  // steps between clock reads
  void redraw(long step, double t);

  using Clock = std::chrono::steady_clock;
  long total_;
  double t_end_;
  bool enabled_;
  bool drawn_ = false;
  int countdown_ = check_every;
  Clock::time_point start_, last_draw_;
};

}  // namespace sesi::program
