#pragma once
/// @file parallel.hpp
/// Deterministic loops over bodies on threads (OpenMP when the build has it, -fopenmp; serial
/// otherwise, with the same results).
///
/// Determinism is by construction, not by luck: every loop body writes only to its own body's
/// entries, and every sum over bodies is formed afterwards in body order (sum_in_order), so the
/// partition of bodies among threads never changes a single bit of a result. The thread count
/// is a setting (set_threads, the program's --threads); loops below min_parallel_bodies stay on
/// one thread, where starting threads would cost more than they save.

#include <algorithm>
#include <exception>
#include <mutex>
#include <vector>

#if defined(_OPENMP)
#include <omp.h>
#endif

namespace sesi::parallel {

/// Loops over fewer bodies than this run on one thread. Measured on the 2-core development
/// machine (docs/benchmarks.md, "Threads"): below ~256 bodies a level flow or a pair row costs
/// less than waking a second thread.
inline constexpr int min_parallel_bodies = 256;

namespace detail {
inline int& thread_setting() {
  static int threads = 0;
  return threads;
}
}  // namespace detail

/// Threads for sesi's loops: n >= 1, or 0 for all cores (OpenMP's default). Results do not
/// depend on it.
inline void set_threads(int n) { detail::thread_setting() = n < 0 ? 0 : n; }

/// The threads a loop over enough bodies uses (1 in a build without OpenMP).
inline int threads() {
#if defined(_OPENMP)
  const int n = detail::thread_setting();
  return n > 0 ? n : omp_get_max_threads();
#else
  return 1;
#endif
}

/// Whether sesi was compiled with OpenMP.
inline constexpr bool available() {
#if defined(_OPENMP)
  return true;
#else
  return false;
#endif
}

namespace detail {
/// The threaded part of for_chunks (chunks >= 2), apart so that the serial path stays small
/// enough to be inlined: a three-body step must not pay for the thread machinery.
template <class F>
void for_chunks_on_threads(int n, int chunks, F& f) {
  std::exception_ptr failure;
  int failed_chunk = chunks;
  std::mutex guard;
#if defined(_OPENMP)
#pragma omp parallel for schedule(static, 1) num_threads(std::min(chunks, threads()))
#endif
  for (int c = 0; c < chunks; ++c) {
    const int begin = static_cast<int>(static_cast<long long>(n) * c / chunks);
    const int end = static_cast<int>(static_cast<long long>(n) * (c + 1) / chunks);
    try {
      f(begin, end, c);
    } catch (...) {
      const std::lock_guard<std::mutex> lock(guard);
      if (c < failed_chunk) {
        failed_chunk = c;
        failure = std::current_exception();
      }
    }
  }
  if (failure) std::rethrow_exception(failure);
}
}  // namespace detail

/// f(begin, end, chunk) over `chunks` contiguous, equal ranges of [0, n) (chunk = 0..chunks-1),
/// on up to threads() threads. An exception thrown by f (an invariant check's handler, say) is
/// rethrown after the loop: the one from the lowest chunk, so even failures do not depend on the
/// thread count.
template <class F>
void for_chunks(int n, int chunks, F&& f) {
  if (n <= 0) return;
  chunks = std::max(1, std::min(chunks, n));
  if (chunks == 1) {
    f(0, n, 0);
    return;
  }
  detail::for_chunks_on_threads(n, chunks, f);
}

/// The number of chunks for a loop over n bodies: one per thread above min_parallel_bodies.
inline int chunks_for(int n) { return n >= min_parallel_bodies ? threads() : 1; }

/// f(i) for i in [0, n), in parallel above min_parallel_bodies. f must write only to i's own data.
template <class F>
void for_each(int n, F&& f) {
  if (n < min_parallel_bodies) {
    for (int i = 0; i < n; ++i) f(i);
    return;
  }
  for_chunks(n, chunks_for(n), [&](int begin, int end, int) {
    for (int i = begin; i < end; ++i) f(i);
  });
}

/// The sum of values[0] + values[1] + ... in that order (so a sum over bodies whose terms were
/// computed on any number of threads is the same to the bit).
template <class Scalar>
Scalar sum_in_order(const std::vector<Scalar>& values) {
  Scalar s(0);
  for (const Scalar& v : values) s += v;
  return s;
}

}  // namespace sesi::parallel
