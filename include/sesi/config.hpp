#pragma once
/// @file config.hpp
/// Project-wide checks: one macro for invariants, with a replaceable failure handler.

#include <cstdio>
#include <cstdlib>

namespace sesi {

/// Signature of the invariant-failure handler.
using CheckHandler = void (*)(const char* expr, const char* what, const char* file, int line);

namespace detail {
[[noreturn]] inline void default_check_handler(const char* expr, const char* what, const char* file,
                                               int line) {
  std::fprintf(stderr, "sesi: invariant failed: %s (%s) at %s:%d\n", what, expr, file, line);
  std::abort();
}
inline CheckHandler& check_handler_slot() {
  static CheckHandler handler = nullptr;
  return handler;
}
inline void check_failed(const char* expr, const char* what, const char* file, int line) {
  if (CheckHandler h = check_handler_slot()) {
    h(expr, what, file, line);
  } else {
    default_check_handler(expr, what, file, line);
  }
}
}  // namespace detail

/// Replace the handler called when an invariant check fails (tests install one that throws).
/// @return the previous handler (nullptr means the default, which prints and aborts).
inline CheckHandler set_check_handler(CheckHandler handler) {
  CheckHandler previous = detail::check_handler_slot();
  detail::check_handler_slot() = handler;
  return previous;
}

}  // namespace sesi

/// SESI_CHECK(cond, what): an invariant written down. Checked when SESI_ENABLE_CHECKS is
/// defined (the default in builds without NDEBUG), compiled out otherwise.
#if !defined(SESI_ENABLE_CHECKS) && !defined(NDEBUG)
#define SESI_ENABLE_CHECKS 1
#endif
#if defined(SESI_ENABLE_CHECKS) && SESI_ENABLE_CHECKS
#define SESI_CHECK(cond, what)                                       \
  do {                                                               \
    if (!(cond)) ::sesi::detail::check_failed(#cond, what, __FILE__, __LINE__); \
  } while (false)
#else
#define SESI_CHECK(cond, what) \
  do {                         \
  } while (false)
#endif
