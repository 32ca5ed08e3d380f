#pragma once
/// @file profile.hpp
/// A profile of the step (issue #27): wall time per phase of a step, and the busy time of every
/// thread inside sesi::parallel's loops, so that the part of a step that only one thread does
/// (the part Amdahl's law charges) can be read off.
///
/// Off by default. A Scope costs one relaxed atomic load and a branch when off; when on it reads
/// the clock twice (std::chrono::steady_clock) and touches a few counters (see
/// docs/benchmarks.md, "Profile of a step", for the measured cost). Profiling only reads clocks:
/// results are bit-identical with and without it.
///
/// The model:
///  - One thread records (the one that called start(): the thread that runs the steps). Its
///    current phase is the innermost open Scope (Phase::other when none). Wall time is charged to
///    the current phase only, so an outer phase's wall excludes its inner phases' (exclusive
///    time), and the phases' walls add up to the profiled window.
///  - A loop of sesi::parallel (for_chunks, and for_each over enough bodies to use it) started by
///    that thread outside another loop is a parallel region: its wall time on the calling thread
///    is charged to the current phase as loop time, and each thread that runs some of its chunks
///    (slot 0 the caller, slot k + 1 the team's helper k) adds the time of those chunks to its
///    busy time in that phase. Scopes opened inside a loop's chunks, and loops nested in a chunk,
///    are not recorded apart (their time is the enclosing chunk's).
///  - serial = wall - loop time: the phase's work that no other thread can share.

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <vector>

namespace sesi::profile {

/// The phases of a step. Phase::other is step time inside no other phase.
enum class Phase : int { other = 0, drift, force, neighbours, thermostat, checks, output, checkpoint, count };

/// The number of phases (Phase::count).
inline constexpr int phase_count = static_cast<int>(Phase::count);

/// "other", "drift", "force", "neighbours", "thermostat", "checks", "output", "checkpoint".
inline const char* name(Phase phase) {
  switch (phase) {
    case Phase::other: return "other";
    case Phase::drift: return "drift";
    case Phase::force: return "force";
    case Phase::neighbours: return "neighbours";
    case Phase::thermostat: return "thermostat";
    case Phase::checks: return "checks";
    case Phase::output: return "output";
    case Phase::checkpoint: return "checkpoint";
    case Phase::count: break;
  }
  return "unknown";
}

namespace detail {
inline std::atomic<bool> enabled_flag{false};

/// Nanoseconds of the monotonic clock.
inline long long now_ns() noexcept {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

/// One thread's busy time per phase, on its own cache lines (threads write only their own slot).
struct alignas(64) ThreadSlot {
  std::array<long long, phase_count> busy_ns{};
  std::array<long long, phase_count> chunks{};
};

/// What the recording thread accumulates; allocated by start(), never during a step.
struct Recorder {
  std::vector<ThreadSlot> slots;  ///< one per thread: 0 the recording thread, k + 1 helper k
  std::array<long long, phase_count> wall_ns{};       ///< exclusive wall time per phase
  std::array<long long, phase_count> loop_wall_ns{};  ///< wall of parallel loops started in it
  std::array<long long, phase_count> calls{};         ///< Scopes entered
  std::array<long long, phase_count> loops{};         ///< parallel loops started in it
  Phase current = Phase::other;
  long long mark = 0;   ///< when the current phase's running interval began
  long long begin = 0;  ///< start()
  int loop_depth = 0;   ///< > 0 while a loop of this thread runs

  /// Close the current interval at t, charging it to the current phase.
  void charge(long long t) noexcept {
    wall_ns[static_cast<int>(current)] += t - mark;
    mark = t;
  }
};

inline Recorder& recorder() {
  static Recorder r;
  return r;
}

/// The recorder, on the thread that records (nullptr on every other thread).
inline Recorder*& this_thread_recorder() noexcept {
  thread_local Recorder* r = nullptr;
  return r;
}

/// This thread's slot: 0 for any thread that is not one of the team's helpers (set_thread_slot).
inline int& thread_slot() noexcept {
  thread_local int slot = 0;
  return slot;
}
}  // namespace detail

/// Whether the profile is recording (a relaxed atomic load: nearly free).
inline bool enabled() noexcept { return detail::enabled_flag.load(std::memory_order_relaxed); }

/// RAII: the time from construction to destruction is charged to `phase` (nestable: an inner
/// scope's time is charged to the inner phase only). Does nothing when !enabled(), on a thread
/// other than the recording one, or inside a parallel loop's chunk.
class Scope {
 public:
  explicit Scope(Phase phase) noexcept {
    if (!enabled()) return;
    detail::Recorder* const r = detail::this_thread_recorder();
    if (r == nullptr || r->loop_depth > 0) return;
    r->charge(detail::now_ns());
    previous_ = r->current;
    r->current = phase;
    ++r->calls[static_cast<int>(phase)];
    recorder_ = r;
  }
  ~Scope() {
    if (recorder_ == nullptr) return;
    recorder_->charge(detail::now_ns());
    recorder_->current = previous_;
  }
  Scope(const Scope&) = delete;
  Scope& operator=(const Scope&) = delete;

 private:
  detail::Recorder* recorder_ = nullptr;
  Phase previous_ = Phase::other;
};

/// A parallel loop's part in the profile (used by sesi::parallel): construct one where a loop
/// starts on the calling thread; it times the loop's wall on that thread, and chunk() times a
/// chunk on whichever thread runs it. Inactive (no clock reads) when the profile is off, on
/// another thread, inside another loop, or when `region` is false (a loop too small to share
/// among threads: its time stays serial).
class Loop {
 public:
  explicit Loop(bool region = true) noexcept {
    if (!region || !enabled()) return;
    detail::Recorder* const r = detail::this_thread_recorder();
    if (r == nullptr || r->loop_depth > 0) return;
    ++r->loop_depth;
    phase_ = static_cast<int>(r->current);
    ++r->loops[phase_];
    recorder_ = r;
    start_ = detail::now_ns();
  }
  ~Loop() {
    if (recorder_ == nullptr) return;
    recorder_->loop_wall_ns[phase_] += detail::now_ns() - start_;
    --recorder_->loop_depth;
  }
  Loop(const Loop&) = delete;
  Loop& operator=(const Loop&) = delete;

  bool active() const noexcept { return recorder_ != nullptr; }

  /// f() timed as a chunk of this loop on the calling thread's slot (just f() when inactive).
  template <class F>
  void chunk(F&& f) const {
    if (recorder_ == nullptr) {
      f();
      return;
    }
    const long long t0 = detail::now_ns();
    struct Charge {  // charged even when f throws
      const Loop& loop;
      long long t0;
      ~Charge() {
        const int slot = detail::thread_slot();
        auto& slots = loop.recorder_->slots;
        if (slot < static_cast<int>(slots.size())) {
          slots[slot].busy_ns[loop.phase_] += detail::now_ns() - t0;
          ++slots[slot].chunks[loop.phase_];
        }
      }
    } charge{*this, t0};
    f();
  }

 private:
  detail::Recorder* recorder_ = nullptr;
  int phase_ = 0;
  long long start_ = 0;
};

/// Mark the calling thread as helper k of sesi::parallel's team (busy time goes to slot k + 1).
inline void set_thread_slot(int helper) noexcept { detail::thread_slot() = helper + 1; }

/// One phase of a profile (seconds).
struct PhaseTotals {
  long long calls = 0;                ///< Scopes entered (1 for other)
  long long loops = 0;                ///< parallel loops started in the phase
  double wall = 0;                    ///< exclusive wall time on the recording thread
  double loop_wall = 0;               ///< wall time of the parallel loops started in it
  double serial = 0;                  ///< wall - loop_wall
  std::vector<double> busy;           ///< per thread: time running loop chunks in it
  std::vector<long long> chunks;      ///< per thread: chunks run in it
};

/// A finished profile.
struct Report {
  int threads = 1;                              ///< thread slots (0 the recording thread)
  long steps = 0;                               ///< the steps in the window (set by the caller)
  double wall = 0;                              ///< the profiled window (sum of the phases' wall)
  std::array<PhaseTotals, phase_count> phases;  ///< indexed by Phase
  double serial() const {
    double s = 0;
    for (const PhaseTotals& p : phases) s += p.serial;
    return s;
  }
  /// Total serial time over the window's wall time (0 for an empty window).
  double serial_fraction() const { return wall > 0 ? serial() / wall : 0.0; }
};

/// Start recording on the calling thread, with slots for `threads` threads (the loops' thread
/// count: sesi::parallel::threads()). Resets any earlier profile. Call it outside any Scope.
inline void start(int threads) {
  detail::Recorder& r = detail::recorder();
  detail::enabled_flag.store(false, std::memory_order_relaxed);
  r.slots.assign(static_cast<std::size_t>(std::max(threads, 1)), detail::ThreadSlot{});
  r.wall_ns.fill(0);
  r.loop_wall_ns.fill(0);
  r.calls.fill(0);
  r.loops.fill(0);
  r.current = Phase::other;
  r.loop_depth = 0;
  detail::this_thread_recorder() = &r;
  r.begin = r.mark = detail::now_ns();
  detail::enabled_flag.store(true, std::memory_order_release);
}

/// Stop recording (on the thread that started) and return the profile. Call it outside any Scope.
inline Report stop() {
  detail::Recorder& r = detail::recorder();
  const long long end = detail::now_ns();
  r.charge(end);
  detail::enabled_flag.store(false, std::memory_order_relaxed);
  detail::this_thread_recorder() = nullptr;
  Report report;
  report.threads = static_cast<int>(r.slots.size());
  report.wall = 1e-9 * static_cast<double>(end - r.begin);
  for (int k = 0; k < phase_count; ++k) {
    PhaseTotals& p = report.phases[k];
    p.calls = k == static_cast<int>(Phase::other) ? 1 : r.calls[k];
    p.loops = r.loops[k];
    p.wall = 1e-9 * static_cast<double>(r.wall_ns[k]);
    p.loop_wall = 1e-9 * static_cast<double>(r.loop_wall_ns[k]);
    p.serial = 1e-9 * static_cast<double>(r.wall_ns[k] - r.loop_wall_ns[k]);
    for (const detail::ThreadSlot& s : r.slots) {
      p.busy.push_back(1e-9 * static_cast<double>(s.busy_ns[k]));
      p.chunks.push_back(s.chunks[k]);
    }
  }
  return report;
}

}  // namespace sesi::profile
