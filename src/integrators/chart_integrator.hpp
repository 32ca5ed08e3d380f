#pragma once
/// @file chart_integrator.hpp
/// The Integrator of one compile-time chart: what each (space, dimension) instantiates: the
/// system, one composition engine (and one thermostatted engine, for a scene with a
/// [thermostat]: thermostat_stepper.hpp), and the diagnostics of the framed state.

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <utility>
#include <variant>
#include <vector>

#include <sesi/diagnostics.hpp>
#include <sesi/recharting.hpp>

#include <sesi/spaces/euclidean.hpp>
#include <sesi/spaces/hyperbolic.hpp>
#include <sesi/spaces/sphere.hpp>
#include <sesi/topology.hpp>

#include "integrator.hpp"
#include "methods.hpp"
#include "terms.hpp"
#include "thermostat_stepper.hpp"

namespace sesi::program {

/// The chart of a scene's space as Chart (whose dimension must match the scene's); on a space with
/// a topology the Quotient of the covering chart by the scene's box or surface (topology.hpp).
template <class Chart>
Chart make_chart(const SpaceSpec& space) {
  if constexpr (sesi::HasTopology<Chart>) {
    using Topo = typename Chart::Topology;
    auto cover = make_chart<typename Chart::Cover>(space);
    if constexpr (requires { typename Topo::Word; }) {
      return Chart(std::move(cover), Topo(space.genus, space.radius));  // a compact surface H^2/Gamma
    } else {
      const typename Topo::Vector edges =
          Eigen::Map<const Eigen::VectorXd>(space.box.data(), static_cast<Eigen::Index>(space.box.size()));
      return Chart(std::move(cover), Topo(edges));  // a periodic box
    }
  } else if constexpr (std::is_constructible_v<Chart, double, int>) {
    return Chart(space.radius, space.dim);  // S^n, H^n
  } else {
    return Chart(space.dim);  // E^n
  }
}

/// The scene's initial state on Chart.
template <class Chart>
sesi::State<Chart> initial_state(const Scene& scene) {
  sesi::State<Chart> x(scene.dim(), scene.body_count());
  for (int b = 0; b < scene.body_count(); ++b) {
    x.q.col(b) = scene.bodies[static_cast<std::size_t>(b)].q;
    x.p.col(b) = scene.bodies[static_cast<std::size_t>(b)].p;
  }
  return x;
}

/// A topology's image record (Topology::Images), or nothing for a chart without one.
template <class Chart>
struct ImagesOf {
  using type = std::monostate;
};
template <sesi::HasTopology Chart>
struct ImagesOf<Chart> {
  using type = typename Chart::Topology::Images;
};

template <class Chart>
class ChartIntegrator final : public Integrator {
  static constexpr bool topology = sesi::HasTopology<Chart>;
  /// A compact surface (group words), not a box (image counts).
  static constexpr bool surface = [] {
    if constexpr (topology) {
      return requires { typename Chart::Topology::Word; };
    } else {
      return false;
    }
  }();

 public:
  explicit ChartIntegrator(const Scene& scene)
      : sys_(make_system(scene, make_chart<Chart>(scene.space))),
        x_(initial_state<Chart>(scene)),
        stepper_(make_chart_stepper(scene)) {
    if constexpr (sesi::ClusterChart<Chart>) enter_cluster_frame(scene);
    if constexpr (topology) {
      // Bodies given anywhere start in the domain (every one outside it, by any amount, even on
      // the far face of a box: a margin below 0), with their images at the identity: the
      // unwrapped positions start where they are.
      const auto& topo = sys_.chart().topology();
      images_ = topo.identity_images(x_.bodies());
      sesi::wrap(sys_, x_, images_, -1.0);
      images_ = topo.identity_images(x_.bodies());
      margin_ = wrap_margin(scene, topo.max_cutoff());
    }
    // A body that starts near a singular set of the scene's chart is re-charted before the first
    // step, as after every step: else that step runs in the singular chart (on S^9 a body at
    // sin q_8 = 0.11 turns its last angle by 0.9 rad in one step of 0.01, and sesi8-kahan-li
    // ended 2e-4 off where geodesic8-kahan-li was 1e-13).
    if constexpr (sesi::Rechartable<Chart>) sesi::rechart(sys_, x_, sesi::RechartPolicy<double>{});
    if (stepper_->processed()) {
      dt_ = scene.integrator.dt.value_or(0.0);
      initial_ = x_;
    }
    // The diagnostics evaluate where the step's last kick did: one set of Verlet lists serves both.
    w_.share_lists(stepper_->workspace());
  }
  ChartIntegrator(const ChartIntegrator&) = delete;
  ChartIntegrator& operator=(const ChartIntegrator&) = delete;

  void step(double t, double h) override {
    const bool framed = x_.framed();
    if (whole_run_ && framed) {
      for (std::size_t k = 0; k < own_.size(); ++k) own_frames_[k] = x_.frames[static_cast<std::size_t>(own_[k])];
    }
    stepper_->step(x_, t, h);
    bool wrapped = false;
    if constexpr (topology) wrapped = wrap();  // a thermostat's step too
    if (whole_run_) {
      // A domain with pair terms without a cutoff: where a body anywhere was re-charted (its
      // frame changed: a turn or a homing) or wrapped, one process evaluates every force afresh
      // at the next step (System::patch_gradient cannot patch such terms), so every process
      // does, even one whose bodies did not change: else it would reuse its kept gradient while
      // the others gather the points for theirs.
      bool changed = wrapped || framed != x_.framed();
      if (framed && !changed) {
        for (std::size_t k = 0; k < own_.size() && !changed; ++k) {
          changed = own_frames_[k] != x_.frames[static_cast<std::size_t>(own_[k])];
        }
      }
      if (any_(changed)) sys_.renew_instance();
    }
    shown_valid_ = false;
    if (dt_ == 0.0) dt_ = h;  // a processed method's step, when the scene has none
  }

  bool thermostatted() const override { return thermostat_ != nullptr; }
  void set_temperature(double kT) override {
    if (!thermostat_) return;
    sesi::Thermostat<Chart>& t = thermostat_->thermostat();
    // Nose-Hoover's extended energy depends on kT (N_f kT xi_1, the masses Q ~ kT): a schedule
    // changes it between steps at a fixed state by a known jump, taken out of the conserved
    // quantity, so that it stays constant up to the method's error while the schedule moves.
    // (Langevin's and CSVR's offset is -heat, which no kT enters; the jump is then exactly 0.)
    const double before = t.kind() == sesi::ThermostatKind::nose_hoover ? t.conserved_offset() : 0.0;
    t.set_temperature(kT);
    if (t.kind() == sesi::ThermostatKind::nose_hoover) schedule_jumps_ += t.conserved_offset() - before;
  }
  std::vector<double> thermostat_state() const override { return with_thermostat(FramedState{}).thermostat; }
  void set_thermostat_state(const std::vector<double>& saved) override { load_thermostat(saved, true); }
  std::uint64_t thermostat_step() const override { return thermostat_ ? thermostat_->thermostat().step() : 0; }
  void set_thermostat_step(std::uint64_t k) override {
    if (thermostat_) thermostat_->thermostat().set_step(k);
  }
  double heat() const override { return thermostat_ ? thermostat_->thermostat().heat() : 0.0; }
  double conserved_offset() const override {
    return thermostat_ ? thermostat_->thermostat().conserved_offset() - schedule_jumps_ : 0.0;
  }
  double kinetic_temperature() override {
    // N_f = N n: every chart momentum is a degree of freedom (no constraint removes one).
    const double dof = static_cast<double>(whole_bodies_ > 0 ? whole_bodies_ : sys_.bodies()) *
                       static_cast<double>(sys_.dim());
    return 2.0 * sys_.kinetic_energy(shown()) / dof;
  }
  std::array<double, 2> configurational_sums() override {
    const auto sums = sesi::configurational_sums(sys_, shown());
    return {static_cast<double>(sums[0]), static_cast<double>(sums[1])};
  }

  int first_non_finite_body() const override {
    // After every step: on threads, each chunk stopping at its first bad body; the least wins.
    const int n = x_.bodies();
    std::atomic<int> first{n};
    sesi::parallel::for_chunks(n, sesi::parallel::chunks_for(n), [&](int begin, int end, int) {
      for (int b = begin; b < end && b < first.load(std::memory_order_relaxed); ++b) {
        if (x_.q.col(b).allFinite() && x_.p.col(b).allFinite()) continue;
        int seen = first.load(std::memory_order_relaxed);
        while (b < seen && !first.compare_exchange_weak(seen, b, std::memory_order_relaxed)) {
        }
        return;
      }
    });
    return first.load() < n ? first.load() + 1 : 0;
  }
  double energy() override { return sys_.energy(shown(), w_); }
  Eigen::VectorXd momentum_map() override { return sesi::momentum_map(sys_, shown()); }
  Eigen::MatrixXd points() override { return sesi::embedding_points(sys_, shown()); }
  // (A cluster frame at the identity, as every H^n scene near the origin has, changes nothing.)
  bool clustered() const override { return x_.clustered && !x_.cluster.isIdentity(0.0); }
  Eigen::MatrixXd local_points() override {
    sys_.embed_all(shown(), w_);
    return w_.X;
  }
  bool listed_close_pairs(double reach, std::vector<std::pair<int, int>>& out) override {
    if constexpr (surface) return false;  // (partners are images there: the caller's search)
    const sesi::NeighbourLists* lists = sys_.neighbour_lists(w_, reach);
    if (!lists) return false;
    // The chord of reach bounds the pairs, as the neighbour index measures them (a chord is
    // monotone in the distance); w_.X holds the points energy() saw.
    const double chord = sys_.chart().chord_of_distance(reach);
    // Rows in chunks on threads, each into its own buffer, joined in chunk order: the pairs in
    // ascending (i, j) whatever the thread count.
    const int n = lists->bodies();
    const int chunks = sesi::parallel::chunks_for(n);
    close_.resize(static_cast<std::size_t>(chunks));
    sesi::parallel::for_chunks(n, chunks, [&](int begin, int end, int c) {
      std::vector<std::pair<int, int>>& found = close_[static_cast<std::size_t>(c)];
      found.clear();
      typename sesi::detail::ImageVector<Chart>::type y(w_.X.rows());
      for (int i = begin; i < end; ++i) {
        for (int e = lists->begin(i); e < lists->end(i); ++e) {
          const int j = lists->index[static_cast<std::size_t>(e)];
          if (j <= i) continue;
          if (sesi::NeighbourIndex<Chart>::chord2_of(sys_.chart(), w_.X, i, j, y) < chord * chord) {
            found.emplace_back(i, j);
          }
        }
      }
    });
    out.clear();
    for (const auto& found : close_) out.insert(out.end(), found.begin(), found.end());
    return true;
  }
  Eigen::VectorXd to_local(const Eigen::VectorXd& world) const override {
    if constexpr (sesi::ClusterChart<Chart>) {
      if (clustered()) {
        typename Chart::Ambient c = world, out;
        sys_.chart().to_frame(x_.cluster, c, out);
        return out;
      }
    }
    return world;
  }
  Eigen::MatrixXd velocities() override { return sesi::embedding_velocities(sys_, shown()); }
  Eigen::Matrix<std::int64_t, Eigen::Dynamic, Eigen::Dynamic> image_counts() const override {
    if constexpr (topology && !surface) return images_;
    return {};
  }
  std::vector<std::vector<std::int16_t>> words() const override {
    if constexpr (surface) return {images_.begin(), images_.end()};
    return {};
  }
  void set_words(std::vector<std::vector<std::int16_t>> words) override {
    if constexpr (surface) {
      if (words.size() != images_.size()) throw std::logic_error("set_words: not one word per body");
      images_ = std::move(words);
    }
  }
  /// x_b + L .* n_b on a box (exact in the counts), W_b x_b on a surface (Sausset & Tarjus 2007:
  /// the group element that took the body back, applied to its point in the domain).
  Eigen::MatrixXd unwrapped_points() override {
    Eigen::MatrixXd x = points();
    if constexpr (surface) {
      const auto& topo = sys_.chart().topology();
      for (Eigen::Index b = 0; b < x.cols(); ++b) {
        const auto& word = images_[static_cast<std::size_t>(b)];
        if (!word.empty()) x.col(b) = topo.element(word) * x.col(b);
      }
    } else if constexpr (topology) {
      const auto& L = sys_.chart().topology().edges();
      for (Eigen::Index b = 0; b < x.cols(); ++b) {
        for (Eigen::Index k = 0; k < x.rows(); ++k) x(k, b) += L[k] * static_cast<double>(images_(k, b));
      }
    }
    return x;
  }
  int body_with_non_finite_energy() override {
    const sesi::State<Chart>& x = shown();
    typename Chart::Point q(sys_.dim()), p(sys_.dim());
    int bad = 0;
    for (int b = 0; b < sys_.bodies() && bad == 0; ++b) {
      q = x.q.col(b);
      p = x.p.col(b);
      if (!std::isfinite(sesi::kinetic_energy(sys_.chart(), q, p, sys_.mass(b)))) bad = b + 1;
    }
    // (A domain's gradient with pair terms without a cutoff gathers from every process: each
    // evaluates it, whatever its own bodies are.)
    if (bad != 0 && !whole_run_) return bad;
    typename SystemOf<Chart>::StateType::Matrix gradient;
    sys_.potential_gradient(x, w_, gradient);
    if (bad != 0) return bad;
    for (int b = 0; b < sys_.bodies(); ++b) {
      if (!gradient.col(b).allFinite()) return b + 1;
    }
    return 0;
  }
  /// A processed method's state is the kernel's variables for the scene's step, before the first
  /// step the state itself (a state entered with another step, after a shortened last step or a
  /// change of dt, is moved to the scene's step on a copy): restore takes them up again as such.
  FramedState framed_state() const override {
    sesi::State<Chart> moved;
    const bool rebase = stepper_->processed() && stepper_->entered_step() != 0.0 && stepper_->entered_step() != dt_;
    if (rebase) stepper_->reentered(x_, dt_, moved);
    return with_thermostat(framed(rebase ? moved : x_));
  }
  void restore(const FramedState& state) override {
    take(state, true);
    // (The initial state, e.g. another method's before its first step, is the state itself.)
    if (stepper_->processed()) stepper_->assume_entered(dt_ == 0.0 || same_state(x_, initial_) ? 0.0 : dt_);
  }
  FramedState shown_state() const override { return with_thermostat(framed(shown())); }
  void start_from(const FramedState& state) override {
    take(state, false);
    if (stepper_->processed()) {
      initial_ = x_;  // the state itself until the first step (restore and framed_state)
      stepper_->assume_entered(0.0);
    }
  }
  void set_domain(DomainHooks hooks) override {
    if (stepper_->processed() || !stepper_->workspace()) {
      throw std::logic_error("a domain of a run across processes needs a plain chart method");
    }
    if (thermostat_) {
      thermostat_->thermostat().set_body_keys(std::vector<std::uint64_t>(hooks.ids.begin(), hooks.ids.end()));
    }
    whole_bodies_ = hooks.bodies;
    any_ = std::move(hooks.any);
    halo_ = std::move(hooks.halo);
    own_.clear();
    for (int b = 0, h = 0; b < sys_.bodies(); ++b) {
      if (h < static_cast<int>(halo_.size()) && halo_[static_cast<std::size_t>(h)] == b) {
        ++h;
      } else {
        own_.push_back(b);
      }
    }
    whole_run_ = hooks.gather && sys_.whole_run_terms();
    if (whole_run_) {
      // Pair terms without a cutoff: each own body pairs with every body of the whole run, whose
      // masses come once and whose points come at every evaluation (a collective call).
      std::vector<double> masses(static_cast<std::size_t>(whole_bodies_));
      hooks.gather(sys_.masses().data(), 1, masses.data());
      sys_.set_whole_run(hooks.ids, own_, std::move(masses), hooks.gather);
      own_frames_.resize(own_.size());
    }
    auto refresh = std::move(hooks.drifted);
    sys_.set_domain(std::move(hooks.sum), [this, refresh](sesi::State<Chart>& x, typename SystemOf<Chart>::Workspace& w) {
      refresh(x.q.data(), static_cast<int>(x.q.rows()), static_cast<int>(x.q.cols()));
      sys_.refresh_bodies(x, w, halo_);  // their trig, which the level flows kept for the old q
    });
  }
  int packed_size() const override {
    const int a = sys_.ambient_dim();
    return 2 * sys_.dim() + a * a + (topology && !surface ? sys_.dim() : 0);
  }
  void pack(const std::vector<int>& bodies, std::vector<double>& out) const override {
    const int d = sys_.dim(), a = sys_.ambient_dim();
    for (const int b : bodies) {
      for (int i = 0; i < d; ++i) out.push_back(x_.q(i, b));
      for (int i = 0; i < d; ++i) out.push_back(x_.p(i, b));
      for (int c = 0; c < a; ++c) {
        for (int r = 0; r < a; ++r) {
          out.push_back(x_.framed() ? x_.frames[static_cast<std::size_t>(b)](r, c) : (r == c ? 1.0 : 0.0));
        }
      }
      if constexpr (topology && !surface) {
        for (int i = 0; i < d; ++i) out.push_back(static_cast<double>(images_(i, b)));  // (exact below 2^53)
      }
    }
  }
  void unpack(const std::vector<int>& bodies, const double* in) override {
    const int d = sys_.dim(), a = sys_.ambient_dim();
    for (const int b : bodies) {
      for (int i = 0; i < d; ++i) x_.q(i, b) = *in++;
      for (int i = 0; i < d; ++i) x_.p(i, b) = *in++;
      const Eigen::Map<const Eigen::MatrixXd> frame(in, a, a);
      in += a * a;
      if constexpr (topology && !surface) {
        for (int i = 0; i < d; ++i) images_(i, b) = static_cast<std::int64_t>(*in++);
      }
      if (!x_.framed()) {
        if (frame.isIdentity(0.0)) continue;
        x_.enable_frames(a);
      }
      x_.frames[static_cast<std::size_t>(b)] = frame;
    }
    shown_valid_ = false;
  }
  Eigen::MatrixXd cluster() const override {
    if (!x_.clustered) return {};
    return x_.cluster;
  }
  void set_cluster(const Eigen::MatrixXd& c) override {
    if constexpr (sesi::ClusterChart<Chart>) {
      x_.clustered = c.size() != 0;
      if (x_.clustered) x_.cluster = c;
      shown_valid_ = false;
    }
  }
  void frame_points(Eigen::MatrixXd& X, Eigen::MatrixXd& V) override {
    if (!x_.clustered) {
      X = points();
      V = velocities();
      return;
    }
    sesi::State<Chart> local = shown();
    local.clustered = false;
    X = sesi::embedding_points(sys_, local);
    V = sesi::embedding_velocities(sys_, local);
  }
  Eigen::VectorXd momentum_in_world(const Eigen::VectorXd& m) const override {
    if (!shown().clustered) return m;
    return sesi::momentum_map_in_world<double>(m, shown().cluster);
  }
  void kicked_points(const std::vector<int>& bodies, Eigen::MatrixXd& out) override {
    const auto* w = stepper_->workspace();
    out.resize(sys_.ambient_dim(), static_cast<Eigen::Index>(bodies.size()));
    if (w && w->X.cols() == x_.bodies()) {
      for (std::size_t k = 0; k < bodies.size(); ++k) out.col(static_cast<Eigen::Index>(k)) = w->X.col(bodies[k]);
      return;
    }
    sys_.embed_all(x_, w_);  // before the first force evaluation
    const Eigen::MatrixXd all = w_.X;
    for (std::size_t k = 0; k < bodies.size(); ++k) out.col(static_cast<Eigen::Index>(k)) = all.col(bodies[k]);
  }
  /// In the scene's own chart: bodies re-charted by the stepper are mapped back (q and p of
  /// the outputs and of summary.json always mean the same coordinates).
  void read(Eigen::MatrixXd& q, Eigen::MatrixXd& p) const override {
    const sesi::State<Chart>& x = shown();
    if (x.framed() || x.clustered) {
      const auto world = sesi::in_world_chart(sys_, x);
      q = world.q;
      p = world.p;
    } else {
      q = x.q;
      p = x.p;
    }
  }

 private:
  /// The stepper of scene's method, or the thermostatted one (thermostat_ then points to it).
  std::unique_ptr<AnyStepper<SystemOf<Chart>>> make_chart_stepper(const Scene& scene) {
    if (!scene.thermostat) return make_stepper(scene.integrator.method, sys_);
    // The scene checks allow a thermostat with sesi2 only (the stage runs with Strang's table).
    if (scene.integrator.method != "sesi2") {
      throw std::logic_error("a thermostat with method '" + scene.integrator.method + "' (sesi2 only)");
    }
    auto stepper = std::make_unique<ThermostatStepper<SystemOf<Chart>>>(sys_, *scene.thermostat);
    thermostat_ = stepper.get();
    return stepper;
  }
  /// out with the thermostat's saved state (Thermostat::save) when one acts.
  FramedState with_thermostat(FramedState out) const {
    if (thermostat_) {
      out.thermostat = thermostat_->thermostat().save();
      out.thermostat.push_back(schedule_jumps_);  // last: the integrator's own (set_temperature)
    }
    return out;
  }
  /// The state the outputs and diagnostics see: x_, or for a processed method the state its
  /// kernel's variables stand for (post-processed on a copy once per state, kept until the next
  /// step or restore).
  const sesi::State<Chart>& shown() const {
    if (!stepper_->processed()) return x_;
    if (!shown_valid_) {
      stepper_->output(x_, shown_);
      shown_valid_ = true;
    }
    return shown_;
  }
  /// x as a FramedState, with the topology's image record (images_: a topology's integrator
  /// runs no processed method, so x is x_).
  FramedState framed(const sesi::State<Chart>& x) const {
    FramedState out;
    out.q = x.q;
    out.p = x.p;
    out.clustered = x.clustered;
    out.frames.assign(x.frames.begin(), x.frames.end());
    if (x.clustered) out.cluster = x.cluster;
    out.image_counts = image_counts();
    out.words = words();
    return out;
  }
  /// x_ <- state, a chart method's state of this scene's size (anything else is a caller's
  /// mistake, never reinterpreted: std::logic_error), and the thermostat's (strict: a
  /// checkpoint's, which must fit; Thermostat::load checks).
  void take(const FramedState& state, bool strict) {
    if (state.embedded) {
      throw std::logic_error("a chart method's integrator was given a geodesic method's state (x, v) to restore");
    }
    const auto sized = [&](const Eigen::MatrixXd& m) { return m.rows() == x_.q.rows() && m.cols() == x_.q.cols(); };
    const auto square = [&](const Eigen::MatrixXd& m) {
      return m.rows() == sys_.ambient_dim() && m.cols() == sys_.ambient_dim();
    };
    bool fits = sized(state.q) && sized(state.p) &&
                (state.frames.empty() || state.frames.size() == static_cast<std::size_t>(x_.bodies())) &&
                (!state.clustered || square(state.cluster));
    for (const Eigen::MatrixXd& f : state.frames) fits = fits && square(f);
    if constexpr (!sesi::ClusterChart<Chart>) fits = fits && !state.clustered;
    // The image record: of this topology's kind and size, or none (the images start at the identity).
    const std::size_t bodies = static_cast<std::size_t>(x_.bodies());
    if constexpr (surface) {
      fits = fits && state.image_counts.size() == 0 && (state.words.empty() || state.words.size() == bodies);
    } else if constexpr (topology) {
      fits = fits && state.words.empty() &&
             (state.image_counts.size() == 0 ||
              (state.image_counts.rows() == x_.q.rows() && state.image_counts.cols() == x_.q.cols()));
    } else {
      fits = fits && state.image_counts.size() == 0 && state.words.empty();
    }
    if (!fits) throw std::logic_error("the chart state to restore has the wrong size");
    x_.q = state.q;
    x_.p = state.p;
    x_.frames.assign(state.frames.begin(), state.frames.end());
    x_.clustered = state.clustered;
    if (state.clustered) x_.cluster = state.cluster;
    if constexpr (surface) {
      images_ = state.words.empty() ? sys_.chart().topology().identity_images(x_.bodies())
                                    : typename ImagesOf<Chart>::type(state.words.begin(), state.words.end());
    } else if constexpr (topology) {
      if (state.image_counts.size() == 0) {
        images_ = sys_.chart().topology().identity_images(x_.bodies());
      } else {
        images_ = state.image_counts;
      }
    }
    // A state without a thermostat's (an NVE run's) leaves this thermostat as it is: at its start.
    // Another integrator's (start_from: Python's sim.thermostat or sim.method changed) goes on
    // only if it is of the same shape (a chain's variables are not another kind's).
    load_thermostat(state.thermostat, strict);
    shown_valid_ = false;
  }
  /// After a step: a topology's bodies back into its domain (sesi::wrap). A domain wraps when
  /// any body of the whole simulation is out by more than the margin, as one process does (then
  /// every body out by any amount, the halo's alike with its owners': the same points, so the
  /// same isometries and, on a surface, the same words).
  /// Whether a domain's bodies were wrapped (false for one process: nothing asks).
  bool wrap() {
    if constexpr (topology) {
      if (any_) {
        if (!any_(sys_.chart().topology().out_by_more(sys_.chart(), x_, margin_))) return false;
        sesi::wrap(sys_, x_, images_, -1.0);
        return true;
      }
      sesi::wrap(sys_, x_, images_, margin_);
    }
    return false;
  }
  /// with_thermostat's record into the thermostat (none: it stays as it is); not strict, only
  /// one of the same shape.
  void load_thermostat(const std::vector<double>& state, bool strict) {
    if (thermostat_ && !state.empty() && (strict || state.size() == thermostat_->thermostat().save().size() + 1)) {
      std::vector<double> saved = state;
      schedule_jumps_ = saved.back();
      saved.pop_back();
      thermostat_->thermostat().load(saved);
    }
  }
  static bool same_state(const sesi::State<Chart>& a, const sesi::State<Chart>& b) {
    const auto same = [](const auto& u, const auto& v) {
      return u.rows() == v.rows() && u.cols() == v.cols() && u == v;
    };
    if (!same(a.q, b.q) || !same(a.p, b.p) || a.frames.size() != b.frames.size() || a.clustered != b.clustered) {
      return false;
    }
    for (std::size_t i = 0; i < a.frames.size(); ++i) {
      if (!same(a.frames[i], b.frames[i])) return false;
    }
    return !a.clustered || same(a.cluster, b.cluster);
  }

  /// H^n: the bodies go into a cluster frame (docs/charts.md) at the scene's first force centre,
  /// or else at the bodies' centre; at the origin it is the identity (nothing changes until
  /// the cluster drifts 2 R away and re-centres). Far out, each body is re-read from its world
  /// point and velocity without cancellation, so pair chords and central terms are O(1).
  void enter_cluster_frame(const Scene& scene) {
    const sesi::RechartPolicy<double> policy{};
    for (const PotentialSpec& spec : scene.potentials) {
      if (const auto* central = std::get_if<CentralCotangentSpec>(&spec)) {
        const typename Chart::Ambient c = central->center;
        sesi::enter_cluster_frame(sys_, x_, policy, &c);
        return;
      }
    }
    sesi::enter_cluster_frame(sys_, x_, policy);
  }

  SystemOf<Chart> sys_;
  sesi::State<Chart> x_;
  // A topology: each body's image record (sesi::wrap) and the wrap's margin (wrap_margin).
  typename ImagesOf<Chart>::type images_{};
  double margin_ = 0.0;
  ThermostatStepper<SystemOf<Chart>>* thermostat_ = nullptr;  // stepper_, if thermostatted
  double schedule_jumps_ = 0.0;  // Nose-Hoover: the extended energy's jumps at kT changes (set_temperature)
  std::unique_ptr<AnyStepper<SystemOf<Chart>>> stepper_;  // refers to sys_
  typename SystemOf<Chart>::Workspace w_ = sys_.make_workspace();  // the diagnostics' own
  std::vector<std::vector<std::pair<int, int>>> close_;  // listed_close_pairs' buffers, per chunk
  std::vector<int> halo_;  // a domain's halo (set_domain)
  std::vector<int> own_;   // a domain's own bodies (set_domain)
  // A domain with pair terms without a cutoff (System::set_whole_run), and its own bodies'
  // frames before a step (step: whether one was re-charted).
  bool whole_run_ = false;
  std::vector<typename sesi::State<Chart>::Frame> own_frames_;
  int whole_bodies_ = 0;   // a domain's whole simulation's body count (set_domain; 0: none)
  std::function<bool(bool)> any_;  // a domain's "on any process" (set_domain)
  // Processed methods (AnyStepper::processed): the step of the kernel's variables in
  // framed_state (the scene's), the initial state, and the post-processed state (shown()).
  double dt_ = 0.0;
  sesi::State<Chart> initial_;
  mutable sesi::State<Chart> shown_;
  mutable bool shown_valid_ = false;
};

/// The integrator on Space<N> for the N in Dims (dispatch.hpp's FixedDims) equal to scene.dim(),
/// or nullptr.
template <template <int, class> class Space, int... Dims>
std::unique_ptr<Integrator> integrator_for(const Scene& scene, std::integer_sequence<int, Dims...>) {
  std::unique_ptr<Integrator> out;
  const auto try_dim = [&]<int N>() {
    if (scene.dim() != N) return false;
    out = std::make_unique<ChartIntegrator<Space<N, double>>>(scene);
    return true;
  };
  static_cast<void>((try_dim.template operator()<Dims>() || ...));
  return out;
}

}  // namespace sesi::program
