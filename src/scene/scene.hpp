#pragma once
/// @file scene.hpp
/// A scene at run time: what a scene file (docs/scene-format.md) or the embedded default holds,
/// validated and with every body's initial condition in chart coordinates (q, p).

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <variant>
#include <vector>

#include <Eigen/Core>

#include <sesi/neighbours.hpp>  // default_skin_fraction

namespace sesi::program {

enum class SpaceKind { sphere, hyperbolic, euclidean };

/// "sphere", "hyperbolic", "euclidean".
std::string_view space_name(SpaceKind kind);

/// The space of a scene, with its topology (docs/scene-format.md, [space]; docs/topology.md): the
/// whole S^n, H^n or E^n, or E^n with a periodic box (`box`), or a compact surface H^2/Gamma of
/// genus g (`genus`). Bodies of a topology are kept in its domain (sesi::wrap).
struct SpaceSpec {
  SpaceKind kind = SpaceKind::sphere;
  int dim = 2;
  double radius = 1.0;  ///< 1 (unused) on euclidean
  /// E^n only: the edges L_1..L_n of an orthorhombic periodic box, domain [0, L_k) per axis
  /// (sesi::PeriodicBox); empty: no box.
  std::vector<double> box{};  // ({}: scenes built as {kind, dim, radius} stay warning-free)
  /// H^2 only: the genus g >= 2 of the compact surface (sesi::HyperbolicSurface); 0: the whole H^n.
  int genus = 0;

  /// Whether the space has a topology (a box or a genus).
  bool has_topology() const { return !box.empty() || genus != 0; }
};

struct Body {
  double mass = 1.0;
  Eigen::VectorXd q;  ///< chart coordinates (dim)
  Eigen::VectorXd p;  ///< conjugate momenta (dim)
};

// ---- potential terms (one struct per `kind`, the parameters of docs/scene-format.md) ----
struct ChordWellSpec {
  double theta0;
  double strength;
};
/// min_distance of the singular terms: the close-encounter floor (docs/stability.md); < 0 the
/// library's default (length scale * eps^(1/3)), 0 no check.
struct CotangentGravitySpec {
  double G;
  double min_distance = -1.0;
};
struct CentralCotangentSpec {
  double k;
  Eigen::VectorXd center;  ///< an embedding point
  double min_distance = -1.0;
};
struct HarmonicPairSpec {
  double k;
  double d0;
};
struct LennardJonesSpec {
  double epsilon;
  double sigma;
  double cutoff;
  double min_distance = -1.0;
};
/// An external potential given as code (the Python package's `add_potential(value=f,
/// gradient=g)`, issue #13): V(x, m) on a body's world embedding point x and mass m, and dV/dx.
/// Never read from a scene file; a scene holding one runs on one thread and takes no checkpoints.
struct FunctionExternalSpec {
  class Functions {
   public:
    virtual ~Functions() = default;
    virtual double value(const Eigen::VectorXd& x, double m) const = 0;
    /// g = dV/dx at x (g has x's size on entry).
    virtual void gradient(const Eigen::VectorXd& x, double m, Eigen::VectorXd& g) const = 0;
  };
  /// Shared, so that copies of the scene and of the system's terms copy no callable.
  std::shared_ptr<const Functions> functions;
};
using PotentialSpec = std::variant<ChordWellSpec, CotangentGravitySpec, CentralCotangentSpec,
                                   HarmonicPairSpec, LennardJonesSpec, FunctionExternalSpec>;

/// The `kind` string of a potential.
std::string_view potential_kind(const PotentialSpec& spec);

enum class TrajectoryFormat { csv, h5md };

/// "csv", "h5md".
std::string_view trajectory_format_name(TrajectoryFormat format);

/// One method tried by `method = "auto"` (run/auto_method.cpp): its pilot runs and what it
/// would cost to meet the tolerance.
struct AutoCandidate {
  std::string method;
  double pilot_dt = 0;     ///< the step of its last pilot run (0: none succeeded)
  double pilot_error = 0;  ///< that run's max relative energy error (inf: it failed)
  double dt = 0;           ///< the step predicted to meet the tolerance
  double cost = 0;         ///< predicted cost of the run: steps x stages x stage cost (inf: out)
  bool refined = false;    ///< had a second pilot run at its predicted step
};

/// What `method = "auto"` picked, and why (summary.json's "auto"; kept in checkpoints).
struct AutoChoice {
  double tolerance = 0;            ///< the target max relative energy error
  std::optional<double> given_dt;  ///< a step of the scene or of --dt that the choice replaced
  long given_output_every = 1;
  double pilot_t_end = 0;          ///< length of each pilot run
  long pilot_steps = 0;            ///< steps of all pilot runs together
  double pilot_seconds = 0;        ///< their wall time (the run's own is summary.json's)
  double predicted_error = 0;      ///< of the chosen method and step
  std::vector<AutoCandidate> candidates;
  std::string reason;              ///< one sentence
};

struct IntegratorSpec {
  std::string method = "sesi4";
  /// method = "auto": the target max relative energy error (issue #15); empty otherwise.
  std::optional<double> tolerance;
  /// method = "auto" once resolved (resolve_auto, run/auto_method.hpp): method and dt are then
  /// the chosen ones.
  std::optional<AutoChoice> auto_choice;
  std::optional<double> dt;     ///< required by the time the run starts (file or --dt)
  std::optional<double> t_end;  ///< required by the time the run starts (file or --t-end)
  long output_every = 1;
  /// Threshold of the energy guard on |E - E0| / (K0 + |V0|) (sesi::EnergyGuard); empty: the
  /// library's default; 0: off (`energy_guard = false`).
  std::optional<double> energy_guard;
  /// Threads for forces, flows and diagnostics; 0: all cores (results do not depend on it).
  int threads = 0;
  /// Steps between the energy, momentum, guard and close-encounter checks (output rows are
  /// always checked); 0: the default, default_check_every(body count) (run_loop.cpp).
  long check_every = 0;
  /// Steps between checkpoints (DIR/checkpoint, checkpoint.hpp); 0: none but the one written
  /// when a signal stops the run. Checkpoint steps are checked steps.
  long checkpoint_every = 0;
  /// Skin of the short-range terms' Verlet lists, a fraction of each term's cutoff (0: lists
  /// rebuilt every force evaluation); only the run time depends on it (System::set_neighbour_skin).
  double neighbour_skin = sesi::default_skin_fraction;
  /// Format of the trajectory: csv (trajectory.csv) or h5md (trajectory.h5, H5MD 1.1).
  TrajectoryFormat trajectory_format = TrajectoryFormat::csv;
  int line = 0;  ///< line of [integrator] in the scene file (0: none), for messages
};

/// The thermostat of a scene's `[thermostat]` table (docs/thermostats.md, docs/scene-format.md),
/// run by sesi::Thermostat (include/sesi/thermostat.hpp). Temperatures are in energy units (k_B = 1).
struct ThermostatSpec {
  /// "langevin" (BAOAB), "nose-hoover" (a Nose-Hoover chain), "csvr" (stochastic velocity
  /// rescaling) or "brownian" (overdamped, the BAOAB limit).
  std::string kind;
  /// The temperature as (t, kT) knots, piecewise linear in t and constant before the first knot
  /// and after the last: a constant temperature is one knot (0, kT). Times strictly increasing.
  std::vector<std::pair<double, double>> schedule;
  double gamma = 0;  ///< langevin, brownian: the friction (1/time), > 0
  double tau = 0;    ///< nose-hoover, csvr: the relaxation time, > 0
  int chain = 3;     ///< nose-hoover: the chain length M >= 1
  std::uint64_t seed = 0;  ///< the noise's key (langevin, csvr, brownian)
  int line = 0;      ///< line of [thermostat] in the scene file (0: none), for messages

  /// kT at time t (the schedule, linear between knots).
  double temperature_at(double t) const {
    if (schedule.empty()) return 0.0;
    if (t <= schedule.front().first) return schedule.front().second;
    if (t >= schedule.back().first) return schedule.back().second;
    std::size_t k = 1;
    while (schedule[k].first < t) ++k;
    const auto [t0, T0] = schedule[k - 1];
    const auto [t1, T1] = schedule[k];
    return T0 + (T1 - T0) * ((t - t0) / (t1 - t0));
  }
};

/// Exact solutions the program knows (the scene must match them; scene_reader checks).
enum class ExactSolution { none, paper };

struct Scene {
  std::string name;    ///< output directory name and summary label
  std::string source;  ///< the scene file as given, or "<default scene>"
  SpaceSpec space;
  std::vector<Body> bodies;
  std::vector<PotentialSpec> potentials;
  IntegratorSpec integrator;
  ExactSolution exact = ExactSolution::none;
  std::optional<ThermostatSpec> thermostat;  ///< `[thermostat]`, or none: constant energy (NVE)

  int dim() const { return space.dim; }
  int body_count() const { return static_cast<int>(bodies.size()); }
};

}  // namespace sesi::program
