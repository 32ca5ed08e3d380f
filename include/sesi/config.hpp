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

/// SESI_INLINE: a function of the many-body kernel's inner loop that must be inlined there. GCC
/// left small members such as Sphere::pair_geometry out of line in the program's large dispatch
/// files (perf of `sesi run`: 7 % of a 10^5-body step in the call), though not in a small test.
#if defined(__GNUC__) || defined(__clang__)
#define SESI_INLINE inline __attribute__((always_inline))
#else
#define SESI_INLINE inline
#endif

/// SESI_FLATTEN: every call inside the function is inlined into it (GCC's flatten), for the
/// few loops of the many-body step whose callees the inliner's unit-growth limits leave out of
/// line in the program's large dispatch files (perf: Eigen's fixed-size copies, the arc
/// function's polynomial).
#if defined(__GNUC__) && !defined(__clang__)
#define SESI_FLATTEN __attribute__((flatten))
#else
#define SESI_FLATTEN
#endif
