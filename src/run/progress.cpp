#include "progress.hpp"

#include <cstdio>
#include <string>

#include <unistd.h>

namespace sesi::program {

namespace {
constexpr double show_after_seconds = 1.0;
constexpr double redraw_seconds = 0.1;
constexpr int bar_width = 30;

std::string duration(double seconds) {
  char buffer[32];
  if (seconds < 60) {
    std::snprintf(buffer, sizeof buffer, "%.0fs", seconds);
  } else if (seconds < 3600) {
    std::snprintf(buffer, sizeof buffer, "%dm%02ds", static_cast<int>(seconds) / 60, static_cast<int>(seconds) % 60);
  } else {
    std::snprintf(buffer, sizeof buffer, "%dh%02dm", static_cast<int>(seconds) / 3600,
                  (static_cast<int>(seconds) / 60) % 60);
  }
  return buffer;
}
}  // namespace

ProgressBar::ProgressBar(long total_steps, double t_end, bool enabled)
    : total_(total_steps), t_end_(t_end), enabled_(enabled && total_steps > 0), start_(Clock::now()) {}

ProgressBar::~ProgressBar() { finish(); }

bool ProgressBar::wanted(bool quiet) { return !quiet && isatty(STDERR_FILENO) == 1; }

void ProgressBar::redraw(long step, double t) {
  const auto now = Clock::now();
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  if (elapsed < show_after_seconds) return;
  if (drawn_ && std::chrono::duration<double>(now - last_draw_).count() < redraw_seconds) return;
  last_draw_ = now;
  drawn_ = true;
  const double done = static_cast<double>(step) / static_cast<double>(total_);
  const int filled = static_cast<int>(done * bar_width);
  std::string bar(static_cast<std::size_t>(filled), '#');
  bar.append(static_cast<std::size_t>(bar_width - filled), '-');
  const double remaining = done > 0 ? elapsed * (1 - done) / done : 0.0;
  std::fprintf(stderr, "\r[%s] %3.0f%%  t = %-10.4g of %-10.4g %s left \033[K", bar.c_str(), 100 * done, t,
               t_end_, duration(remaining).c_str());
  std::fflush(stderr);
}

void ProgressBar::finish() {
  if (!drawn_) return;
  std::fputs("\r\033[K", stderr);
  std::fflush(stderr);
  drawn_ = false;
}

}  // namespace sesi::program
