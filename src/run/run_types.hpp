#pragma once
/// @file run_types.hpp
/// What the run loop hands to the outputs, and how a run ended. Plain dynamic Eigen types, so
/// that everything after the loop is compiled once, not once per (space, dimension).

#include <array>
#include <atomic>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include <sesi/profile.hpp>

namespace sesi::program {

class ProgressBar;
struct Checkpoint;
class BodyGather;

/// The state of all bodies at one time, in chart and embedding coordinates.
struct Snapshot {
  long step = 0;
  double t = 0.0;
  Eigen::MatrixXd q, p;  ///< chart coordinates and momenta, dim x bodies
  Eigen::MatrixXd x, v;  ///< embedding points and velocities, ambient x bodies (v: final only)
  double energy = 0.0;
  Eigen::VectorXd momentum;  ///< the momentum map (sesi::momentum_map)
  /// A thermostatted run's observables (Integrator), else unset: the schedule's target kT at t,
  /// the kinetic temperature 2K / N_f, the configurational sums {sum |grad V|^2, sum Laplacian V}
  /// (their ratio is the configurational temperature), the heat the thermostat put in, and the
  /// conserved quantity energy + Integrator::conserved_offset() (NaN for brownian).
  bool thermostat = false;
  double temperature = 0.0, kinetic_temperature = 0.0, heat = 0.0, conserved = 0.0;
  std::array<double, 2> configurational{};
  double configurational_temperature() const { return configurational[0] / configurational[1]; }
  /// A run on a topology (SpaceSpec::box or genus; x is then the wrapped, in-domain point), else
  /// empty: on an E^n box the image counts n (dim x bodies; the unwrapped point is x + L .* n,
  /// exact in the counts); on an H^2 surface each body's word W_b (letters 0..4g-1, sides of the
  /// polygon; the product of their generators left to right) and the unwrapped point u_b = W_b x_b
  /// in the universal cover (ambient x bodies; Integrator::image_counts, words, unwrapped_points).
  Eigen::Matrix<std::int64_t, Eigen::Dynamic, Eigen::Dynamic> image_counts;
  std::vector<std::vector<std::int16_t>> words;
  Eigen::MatrixXd unwrapped;
  /// Across MPI ranks (Integrator::own_state), else null: q, p, x, v and image_counts hold this
  /// rank's own bodies only, ids their indices in the run (ascending), and rank 0's outputs take
  /// the columns from their owners in blocks of bodies through `gather` (for_each_block), so that
  /// no rank holds every body's columns at once.
  const BodyGather* gather = nullptr;
  std::vector<int> ids;
};

/// Columns first .. first + count - 1 of a Snapshot's body matrices (rows as the snapshot's, 0
/// rows for a field not asked for or not held), in the run's body order.
struct BodyBlock {
  Eigen::Index first = 0, count = 0;
  using Map = Eigen::Map<const Eigen::MatrixXd>;
  using CountMap = Eigen::Map<const Eigen::Matrix<std::int64_t, Eigen::Dynamic, Eigen::Dynamic>>;
  const double *q_data = nullptr, *p_data = nullptr, *x_data = nullptr, *v_data = nullptr;
  const std::int64_t* n_data = nullptr;
  Eigen::Index q_rows = 0, p_rows = 0, x_rows = 0, v_rows = 0, n_rows = 0;
  Map q() const { return Map(q_data, q_rows, count); }
  Map p() const { return Map(p_data, p_rows, count); }
  Map x() const { return Map(x_data, x_rows, count); }
  Map v() const { return Map(v_data, v_rows, count); }
  CountMap image_counts() const { return CountMap(n_data, n_rows, count); }
};

/// The fields a pass over a snapshot's blocks asks for (a bit each).
enum BodyField : unsigned { field_q = 1, field_p = 2, field_x = 4, field_v = 8, field_n = 16 };

/// The columns of a Snapshot spread over MPI ranks (Snapshot::gather; src/domain). Rank 0 asks,
/// the other ranks answer from their own bodies in serve() meanwhile: every rank calls one of
/// them for the same snapshot, as for any collective call.
class BodyGather {
 public:
  virtual ~BodyGather() = default;
  /// Rank 0: the fields of s of bodies [first, first + count) from their owners, into out (per
  /// body in body order: each field asked for, in BodyField's order, its rows).
  virtual void fetch(const Snapshot& s, unsigned fields, Eigen::Index first, Eigen::Index count,
                     std::vector<double>& out) const = 0;
  /// Rank 0: no more fetches of s; the other ranks' serve() returns.
  virtual void done() const = 0;
  /// The other ranks: answer rank 0's fetches of s until its done().
  virtual void serve(const Snapshot& s) const = 0;
  /// The run's body count.
  virtual Eigen::Index bodies() const = 0;
  /// Whether this is rank 0, which writes the outputs; rank 0's value on every rank.
  virtual bool root() const = 0;
  virtual double shared(double value) const = 0;
};

/// Rank 0 of a run across ranks: the other ranks serve s (BodyGather::serve) until this goes,
/// after the passes over s of a row or a summary, or an exception in them. Nothing in one process.
class ServedUntil {
 public:
  explicit ServedUntil(const Snapshot& s) : s_(s) {}
  ~ServedUntil() {
    if (s_.gather) s_.gather->done();
  }
  ServedUntil(const ServedUntil&) = delete;
  ServedUntil& operator=(const ServedUntil&) = delete;

 private:
  const Snapshot& s_;
};

/// f on consecutive blocks of bodies of s in body order, each with the fields asked for: views of
/// s's own matrices in one process; across ranks (rank 0; the others serve) gathered blocks.
void for_each_block(const Snapshot& s, unsigned fields, const std::function<void(const BodyBlock&)>& f);
/// The run's body count of s (across ranks every rank's, not this rank's own).
Eigen::Index body_count(const Snapshot& s);

/// A surface word as the outputs write it (trajectory.csv's b<k>_word, trajectory.h5's
/// particles/all/word): "e" for the identity, else the 1-based side numbers joined by '.'
/// ("3.7.2" is g_2 g_6 g_1 in 0-based letters).
std::string word_text(const std::vector<std::int16_t>& word);
/// The word of such a text (letters 0-based), or none when it is not one (an empty text, a
/// letter that is not a number from 1 to `sides`).
std::optional<std::vector<std::int16_t>> parse_word_text(std::string_view text, int sides);

enum class StopReason { completed, non_finite, invariant_failed, interrupted, energy_guard, close_encounter };

/// How a run ended.
struct RunOutcome {
  StopReason reason = StopReason::completed;
  long steps_done = 0;     ///< the last step known good: the last that passed the run's checks
  long failed_step = 0;    ///< the step where the failure was found (1-based), 0 if none
  double failed_t = 0.0;   ///< its end time
  int failed_body = 0;     ///< 1-based, 0 when not known
  std::string detail;      ///< what failed, in words
  /// With RunControl::profile: the profile of the run's steps (its `steps` the steps taken here,
  /// from the first after the start or checkpoint to the last known good).
  std::optional<sesi::profile::Report> profile;
  bool complete() const { return reason == StopReason::completed; }
};

/// What the run loop watches besides the state.
struct RunControl {
  const std::atomic<bool>* interrupted = nullptr;  ///< set by SIGINT/SIGTERM
  ProgressBar* progress = nullptr;
  /// Called after each step k that passed its checks (after its output row, if any); for
  /// `sesi bench --scaling`, which times a window of steps inside one run.
  std::function<void(long k)> after_step;
  /// Called with each checkpoint the run takes (every checkpoint_every steps, and at a signal);
  /// writes it (checkpoint.hpp). Empty: none taken.
  std::function<void(const Checkpoint&)> checkpoint;
  /// Profile the steps (sesi::profile; `sesi run --profile`): RunOutcome::profile.
  bool profile = false;
  /// A run across ranks (docs/parallel.md): rank 0's verdict on every rank (empty: one process).
  /// The loop passes each check's verdict through it, so that every rank takes the same branch
  /// and makes the same collective calls on the integrator; rank 0 decides (it has the data).
  std::function<bool(bool)> agree;
  /// Whether any rank's value is true (empty: one process): a signal that reached one rank
  /// stops all of them after the same step.
  std::function<bool(bool)> any;
};

/// What RunOutcome::detail says of a non-finite state: "the state became non-finite: body 3's
/// momenta overflowed to +-inf" when a value of body's column of q or p (1-based) is infinite,
/// "... became NaN" when one is NaN and none is infinite; with both finite, the same of energy
/// (the total energy that was not finite, and body the one whose term was). Overflow and NaN have
/// different causes (a step or a force too large for double, against 0/0 at a singular point), so
/// the message tells them apart (issue #12: "the messages for overflow say overflow").
/// q and p are called `coordinates` and `momenta` (a chart state) unless named otherwise (a
/// geodesic method's embedding points and velocities).
std::string non_finite_detail(const Eigen::MatrixXd& q, const Eigen::MatrixXd& p, int body, double energy,
                              const char* q_name = "coordinates", const char* p_name = "momenta");

/// "completed", "non-finite state", "invariant failed", "interrupted", "energy error exceeded",
/// "close encounter".
const char* stop_reason_name(StopReason reason);

}  // namespace sesi::program
