#include "signals.hpp"

#include <csignal>
#include <cstring>

#include <unistd.h>

namespace sesi::program::signals {

namespace {

std::atomic<bool> running{false};
std::atomic<bool> stop{false};
std::atomic<const char*> unfinished{nullptr};
static_assert(std::atomic<bool>::is_always_lock_free && std::atomic<const char*>::is_always_lock_free,
              "the signal handler needs lock-free atomics");

void say(const char* text) {
  const ssize_t ignored = ::write(STDERR_FILENO, text, std::strlen(text));
  static_cast<void>(ignored);
}

extern "C" void on_signal(int) {
  if (running.load() && !stop.exchange(true)) return;  // the run stops between steps
  if (const char* file = unfinished.load()) ::unlink(file);
  say(running.load() ? "sesi: error: interrupted again: stopped at once; the last complete checkpoint is kept\n"
                     : "sesi: error: interrupted before the run started; nothing written\n");
  ::_exit(130);
}

}  // namespace

void install() {
  struct sigaction action {};
  action.sa_handler = on_signal;
  sigemptyset(&action.sa_mask);
  for (const int s : {SIGINT, SIGTERM, SIGHUP}) sigaction(s, &action, nullptr);
}

void begin_run() { running.store(true); }

const std::atomic<bool>& stop_requested() { return stop; }

void set_unfinished_file(const char* path) { unfinished.store(path); }

}  // namespace sesi::program::signals
