#pragma once
/// @file parallel.hpp
/// Deterministic loops over bodies on threads (when the build has OpenMP, -fopenmp, which gives
/// the default thread count; the threads are sesi's own team, detail::Team), serial otherwise,
/// with the same results.
///
/// Determinism is by construction, not by luck: every loop body writes only to its own body's
/// entries, and every sum over bodies is formed afterwards in body order (sum_in_order), so the
/// partition of bodies among threads never changes a single bit of a result. The thread count
/// is a setting (set_threads, the program's --threads); a loop takes one thread per
/// min_parallel_bodies bodies (threads_for), so a scene too small to pay for threads runs on one,
/// and the team's threads wait passively, so a busy machine costs at most the chunks a
/// descheduled thread has already taken (issue #24).

#include <algorithm>
#include <condition_variable>
#include <exception>
#include <mutex>
#include <thread>
#include <type_traits>
#include <vector>

#include "sesi/profile.hpp"

#if defined(_OPENMP)
#include <omp.h>
#endif

namespace sesi::parallel {

/// Loops over fewer bodies than this run on one thread, and a loop gets a thread per this many
/// bodies (threads_for). Measured on the 2-core development machine (docs/benchmarks.md,
/// "Threads"): below ~256 bodies a level flow or a pair row costs less than waking a second
/// thread, and a 300-body Lennard-Jones run was slower on two threads than on one.
inline constexpr int min_parallel_bodies = 256;

/// Whether a loop over n bodies is shared among threads when there are two or more (n >= 2
/// min_parallel_bodies, threads_for): a profile counts such a loop as a parallel region even when
/// it runs on one thread, so that a one-thread profile shows the serial part Amdahl's law charges.
inline constexpr bool shared_loop(int n) { return n / min_parallel_bodies >= 2; }

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
/// sesi's own team of threads. A loop's caller takes chunks itself and the helpers take chunks
/// as they wake, so a loop never waits for a helper that has not started: on a busy machine a
/// descheduled helper costs nothing (an OpenMP barrier waits for every thread of the team, and
/// libgomp's helpers spin while they wait; OMP_WAIT_POLICY is read only when libgomp is loaded).
/// Helpers and the caller wait passively (a condition variable), never by spinning.
class Team {
 public:
  using Call = void (*)(void* context, int chunk);

  /// Never destroyed: its helpers wait until the process ends (no join at exit, and none in a
  /// forked child, where the helpers do not exist).
  static Team& instance() {
    static Team* const team = new Team;
    return *team;
  }

  /// call(context, c) for c in [0, chunks), on the calling thread and up to `helpers` others.
  /// False (nothing run) when the team is busy with another loop (a nested loop, or a loop on
  /// another thread): the caller then runs the chunks itself.
  bool run(int chunks, int helpers, Call call, void* context) {
    if (inside()) return false;  // before try_lock: this thread may hold busy_ already
    std::unique_lock<std::mutex> caller(busy_, std::try_to_lock);
    if (!caller.owns_lock()) return false;
    std::unique_lock<std::mutex> lock(mutex_);
    helpers = std::min(helpers, chunks - 1);
    while (static_cast<int>(workers_.size()) < helpers) {
      try {
        const int k = static_cast<int>(workers_.size());
        workers_.emplace_back([this, k] { work(k); });
      } catch (...) {  // no more threads to be had: go on with those there are
        helpers = static_cast<int>(workers_.size());
      }
    }
    call_ = call;
    context_ = context;
    chunks_ = chunks;
    helpers_ = helpers;
    next_ = 0;
    finished_ = 0;
    ++generation_;
    if (helpers > 0) wake_.notify_all();
    inside() = true;
    take_chunks(lock);
    done_.wait(lock, [&] { return finished_ == chunks_; });  // only chunks already taken
    inside() = false;
    chunks_ = 0;
    call_ = nullptr;
    context_ = nullptr;
    return true;
  }

  Team(const Team&) = delete;
  Team& operator=(const Team&) = delete;

 private:
  Team() = default;

  /// Whether this thread is running a chunk (a loop inside one runs serially).
  static bool& inside() {
    thread_local bool flag = false;
    return flag;
  }

  /// Take and run chunks until none is left (lock held on entry and exit).
  void take_chunks(std::unique_lock<std::mutex>& lock) {
    while (next_ < chunks_) {
      const int c = next_++;
      const Call call = call_;
      void* const context = context_;
      lock.unlock();
      call(context, c);
      lock.lock();
      if (++finished_ == chunks_) done_.notify_one();
    }
  }

  void work(int k) {
    inside() = true;
    profile::set_thread_slot(k);  // a profile charges this thread's chunks to slot k + 1
    std::unique_lock<std::mutex> lock(mutex_);
    unsigned long seen = generation_;
    while (true) {
      wake_.wait(lock, [&] { return generation_ != seen && next_ < chunks_; });
      seen = generation_;
      if (k < helpers_) take_chunks(lock);
    }
  }

  std::mutex busy_;   // held by the thread whose loop the team runs
  std::mutex mutex_;  // guards everything below
  std::condition_variable wake_, done_;
  std::vector<std::thread> workers_;
  Call call_ = nullptr;
  void* context_ = nullptr;
  int chunks_ = 0, helpers_ = 0, next_ = 0, finished_ = 0;
  unsigned long generation_ = 0;
};

/// The threaded part of for_chunks (chunks >= 2), apart so that the serial path stays small
/// enough to be inlined: a three-body step must not pay for the thread machinery.
template <class F>
void for_chunks_on_threads(int n, int chunks, F& f) {
  struct Loop {
    F& f;
    int n, chunks;
    std::exception_ptr failure;
    int failed_chunk;
    std::mutex guard;
    const profile::Loop& profiled;
  };
  const profile::Loop profiled;  // the loop's wall time, and each chunk's on its thread
  Loop loop{f, n, chunks, nullptr, chunks, {}, profiled};
  const auto call = [](void* context, int c) {
    Loop& l = *static_cast<Loop*>(context);
    const int begin = static_cast<int>(static_cast<long long>(l.n) * c / l.chunks);
    const int end = static_cast<int>(static_cast<long long>(l.n) * (c + 1) / l.chunks);
    try {
      l.profiled.chunk([&] { l.f(begin, end, c); });
    } catch (...) {
      const std::lock_guard<std::mutex> lock(l.guard);
      if (c < l.failed_chunk) {
        l.failed_chunk = c;
        l.failure = std::current_exception();
      }
    }
  };
  // A thread for every four chunks (chunks_for), up to threads().
  const int team = std::min(threads(), (chunks + 3) / 4);
  if (team < 2 || !Team::instance().run(chunks, team - 1, call, &loop)) {
    for (int c = 0; c < chunks; ++c) call(&loop, c);  // one thread, or the team is busy: here
  }
  if (loop.failure) std::rethrow_exception(loop.failure);
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
  if (chunks == 1) {  // a parallel region in a profile if it would share out on more threads
    const profile::Loop profiled(shared_loop(n));
    profiled.chunk([&] { f(0, n, 0); });
    return;
  }
  detail::for_chunks_on_threads(n, chunks, f);
}

/// The threads a loop over n bodies uses: up to threads(), as many as get min_parallel_bodies
/// bodies each (so one below twice that: a second thread would not pay for waking it).
inline int threads_for(int n) { return std::max(1, std::min(threads(), n / min_parallel_bodies)); }

/// The number of chunks for a loop over n bodies: 1 on one thread, else four per thread, so that
/// the threads that are running take the chunks of one that is not (a busy machine). The chunks
/// do not change a result, only who computes it.
inline int chunks_for(int n) {
  const int t = threads_for(n);
  return t > 1 ? 4 * t : 1;
}

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

/// Prefix sums in place of the integers data[0 .. n): data[i] becomes data[0] + ... + data[i].
/// On threads by chunks (each chunk's total, those totals' prefix sums in chunk order, then each
/// chunk's running sums from its start: Blelloch, "Prefix sums and their applications",
/// CMU-CS-90-190, 1990): integer sums, so
/// the same result for any chunks. partial is the chunks' scratch (kept by the caller, so that a
/// step allocates nothing). A neighbour rebuild's row offsets were serial at 10^5 bodies.
template <class Int>
void prefix_sums(Int* data, int n, std::vector<Int>& partial) {
  static_assert(std::is_integral_v<Int>, "prefix_sums: integers only (their sums are exact in any order)");
  const int chunks = std::max(1, std::min(chunks_for(n), n));
  if (partial.size() < static_cast<std::size_t>(chunks)) partial.resize(static_cast<std::size_t>(chunks));
  for_chunks(n, chunks, [&](int begin, int end, int c) {
    Int s(0);
    for (int i = begin; i < end; ++i) s += data[i];
    partial[static_cast<std::size_t>(c)] = s;
  });
  Int before(0);  // the chunks' starting sums (a few chunks: here)
  for (int c = 0; c < chunks; ++c) {
    const Int here = partial[static_cast<std::size_t>(c)];
    partial[static_cast<std::size_t>(c)] = before;
    before += here;
  }
  for_chunks(n, chunks, [&](int begin, int end, int c) {
    Int s = partial[static_cast<std::size_t>(c)];
    for (int i = begin; i < end; ++i) data[i] = s += data[i];
  });
}

/// The indices i in [0, n) with keep(i), in ascending order: emit(k, i) for the k-th of them, on
/// threads (each chunk counts its own, the counts' prefix sums give each chunk's first k, then
/// each chunk emits), so the same calls for any thread count. keep is called twice per index;
/// sized(total) once between the passes (to size the output). counts is the chunks' scratch
/// (kept by the caller). Returns how many were kept.
template <class Keep, class Sized, class Emit>
int select_in_order(int n, std::vector<int>& counts, Keep&& keep, Sized&& sized, Emit&& emit) {
  if (n <= 0) {
    sized(0);
    return 0;
  }
  const int chunks = std::max(1, std::min(chunks_for(n), n));
  if (counts.size() < static_cast<std::size_t>(chunks)) counts.resize(static_cast<std::size_t>(chunks));
  for_chunks(n, chunks, [&](int begin, int end, int c) {
    int m = 0;
    for (int i = begin; i < end; ++i) m += keep(i) ? 1 : 0;
    counts[static_cast<std::size_t>(c)] = m;
  });
  int total = 0;
  for (int c = 0; c < chunks; ++c) {
    const int here = counts[static_cast<std::size_t>(c)];
    counts[static_cast<std::size_t>(c)] = total;
    total += here;
  }
  sized(total);
  for_chunks(n, chunks, [&](int begin, int end, int c) {
    int k = counts[static_cast<std::size_t>(c)];
    for (int i = begin; i < end; ++i) {
      if (keep(i)) emit(k++, i);
    }
  });
  return total;
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
