#pragma once
/// @file stepper.hpp
/// One composition engine over coefficient tables (coefficients.hpp).
///
/// The base step is the seed's hierarchical Strang splitting (seed paper, eqs. 6-8 and
/// Discussion) of H = K + V with K = K_1 + ... + K_n. Each flow is exact and explicit
/// (chart.hpp), so every composition is explicit, symplectic and, being palindromic,
/// time-reversible. Two forms (Splitting):
///  - drift-kick-drift, the default and the seed's form as printed: half flows of K_1..K_n, the
///    full kick, half flows of K_n..K_1. Where two stages meet, their K_1 half flows are fused
///    into one (K_1 depends on p_1 alone, so its flows compose exactly).
///  - kick-drift-kick: half kick, K_1..K_{n-1} for h/2, K_n for h, K_{n-1}..K_1 for h/2, half
///    kick. The kinetic sweep is itself symmetric, so at second order the chart enters the
///    modified Hamiltonian only through purely kinetic brackets, even in p: the form to use with
///    re-charting (recharting.hpp, RechartingComposition; docs/charts.md), where it keeps the
///    energy error bounded. Kicks where two stages meet fuse, and the first kick of a step
///    reuses the last gradient of the step before: one force evaluation per stage.
///
/// A Stage (the 4th template parameter; default NoStage, which compiles away) adds a
/// thermostat's stages to the kick-drift-kick Strang step (thermostat.hpp, docs/thermostats.md):
///  - an outer hook at the step's start and end, acting on all momenta through the total kinetic
///    energy (a Nose-Hoover chain's or a velocity rescale's half step);
///  - a per-body hook between the two halves of the top level's flow (Langevin's O: BAOAB).
/// Neither moves q, so the kept gradient stays valid: one force evaluation per step with any stage.
/// The stage's interface (the engine's only calls to it):
///   Scalar time_step(Scalar dt)             the engine's step h for a time step dt
///   bool acts_on_total(), acts_on_bodies()  which hooks run this step
///   total(sys, x, ws, h, which)             outer hook over time h, which = 0 (start) or 1 (end)
///   begin_bodies(n, h); body(chart, b, m, q, p); end_bodies(sys)   the per-body hook, body by body
///                                           (on threads: body() writes only body b's data)
///   end_step()                              after the step (the stage's step counter)
///
/// Steppers model odeint's Stepper concept (order(), do_step(sys, x, t, dt), the usual types);
/// sesi/odeint.hpp adds the stepper_category tag so that integrate_const drives them.

#include <algorithm>
#include <array>
#include <atomic>
#include <cstdint>
#include <functional>
#include <type_traits>
#include <utility>
#include <variant>
#include <vector>

#include "sesi/chart.hpp"
#include "sesi/coefficients.hpp"
#include "sesi/profile.hpp"
#include "sesi/state.hpp"
#include "sesi/system.hpp"

namespace sesi {

/// Which form of the base step: drift-kick-drift (the seed's; kinetic half flows outside) or
/// kick-drift-kick (potential half kicks outside; on E^n this is velocity Verlet).
enum class Splitting { drift_kick_drift, kick_drift_kick };

/// The composition engine's default stage: none (the NVE step; every hook compiles away).
struct NoStage {};

namespace detail {
template <class T>
struct unwrap {
  using type = T;
  static T& get(T& t) { return t; }
  static const T& get(const T& t) { return t; }  // do_step(const System&, ...)
};
template <class T>
struct unwrap<std::reference_wrapper<T>> {
  using type = T;
  static T& get(std::reference_wrapper<T> t) { return t.get(); }
};

/// The exact flow of level i for time h on body b, held in sc.q, sc.p, with body b's trig cache
/// in ws when the chart has one (own_trig = false leaves level i's own entry stale): the one call
/// of a level flow that every stepper makes.
template <class Chart, class Scratch>
void cached_level_flow(const Chart& chart, Workspace<Chart>& ws, int b, int i, typename Chart::Scalar m,
                       typename Chart::Scalar h, Scratch& sc, bool own_trig = true) {
  if constexpr (HasTrigCache<Chart>) {
    chart.level_flow(i, sc.q, sc.p, m, h, ws.trig[static_cast<std::size_t>(b)], own_trig);
  } else {
    static_cast<void>(ws);
    static_cast<void>(b);
    static_cast<void>(own_trig);
    level_flow(chart, i, sc.q, sc.p, m, h);
  }
}

/// Charts whose K-flows the kick-drift-kick engine runs in blocks of bodies (flows_in_blocks):
/// a trig cache, its entries for many bodies at once (level_trig), and a fixed dimension (the
/// blocks' points live on the stack: no allocation in a step).
template <class Chart>
concept blocked_flows =
    HasTrigCache<Chart> && Chart::dimension != Eigen::Dynamic &&
    requires(const Chart& c, int i, const typename Chart::Scalar* q, typename Chart::Scalar* s) {
      c.level_trig(i, q, s, s, i);
    };

/// The kick-drift-kick step's K-flows in order, as (level, time) pairs: K_1(h/2)..K_{n-1}(h/2)
/// K_n(h) K_{n-1}(h/2)..K_1(h/2), a zero time of level 0 left out (levels 0-based here).
template <class Scalar, int N>
struct KdkFlows {
  std::array<int, 2 * N + 1> level{};
  std::array<Scalar, 2 * N + 1> time{};
  int count = 0;
  KdkFlows(int top, Scalar h) {
    const Scalar half = h / Scalar(2);
    if (top == 0) {
      if (h != Scalar(0)) add(0, h);
      return;
    }
    if (half != Scalar(0)) add(0, half);
    for (int i = 1; i < top; ++i) add(i, half);
    add(top, h);
    for (int i = top - 1; i >= 1; --i) add(i, half);
    if (half != Scalar(0)) add(0, half);
  }
  void add(int i, Scalar t) {
    level[static_cast<std::size_t>(count)] = i;
    time[static_cast<std::size_t>(count)] = t;
    ++count;
  }
};

/// Whether a and b have the same shape and numbers (a NaN differs from itself), compared column
/// by column on threads.
template <class M>
bool same_columns(const M& a, const M& b) {
  if (a.rows() != b.rows() || a.cols() != b.cols()) return false;
  const int n = static_cast<int>(a.cols());
  std::atomic<bool> differ{false};
  parallel::for_chunks(n, parallel::chunks_for(n), [&](int begin, int end, int) {
    if (a.middleCols(begin, end - begin) != b.middleCols(begin, end - begin)) differ.store(true, std::memory_order_relaxed);
  });
  return !differ.load();
}
/// to = from (sized as from), copied column by column on threads.
template <class M>
void copy_columns(const M& from, M& to) {
  if (to.rows() != from.rows() || to.cols() != from.cols()) to.resize(from.rows(), from.cols());
  const int n = static_cast<int>(from.cols());
  parallel::for_chunks(n, parallel::chunks_for(n), [&](int begin, int end, int) {
    to.middleCols(begin, end - begin) = from.middleCols(begin, end - begin);
  });
}

/// The last kick's gradient dV/dq and what it depended on (the system, the body frames, the
/// cluster frame), so that a step whose first kick is at the point of the last step's last kick
/// reuses it (first same as last, as odeint's velocity_verlet keeps its acceleration).
template <class Chart>
class KeptGradient {
  using state_type = State<Chart>;

 public:
  /// The matrix the last kick wrote (kick_cached's gradient argument).
  typename state_type::Matrix& gradient() { return grad_; }
  /// Record what the gradient just computed into gradient() depends on (frames_kept: the kept
  /// frames are x's already, as when the step reused the kept gradient: a copy the less).
  template <class Sys>
  void keep(const Sys& sys, const state_type& x, bool frames_kept = false) {
    // changed_bodies' marks and scratch sized here, at the first step, so that no later step allocates.
    if (marks_.size() != static_cast<std::size_t>(x.q.cols())) marks_.resize(static_cast<std::size_t>(x.q.cols()));
    const int n = static_cast<int>(x.q.cols());
    if (n > 0 && scan_.size() < static_cast<std::size_t>(parallel::chunks_for(n))) {
      scan_.resize(static_cast<std::size_t>(parallel::chunks_for(n)));
    }
    system_ = &sys;
    if constexpr (requires { sys.instance(); }) instance_ = sys.instance();
    if (!frames_kept) copy_frames(x.frames);
    clustered_ = x.clustered;
    if (x.clustered) cluster_ = x.cluster;
  }
  void forget() { system_ = nullptr; }

  /// Whether the kept gradient is of sys at a state of x's shape, framing and cluster frame:
  /// then out gets the bodies (ascending) whose q (against last_q) or frame differ from the kept
  /// gradient's, the ones System::patch_gradient brings it up to date for.
  template <class Sys>
  bool changed_bodies(const Sys& sys, const state_type& x, const typename state_type::Matrix& last_q,
                      std::vector<int>& out) {
    if (grad_.cols() != x.p.cols() || grad_.rows() != x.p.rows() || last_q.cols() != x.q.cols() ||
        last_q.rows() != x.q.rows() || !same_system(sys) || frames_.size() != x.frames.size() ||
        clustered_ != x.clustered || (x.clustered && cluster_ != x.cluster)) {
      return false;
    }
    // Marked on threads (each body its own mark), collected in body order.
    const int n = static_cast<int>(x.q.cols());
    marks_.resize(static_cast<std::size_t>(n));
    parallel::for_chunks(n, parallel::chunks_for(n), [&](int begin, int end, int) {
      for (int b = begin; b < end; ++b) {
        const std::size_t k = static_cast<std::size_t>(b);
        marks_[k] = last_q.col(b) != x.q.col(b) || (!frames_.empty() && frames_[k] != x.frames[k]);
      }
    });
    // Collected on threads too (a serial pass over every mark was Amdahl's share of a step).
    parallel::select_in_order(
        n, scan_, [&](int b) { return marks_[static_cast<std::size_t>(b)] != 0; },
        [&](int count) { out.resize(static_cast<std::size_t>(count)); },
        [&](int k, int b) { out[static_cast<std::size_t>(k)] = b; });
    return true;
  }
  /// After a patch: the changed bodies' frames are the kept gradient's now.
  void keep_frames(const state_type& x, const std::vector<int>& changed) {
    if (frames_.empty()) return;
    for (const int b : changed) frames_[static_cast<std::size_t>(b)] = x.frames[static_cast<std::size_t>(b)];
  }

 private:
  /// Whether sys is the system of the kept gradient: by its stamp (sesi::System), else by its
  /// address (a system whose parameters change in place needs reset()).
  template <class Sys>
  bool same_system(const Sys& sys) const {
    if constexpr (requires { sys.instance(); }) {
      return system_ != nullptr && instance_ == sys.instance();
    } else {
      return system_ == static_cast<const void*>(&sys);
    }
  }

  /// frames_ = frames, copied on threads (a frame per body: 7 MB at 10^5 bodies on S^2).
  void copy_frames(const std::vector<typename state_type::Frame>& frames) {
    const int n = static_cast<int>(frames.size());
    frames_.resize(frames.size(), state_type::identity_frame());
    parallel::for_chunks(n, parallel::chunks_for(n), [&](int begin, int end, int) {
      std::copy(frames.begin() + begin, frames.begin() + end, frames_.begin() + begin);
    });
  }

  typename state_type::Matrix grad_;
  std::vector<char> marks_;  // changed_bodies' marks
  std::vector<int> scan_;    // changed_bodies' per chunk (parallel::select_in_order)
  const void* system_ = nullptr;
  std::uint64_t instance_ = 0;  // sesi::System's stamp: its address is no identity
  std::vector<typename state_type::Frame> frames_;
  bool clustered_ = false;  // and the cluster frame (State::cluster) it was taken in
  typename state_type::Frame cluster_ = state_type::identity_frame();
};
}  // namespace detail

/// A symmetric composition of the base step over the weights of Table (coefficients.hpp), or,
/// with Table = coefficients::Runtime, over weights given at run time (same engine, same
/// operations: the two step bit for bit alike). Stage: a thermostat's stages (see above; the
/// kick-drift-kick form with the 1-stage Strang table only).
template <class Table, HierarchicalChart Chart,
          Splitting Form = Splitting::drift_kick_drift, class Stage = NoStage>
class Composition {
  static constexpr bool runtime_table = std::is_same_v<Table, coefficients::Runtime>;
  static constexpr bool staged = !std::is_same_v<Stage, NoStage>;
  static_assert(!staged || Form == Splitting::kick_drift_kick,
                "sesi: a stage (thermostat) runs in the kick-drift-kick form only");

 public:
  using Scalar = typename Chart::Scalar;
  using state_type = State<Chart>;
  using deriv_type = State<Chart>;
  using value_type = Scalar;
  using time_type = Scalar;
  using order_type = unsigned short;
  using table = Table;
  using weights_type = std::conditional_t<runtime_table, std::vector<Scalar>,
                                          std::array<Scalar, Table::stages>>;

  /// The table's order (0 for a runtime table: ask order()).
  static constexpr order_type order_value = Table::order;

  Composition() requires(!runtime_table) : w_(Table::template weights<Scalar>()) {}
  /// A fixed table with a stage (a thermostat).
  explicit Composition(Stage stage) requires(!runtime_table && staged)
      : w_(Table::template weights<Scalar>()), stage_(std::move(stage)) {
    check_stage();
  }
  /// A runtime table: palindromic weights summing to 1, of the given order.
  Composition(std::vector<Scalar> weights, order_type order) requires runtime_table
      : w_(std::move(weights)), order_(order) {
    SESI_CHECK(!w_.empty(), "a composition needs at least one stage");
    check_stage();
  }
  /// A runtime table with a stage (a thermostat).
  Composition(std::vector<Scalar> weights, order_type order, Stage stage) requires(runtime_table && staged)
      : w_(std::move(weights)), order_(order), stage_(std::move(stage)) {
    SESI_CHECK(!w_.empty(), "a composition needs at least one stage");
    check_stage();
  }
  /// A runtime-table composition with the weights and order of a fixed table T.
  template <class T>
  static Composition of() requires runtime_table {
    const auto w = T::template weights<Scalar>();
    return Composition(std::vector<Scalar>(w.begin(), w.end()), T::order);
  }
  /// The same with a stage (a thermostat).
  template <class T>
  static Composition of(Stage stage) requires(runtime_table && staged) {
    const auto w = T::template weights<Scalar>();
    return Composition(std::vector<Scalar>(w.begin(), w.end()), T::order, std::move(stage));
  }

  /// The stage (a thermostat: its temperature, step counter, heat).
  Stage& stage() requires staged { return stage_; }
  const Stage& stage() const requires staged { return stage_; }

  order_type order() const {
    if constexpr (runtime_table) {
      return order_;
    } else {
      return Table::order;
    }
  }
  std::size_t stages() const { return w_.size(); }
  const weights_type& weights() const { return w_; }

  /// Advance x from t to t + dt in place (odeint's do_step(sys, x, t, dt)).
  template <class Sys>
  void do_step(Sys&& system, state_type& x, time_type /*t*/, time_type dt) {
    using Raw = std::remove_cvref_t<Sys>;
    const auto& sys = detail::unwrap<Raw>::get(system);
    // A few bodies re-charted since (Recharting, a topology's reduction): their trig and the
    // gradient rows that depend on them are brought up to date, the rest kept. A turn keeps q
    // and changes the body's frame (recharting.hpp), so the frames are asked too: with q alone,
    // one turned body among 10^5 (most steps of a Lennard-Jones run on S^2) cost a whole force
    // evaluation, 1.9 per step instead of 1.
    const bool kept = patch(sys, x);  // whether the kept gradient is x's (kick-drift-kick)
    // The trig caches left by the last step are valid if q is what that step produced (asked
    // only where the patch did not already bring them up to date).
    const bool q_unchanged = kept || detail::same_columns(last_q_, x.q);
    if (!q_unchanged) sys.refresh(x, ws_);  // sizes the workspace; one sine and cosine per coordinate
    if constexpr (Form == Splitting::drift_kick_drift) {
      step_dkd(sys, x, dt);
    } else {
      step_kdk(sys, x, dt, kept);
    }
    detail::copy_columns(x.q, last_q_);
  }

  /// The step's workspace (its Verlet lists serve diagnostics at the same points: share_lists).
  Workspace<Chart>& workspace() { return ws_; }

  /// Forget what the last step left (the trig caches and the last gradient), e.g. after changing
  /// the system's parameters in place; do_step notices a new q, new frames or another system
  /// (another sesi::System object, even at the address of the last one).
  void reset() {
    last_q_.resize(Eigen::NoChange, 0);  // (a fixed-size row count: resize(0, 0) fails Eigen's assertion)
    kept_.forget();
  }

 private:
  /// The exact flow of level i for time h on body b, held in sc.q, sc.p (and its trig cache;
  /// own_trig = false leaves level i's own entry stale, see step_dkd).
  template <class Scratch>
  void flow(const Chart& chart, int b, int i, Scalar m, Scalar h, Scratch& sc, bool own_trig = true) {
    detail::cached_level_flow(chart, ws_, b, i, m, h, sc, own_trig);
  }
  /// Apply f(b, m, scratch) to every body b, loaded into scratch.q, scratch.p and stored back;
  /// on threads for many bodies (each body's flows touch only its own data).
  template <class Sys, class F>
  void each_body(const Sys& sys, state_type& x, F&& f) {
    const profile::Scope drift(profile::Phase::drift);  // the K-flows (and a per-body stage hook)
    if (sys.bodies() < parallel::min_parallel_bodies) {  // the workspace's own q, p: no chunks
      for (int b = 0; b < sys.bodies(); ++b) {
        ws_.q = x.q.col(b);
        ws_.p = x.p.col(b);
        f(b, sys.mass(b), ws_);
        x.q.col(b) = ws_.q;
        x.p.col(b) = ws_.p;
      }
      return;
    }
    sys.for_bodies(ws_, [&](int b, auto& sc) {
      sc.q = x.q.col(b);
      sc.p = x.p.col(b);
      f(b, sys.mass(b), sc);
      x.q.col(b) = sc.q;
      x.p.col(b) = sc.p;
    });
  }
  /// The kick-drift-kick form's K-flows `flows` (no per-body stage hook) where the chart gives
  /// its trig entries for many bodies at once (detail::blocked_flows): bodies in blocks of
  /// flow_block, each flow's arithmetic body by body (level_flow with own_trig = false), then
  /// the block's new sines and cosines in one call, in vector lanes (Chart::level_trig: glibc's
  /// scalar sincos was 12 % of a 10^5-body step on S^2, issue #27). Every body goes through the
  /// same operations as in the per-body loop, so the bits depend on no block, chunk or thread.
  template <class Sys, class Flows>
  void flows_in_blocks(const Sys& sys, state_type& x, const Flows& flows) {
    const profile::Scope drift(profile::Phase::drift);
    constexpr int flow_block = 16;
    const Chart& chart = sys.chart();
    const int n = sys.bodies();
    parallel::for_chunks(n, parallel::chunks_for(n), [&](int begin, int end, int) {
      std::array<typename Chart::Point, flow_block> q, p;
      std::array<Scalar, flow_block> m, qi, sn, cs;
      for (int b0 = begin; b0 < end; b0 += flow_block) {
        const int count = std::min(flow_block, end - b0);
        for (int j = 0; j < count; ++j) {
          q[j] = x.q.col(b0 + j);
          p[j] = x.p.col(b0 + j);
          m[j] = sys.mass(b0 + j);
        }
        for (int f = 0; f < flows.count; ++f) {
          const int i = flows.level[f];
          for (int j = 0; j < count; ++j) {
            chart.level_flow(i, q[j], p[j], m[j], flows.time[f], ws_.trig[static_cast<std::size_t>(b0 + j)],
                             /*own_trig=*/false);
            qi[j] = q[j][i];
          }
          chart.level_trig(i, qi.data(), sn.data(), cs.data(), count);
          for (int j = 0; j < count; ++j) {
            auto& t = ws_.trig[static_cast<std::size_t>(b0 + j)];
            t.s[i] = sn[j];
            t.c[i] = cs[j];
          }
        }
        for (int j = 0; j < count; ++j) {
          x.q.col(b0 + j) = q[j];
          x.p.col(b0 + j) = p[j];
        }
      }
    });
  }
  /// After a drift, before the kick: the system's hook (System::drifted: a domain of a simulation
  /// across processes refreshes its halo there), where it has one.
  template <class Sys>
  void drifted(const Sys& sys, state_type& x) {
    if constexpr (requires { sys.drifted(x, ws_); }) sys.drifted(x, ws_);
  }
  /// A stage's hooks sit in the 1-stage (Strang) step: thermostats run with that table only.
  void check_stage() const {
    if constexpr (staged) SESI_CHECK(w_.size() == 1, "a thermostat runs with the 1-stage Strang table only");
  }
  /// Forward level flows on every body: level 0 for time h0, levels 1..last for time h.
  template <class Sys>
  void forward(const Sys& sys, state_type& x, Scalar h0, Scalar h, int last) {
    each_body(sys, x, [&](int b, Scalar m, auto& sc) {
      if (h0 != Scalar(0)) flow(sys.chart(), b, 0, m, h0, sc);
      for (int i = 1; i <= last; ++i) flow(sys.chart(), b, i, m, h, sc);
    });
  }
  /// Backward level flows on every body: levels from..1 for time h, then level 0 for time h0.
  /// With stale_top, level `from` leaves its own sine stale: in the drift-kick-drift form no
  /// flow reads the top level's sine and the next forward pass flows it again before any kick.
  template <class Sys>
  void backward(const Sys& sys, state_type& x, Scalar h, Scalar h0, int from,
                bool stale_top = false) {
    each_body(sys, x, [&](int b, Scalar m, auto& sc) {
      for (int i = from; i >= 1; --i) flow(sys.chart(), b, i, m, h, sc, !(stale_top && i == from));
      if (h0 != Scalar(0)) flow(sys.chart(), b, 0, m, h0, sc, !(stale_top && from == 0));
    });
  }

  template <class Sys>
  void step_dkd(const Sys& sys, state_type& x, Scalar dt) {
    const int top = sys.dim() - 1;
    const std::size_t s = w_.size();
    Scalar pending = w_[0] * dt / Scalar(2);  // level-0 flow carried over from the last stage
    for (std::size_t k = 0; k < s; ++k) {
      const Scalar half = w_[k] * dt / Scalar(2);
      forward(sys, x, pending, half, top);
      drifted(sys, x);
      sys.kick_cached(x, w_[k] * dt, ws_);
      // Levels n-1..1 now; level 0 is fused with the next stage's first half flow.
      pending = half + (k + 1 < s ? w_[k + 1] * dt / Scalar(2) : Scalar(0));
      backward(sys, x, half, k + 1 < s ? Scalar(0) : pending, top, /*stale_top=*/true);
    }
  }

  /// The kick-drift-kick form. Its first kick is at the point of the last step's last kick, so
  /// it reuses that kick's gradient when nothing it depends on changed (first same as last, as
  /// odeint's velocity_verlet keeps its acceleration): one force evaluation per stage. With a
  /// stage: its outer hook before the first kick and after the last (NHC(h/2) step NHC(h/2)),
  /// its per-body hook between the two halves of the top level's flow (B A O A B). reuse: the
  /// kept gradient is x's (do_step).
  template <class Sys>
  void step_kdk(const Sys& sys, state_type& x, Scalar dt, bool reuse) {
    const int top = sys.dim() - 1;
    const std::size_t s = w_.size();
    bool outer = false, inner = false;
    if constexpr (staged) {
      dt = stage_.time_step(dt);  // Brownian dynamics: the BAOAB limit's h for a time step dt
      outer = stage_.acts_on_total();
      inner = stage_.acts_on_bodies();
      const profile::Scope thermostat(profile::Phase::thermostat);
      if (outer) stage_.total(sys, x, ws_, dt / Scalar(2), 0);
      if (inner) stage_.begin_bodies(sys.bodies(), dt);
    }
    Scalar pending = w_[0] * dt / Scalar(2);  // half kick carried over from the last stage
    for (std::size_t k = 0; k < s; ++k) {
      const Scalar h = w_[k] * dt;
      if (k == 0 && reuse) {
        // p -= h g, body by body on threads (the same bits as the whole matrix at once).
        const auto& g = kept_.gradient();
        parallel::for_chunks(sys.bodies(), parallel::chunks_for(sys.bodies()), [&](int begin, int end, int) {
          x.p.middleCols(begin, end - begin).noalias() -= pending * g.middleCols(begin, end - begin);
        });
      } else {
        sys.kick_cached(x, pending, ws_, kept_.gradient());
      }
      // Kinetic part, one pass body by body (each body's flows touch only its own data):
      // K_1(h/2)..K_{n-1}(h/2) K_n(h) K_{n-1}(h/2)..K_1(h/2); with the per-body hook O,
      // K_1(h/2)..K_n(h/2) O K_n(h/2)..K_1(h/2). Level 0 skips a zero time (as ever).
      const Scalar half = h / Scalar(2);
      if constexpr (detail::blocked_flows<Chart>) {
        if (!inner) {
          flows_in_blocks(sys, x, detail::KdkFlows<Scalar, Chart::dimension>(top, h));
          drifted(sys, x);
          pending = h / Scalar(2) + (k + 1 < s ? w_[k + 1] * dt / Scalar(2) : Scalar(0));
          continue;
        }
      }
      each_body(sys, x, [&](int b, Scalar m, auto& sc) {
        const Chart& chart = sys.chart();
        if (top == 0 && !inner) {
          if (h != Scalar(0)) flow(chart, b, 0, m, h, sc);
          return;
        }
        if (half != Scalar(0)) flow(chart, b, 0, m, half, sc);
        for (int i = 1; i < top; ++i) flow(chart, b, i, m, half, sc);
        if constexpr (staged) {
          if (inner) {
            // The first half leaves the top level's own sine stale: no flow of this body reads
            // it before the second half refreshes it (the hook reads q itself).
            if (top > 0) flow(chart, b, top, m, half, sc, /*own_trig=*/false);
            stage_.body(chart, b, m, sc.q, sc.p);
            if (top > 0) flow(chart, b, top, m, half, sc);
          } else {
            flow(chart, b, top, m, h, sc);
          }
        } else {
          flow(chart, b, top, m, h, sc);
        }
        for (int i = top - 1; i >= 1; --i) flow(chart, b, i, m, half, sc);
        if (half != Scalar(0)) flow(chart, b, 0, m, half, sc);
      });
      drifted(sys, x);
      pending = h / Scalar(2) + (k + 1 < s ? w_[k + 1] * dt / Scalar(2) : Scalar(0));
    }
    sys.kick_cached(x, pending, ws_, kept_.gradient());
    kept_.keep(sys, x, /*frames_kept=*/reuse);  // (a step changes no frame)
    if constexpr (staged) {
      const profile::Scope thermostat(profile::Phase::thermostat);
      if (inner) stage_.end_bodies(sys);
      if (outer) stage_.total(sys, x, ws_, dt / Scalar(2), 1);
      stage_.end_step();
    }
  }

  /// The kick-drift-kick form: whether the kept gradient (and its trig) is x's, brought up to
  /// date by System::patch_gradient where some bodies changed chart or frame since the last
  /// step's last kick, exact to the bit; false where it cannot be (another system, too many
  /// changed bodies, the first step).
  template <class Sys>
  bool patch(const Sys& sys, const state_type& x) {
    if constexpr (Form == Splitting::kick_drift_kick &&
                  requires { sys.patch_gradient(x, ws_, changed_, kept_.gradient()); }) {
      if (!kept_.changed_bodies(sys, x, last_q_, changed_)) return false;
      if (changed_.empty()) return true;  // nothing changed: the kept gradient is x's
      if (!sys.patch_gradient(x, ws_, changed_, kept_.gradient())) return false;
      kept_.keep_frames(x, changed_);
      return true;
    } else {
      static_cast<void>(sys);
      static_cast<void>(x);
      return false;
    }
  }

  weights_type w_;
  [[no_unique_address]] std::conditional_t<runtime_table, order_type, std::monostate> order_{};
  Workspace<Chart> ws_;
  std::vector<int> changed_;  // patch's changed bodies
  typename state_type::Matrix last_q_;  // q after the last step: its trig is in ws_
  detail::KeptGradient<Chart> kept_;  // the kick-drift-kick form's last gradient, at last_q_
  [[no_unique_address]] Stage stage_{};
};

/// The methods by their tables' authors (citations in coefficients.hpp).
template <class Chart>
using Strang = Composition<coefficients::Strang, Chart>;
template <class Chart>
using Yoshida4 = Composition<coefficients::Yoshida4, Chart>;
template <class Chart>
using Suzuki4 = Composition<coefficients::Suzuki4, Chart>;
template <class Chart>
using McLachlan4 = Composition<coefficients::McLachlan4, Chart>;
template <class Chart>
using Yoshida6 = Composition<coefficients::Yoshida6, Chart>;
template <class Chart>
using KahanLi6 = Composition<coefficients::KahanLi6, Chart>;
template <class Chart>
using McLachlan8 = Composition<coefficients::McLachlan8, Chart>;
template <class Chart>
using KahanLi8 = Composition<coefficients::KahanLi8, Chart>;

/// The same methods by the program's names (`sesi run --method sesi4`, sesi.methods() in Python):
/// SESI p is the seed's SESI of order p (seed paper: SESI 2 and SESI 4), the suffix the table.
template <class Chart>
using Sesi2 = Strang<Chart>;
template <class Chart>
using Sesi4 = Yoshida4<Chart>;
template <class Chart>
using Sesi4Suzuki = Suzuki4<Chart>;
template <class Chart>
using Sesi4McLachlan = McLachlan4<Chart>;
template <class Chart>
using Sesi6 = Yoshida6<Chart>;
template <class Chart>
using Sesi6KahanLi = KahanLi6<Chart>;
template <class Chart>
using Sesi8 = McLachlan8<Chart>;
template <class Chart>
using Sesi8KahanLi = KahanLi8<Chart>;

}  // namespace sesi
