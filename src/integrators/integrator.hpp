#pragma once
/// @file integrator.hpp
/// A scene's state with its system and stepper, behind virtual calls: all that the run loop
/// (run_loop.cpp, compiled once) needs from the compile-time world. make_integrator dispatches
/// the scene's runtime space and dimension to a compile-time chart (dispatch.cpp).

#include <array>
#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <stdexcept>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "scene.hpp"

namespace sesi::program {

struct Snapshot;  // run_types.hpp

/// What is stepped, exactly as the integrator holds it. This, not a conversion, is what a
/// checkpoint saves and a resumed run restores. Two kinds:
///  - a chart method's (embedded = false): chart coordinates and momenta q, p of every body in
///    its own chart frame, and the frames (empty: every body in the scene's chart);
///  - a geodesic method's (embedded = true; EmbeddedIntegrator): the embedding points x and
///    velocities v in world coordinates; q, p, frames and cluster are empty.
struct FramedState {
  Eigen::MatrixXd q, p;                ///< dim x bodies
  std::vector<Eigen::MatrixXd> frames;  ///< one ambient x ambient isometry per body, or none
  bool clustered = false;               ///< H^n: the bodies' frames are relative to `cluster`
  Eigen::MatrixXd cluster;              ///< the cluster frame (sesi::State::cluster), if clustered
  bool embedded = false;                ///< a geodesic method's state: x and v below
  Eigen::MatrixXd x, v;                 ///< ambient x bodies, if embedded
  /// A thermostatted run's thermostat (sesi::Thermostat::save(): its step counter, heat, chain
  /// variables; then the integrator's sum of Nose-Hoover's jumps at schedule changes), else
  /// empty. Nothing random: the noise is keyed by the seed and the step.
  std::vector<double> thermostat;
  /// A topology's image record (sesi::wrap; api of include/sesi/topology.hpp), else empty: on a
  /// periodic box the integer image counts (dim x bodies; unwrapped x_b + L .* n_b), on a compact
  /// surface each body's group word W_b (letters: side indices 0..4g-1; unwrapped W_b x_b).
  Eigen::Matrix<std::int64_t, Eigen::Dynamic, Eigen::Dynamic> image_counts;
  std::vector<std::vector<std::int16_t>> words;
};

/// What a domain of one simulation across processes (src/domain/domain_integrator.hpp) sets in
/// the integrator of its bodies: the halo (bodies stepped by other processes, copied here) and
/// how it is refreshed after every drift, and how a sum over bodies is taken (System::set_domain).
struct DomainHooks {
  std::vector<int> halo;  ///< the halo's bodies (indices into this integrator's bodies, ascending)
  /// After every drift: q's halo columns (q: dim x bodies, column-major) overwritten by their owners'.
  std::function<void(double* q, int dim, int bodies)> drifted;
  /// A sum over bodies of one value a body (rows), the whole simulation's, in its body order.
  std::function<double(const std::vector<double>&)> sum;
  /// Each body's index in the whole simulation (a thermostat's noise key), and its body count.
  std::vector<int> ids;
  int bodies = 0;
  /// Whether value holds on any process (a periodic box's wrap is the whole simulation's call).
  std::function<bool(bool)> any;
  /// The own bodies' columns of local (rows x bodies, column-major; the halo's ignored) from
  /// every process into whole (rows x the whole simulation's bodies, in its body order), on
  /// every process: pair terms without a cutoff see every body (System::set_whole_run).
  std::function<void(const double* local, int rows, double* whole)> gather;
};

class Integrator {
 public:
  virtual ~Integrator() = default;
  /// Advance the state from t by h (h may be negative).
  virtual void step(double t, double h) = 0;
  /// The current chart coordinates and momenta (dim x bodies), in the scene's chart.
  virtual void read(Eigen::MatrixXd& q, Eigen::MatrixXd& p) const = 0;

  // Diagnostics of the current state, computed on the state as it is stepped: each body in its
  // own chart frame, never through the scene's chart (whose coordinates of a body far out on H^n
  // would cancel terms of size e^{2r}). Threads as the forces; the same result for any count.

  /// The first body (1-based) whose coordinates or momenta are not finite, or 0.
  virtual int first_non_finite_body() const = 0;
  virtual double energy() = 0;
  virtual Eigen::VectorXd momentum_map() = 0;
  /// Embedding points and velocities in world coordinates (ambient x bodies).
  virtual Eigen::MatrixXd points() = 0;
  virtual Eigen::MatrixXd velocities() = 0;
  /// H^n: whether the bodies are held in a cluster frame (sesi::State::cluster). The points the
  /// potentials see are then local_points(), O(1) for a compact cluster however far out (the
  /// close-encounter check measures those), and to_local moves a world point (a force centre)
  /// into the same frame. Without a cluster frame both are the world's.
  virtual bool clustered() const = 0;
  virtual Eigen::MatrixXd local_points() = 0;
  virtual Eigen::VectorXd to_local(const Eigen::VectorXd& world) const = 0;
  /// The pairs (i < j, 0-based) of the state energy() last saw that are closer than reach,
  /// from the neighbour lists the forces already keep (a short-range term of range >= reach),
  /// into out; false, with out untouched, where there are none (the caller then searches).
  virtual bool listed_close_pairs(double reach, std::vector<std::pair<int, int>>& out) {
    static_cast<void>(reach);
    static_cast<void>(out);
    return false;
  }
  /// The points (as local_points() where `local`, else points()) of bodies (0-based, ascending),
  /// a column each. Across ranks a collective call: rank 0's bodies, gathered on rank 0 from
  /// their owners (the other ranks get none), so no rank holds every body's point.
  virtual Eigen::MatrixXd points_of(const std::vector<int>& bodies, bool local) {
    if (bodies.empty()) return {};
    const Eigen::MatrixXd all = local ? local_points() : points();
    return all(Eigen::all, bodies);
  }
  /// Across ranks: this rank's own bodies' columns of the state the outputs see into s (q and p
  /// as read() gives them, x, v and a box's image counts), with Snapshot::ids and gather set;
  /// false, s untouched, for an integrator of the whole run (the caller reads that whole).
  virtual bool own_state(Snapshot& s) {
    static_cast<void>(s);
    return false;
  }
  /// The state as stepped, and its restoration (a checkpoint's; the run goes on bit for bit as
  /// if it had not stopped: the stepper's caches are recomputed from it alike). restore takes a
  /// state of its own kind only (FramedState::embedded; make_integrator(scene, from) converts).
  virtual FramedState framed_state() const = 0;

  // A domain of a simulation across processes (DomainHooks). Only a chart method's integrator
  // without a thermostat or a processed method has them (the defaults refuse).

  /// Install the domain's hooks (before the first step).
  virtual void set_domain(DomainHooks hooks) {
    static_cast<void>(hooks);
    throw std::logic_error("this integrator cannot be a domain of a run across processes");
  }
  /// Doubles per body in pack(): q (dim), p (dim), the frame (ambient x ambient, column-major;
  /// the identity where the state has no frames).
  virtual int packed_size() const { return 0; }
  /// Append the packed state of bodies (in that order) to out.
  virtual void pack(const std::vector<int>& bodies, std::vector<double>& out) const {
    static_cast<void>(bodies);
    static_cast<void>(out);
  }
  /// Set bodies' state from packed data (packed_size() doubles each, in bodies' order).
  virtual void unpack(const std::vector<int>& bodies, const double* in) {
    static_cast<void>(bodies);
    static_cast<void>(in);
  }
  /// H^n: the cluster frame (sesi::State::cluster) when the bodies are held in one (a domain's
  /// ranks share it), else an empty matrix; set_cluster puts the bodies in the given one (their
  /// frames and coordinates are then relative to it).
  virtual Eigen::MatrixXd cluster() const { return {}; }
  virtual void set_cluster(const Eigen::MatrixXd& c) { static_cast<void>(c); }
  /// The bodies' points and velocities in the frame the momentum map is summed in: a cluster
  /// frame's (before C; sesi::momentum_map), else the world's (points(), velocities()).
  virtual void frame_points(Eigen::MatrixXd& X, Eigen::MatrixXd& V) {
    X = points();
    V = velocities();
  }
  /// A momentum map summed in that frame (sesi::momentum_map_of), in world coordinates.
  virtual Eigen::VectorXd momentum_in_world(const Eigen::VectorXd& m) const { return m; }
  /// Points of bodies at the last force evaluation (ambient x bodies.size()), in the frame the
  /// forces see them in (the cluster's on H^n, local_points(), else the world's): a domain's
  /// moves are measured against them.
  virtual void kicked_points(const std::vector<int>& bodies, Eigen::MatrixXd& out) {
    static_cast<void>(bodies);
    out.resize(0, 0);
  }
  virtual void restore(const FramedState& state) = 0;
  /// The state the outputs see, of the integrator's kind: framed_state() for a plain method, the
  /// post-processed state for a processed one (whose framed_state() is its kernel's variables).
  virtual FramedState shown_state() const = 0;
  /// Go on from state (of its own kind) taken as the state itself, as a new initial state: a
  /// processed method enters its kernel's variables at its next step. Another method's
  /// shown_state() starts this one where that one stood (make_integrator(scene, from)).
  virtual void start_from(const FramedState& state) = 0;
  /// With a non-finite energy: the first body (1-based) whose kinetic energy or potential
  /// gradient is not finite, or 0.
  virtual int body_with_non_finite_energy() = 0;

  // A space with a topology (SpaceSpec::has_topology): points() and read() give the bodies in the
  // domain; these give where they went in the covering space. The defaults are a space's without one.

  /// Periodic box: each body's integer image counts (dim x bodies); empty without a box.
  virtual Eigen::Matrix<std::int64_t, Eigen::Dynamic, Eigen::Dynamic> image_counts() const { return {}; }
  /// Compact surface: each body's group word W_b (letters 0..4g-1, freely reduced); empty without one.
  virtual std::vector<std::vector<std::int16_t>> words() const { return {}; }
  /// Compact surface: every body's word at once (one a body, as words() gives them), e.g. a
  /// domain's bodies' after a cut (pack() carries no words: a halo's are its owner's already).
  virtual void set_words(std::vector<std::vector<std::int16_t>> words) { static_cast<void>(words); }
  /// World points in the universal cover (ambient x bodies): x_b + L .* n_b on a box, W_b x_b on a
  /// surface, points() without a topology.
  virtual Eigen::MatrixXd unwrapped_points() { return points(); }

  // A thermostatted run (Scene::thermostat; sesi::Thermostat, include/sesi/thermostat.hpp). The
  // defaults are a constant-energy integrator's: no thermostat, nothing to set, no heat.

  /// Whether a thermostat acts (only a chart method's integrator has one: the scene checks
  /// refuse a thermostat with a geodesic method).
  virtual bool thermostatted() const { return false; }
  /// The thermostat's target kT from the next step on.
  virtual void set_temperature(double kT) { static_cast<void>(kT); }
  /// The thermostat's own state (sesi::Thermostat::save and the integrator's), for another
  /// integrator of the same scene to go on with (a domain's after a cut); empty without one.
  virtual std::vector<double> thermostat_state() const { return {}; }
  virtual void set_thermostat_state(const std::vector<double>& saved) { static_cast<void>(saved); }
  /// The noise's step key: the steps done since the run's start.
  virtual std::uint64_t thermostat_step() const { return 0; }
  virtual void set_thermostat_step(std::uint64_t k) { static_cast<void>(k); }
  /// The energy the thermostat put into the system so far.
  virtual double heat() const { return 0.0; }
  /// energy() + conserved_offset() is conserved up to the method's error (sesi::Thermostat::
  /// conserved_offset; NaN for brownian, which conserves nothing).
  virtual double conserved_offset() const { return 0.0; }
  /// 2 K / N_f with N_f = bodies x dim (k_B = 1).
  virtual double kinetic_temperature() { return std::numeric_limits<double>::quiet_NaN(); }
  /// {sum_b |grad_b V|^2, sum_b Laplace-Beltrami_b V} (sesi::configurational_sums): their ratio is
  /// the configurational temperature (Rugh 1997); NaN where a term has no Laplacian.
  virtual std::array<double, 2> configurational_sums() {
    return {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::quiet_NaN()};
  }
};

/// How far a body may leave the domain before the bodies are reduced into it (sesi::wrap's
/// margin): a quarter of the longest cutoff of the scene's short-range terms, or of the
/// topology's largest allowed cutoff without any. Rare reductions keep the kept gradient and
/// the Verlet lists valid between them; the neighbour structures allow for the slack.
double wrap_margin(const Scene& scene, double max_cutoff);
/// The longest cutoff of the scene's short-range pair terms (Lennard-Jones), 0 without one.
double short_range_cutoff(const Scene& scene);

/// The integrator of scene (its space, dimension, bodies, potentials and method), at the
/// scene's initial state: a ChartIntegrator (chart_integrator.hpp) for the sesi methods, an
/// EmbeddedIntegrator (embedded_integrator.hpp) for the geodesic methods (S^n and H^n only: on
/// E^n they are refused with an InputError naming the method and the space).
std::unique_ptr<Integrator> make_integrator(const Scene& scene);

/// The integrator of scene's method at the current state of `from`, an integrator of the same
/// scene with maybe another method (sesi.Simulation.method), started from the state from's
/// outputs show (never a processed method's kernel's variables, which another method or step
/// would take for the state): from's shown_state() when both hold the same kind, else from's
/// state read in the scene's chart (read()), as the initial state.
std::unique_ptr<Integrator> make_integrator(const Scene& scene, const Integrator& from);

}  // namespace sesi::program
