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

/// SESI_TARGET_AVX2, SESI_TARGET_AVX512: copies of the many-body kernel's pair loop for wider
/// vectors (System::pair_block), chosen at run time by simd::level(). They compute the same bits
/// as the base copy: a lane does a scalar's IEEE operations, and neither target has FMA, so no
/// multiply-add can be contracted whatever -ffp-contract says. Off x86-64, or with
/// SESI_NO_SIMD_DISPATCH defined, there is the base copy alone.
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__)) && !defined(SESI_NO_SIMD_DISPATCH)
#define SESI_SIMD_DISPATCH 1
#define SESI_TARGET_AVX2 __attribute__((target("avx2")))
#define SESI_TARGET_AVX512 __attribute__((target("avx512f")))
#else
#define SESI_SIMD_DISPATCH 0
#endif
/// SESI_PRAGMA_SIMD: the loop after it is vectorised whatever the cost model says (OpenMP's
/// simd, for GCC). Nothing in a build without OpenMP or under clang, where the compiler decides
/// alone: clang reports a loop it cannot vectorise at a low -O as -Wpass-failed, an error in the
/// sanitizer job's -Werror build.
#if defined(_OPENMP) && !defined(__clang__)
#define SESI_PRAGMA_SIMD _Pragma("omp simd")
#else
#define SESI_PRAGMA_SIMD
#endif

namespace sesi::simd {
/// The vector width of the kernel's pair loop: base (the compiler's own target, SSE2 on a plain
/// x86-64 build), avx2 (4 doubles) or avx512 (8 doubles). Every level gives the same bits.
enum class Level { base = 0, avx2 = 1, avx512 = 2 };
namespace detail {
inline int& forced() {
  static int level = -1;
  return level;
}
}  // namespace detail
/// The widest level this processor runs (base where SESI_SIMD_DISPATCH is 0).
inline Level supported() {
#if SESI_SIMD_DISPATCH
  static const Level level = __builtin_cpu_supports("avx512f") ? Level::avx512
                             : __builtin_cpu_supports("avx2")  ? Level::avx2
                                                                : Level::base;
  return level;
#else
  return Level::base;
#endif
}
/// The level the kernel uses: supported(), or a lower one set by set_level (tests compare the
/// levels' bits; not meant to change while a step runs).
inline Level level() {
  const int forced = detail::forced();
  const Level top = supported();
  return forced >= 0 && forced < static_cast<int>(top) ? static_cast<Level>(forced) : top;
}
inline void set_level(Level level) { detail::forced() = static_cast<int>(level); }
}  // namespace sesi::simd

/// SESI_FLATTEN: every call inside the function is inlined into it (GCC's flatten), for the
/// few loops of the many-body step whose callees the inliner's unit-growth limits leave out of
/// line in the program's large dispatch files (perf: Eigen's fixed-size copies, the arc
/// function's polynomial).
#if defined(__GNUC__) && !defined(__clang__)
#define SESI_FLATTEN __attribute__((flatten))
#else
#define SESI_FLATTEN
#endif
