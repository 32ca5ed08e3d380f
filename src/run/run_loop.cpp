#include "run_loop.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include <sesi/guard.hpp>
#include <sesi/parallel.hpp>
#include <sesi/profile.hpp>

#include "checkpoint.hpp"
#include "errors.hpp"
#include "geometry.hpp"
#include "progress.hpp"
#include "validate.hpp"

namespace sesi::program {

namespace {

/// The singular potentials' close-encounter floors (docs/stability.md), checked at the run's
/// checks on the embedding points in O(N log N) (close and, for cotangent terms on S^n,
/// antipodal pairs through the neighbour index); nothing to do without a singular potential.
class EncounterCheck {
 public:
  EncounterCheck(const Scene& scene, const Geometry& geometry) : scene_(scene), geometry_(geometry) {
    for (std::size_t k = 0; k < scene.potentials.size(); ++k) {
      const double floor = encounter_floor(scene.potentials[k], geometry.length_scale());
      if (floor > 0.0) terms_.push_back({k, floor});
    }
  }
  bool active() const { return !terms_.empty(); }

  /// The encounter deepest below its floor among the points the integrator's potentials see
  /// (its local points, force centres moved there by its to_local), as the detail of the run's
  /// failure, or "" when none. Every body's point only where a term needs them all (a force
  /// centre, a search without the forces' lists): across ranks rank 0 then gathers them.
  std::string check(Integrator& integrator) const {
    const bool local = integrator.clustered();
    Eigen::MatrixXd whole;
    bool held = false;
    const auto all_points = [&]() -> const Eigen::MatrixXd& {
      if (!held) whole = local ? integrator.local_points() : integrator.points();
      held = true;
      return whole;
    };
    double worst = 1.0;
    std::string detail;
    const auto consider = [&](const Term& t, double d, int i, int j) {
      const PotentialSpec& spec = scene_.potentials[t.index];
      const double gap = singular_gap(spec, scene_.space.kind, scene_.space.radius, d);
      if (!(gap / t.floor < worst)) return;  // NaN distances are the non-finite check's
      worst = gap / t.floor;
      const std::string where = j > 0 ? "bodies " + std::to_string(i) + " and " + std::to_string(j)
                                      : "body " + std::to_string(i) + " and the center";
      detail = "close encounter: " + where + " came within " + format_short(gap) +
               (gap < d ? " of antipodal" : "") + ", below the close-encounter floor " +
               format_short(t.floor) + " of the " + std::string(potential_kind(spec)) +
               " potential (potential[" + std::to_string(t.index + 1) + "], min_distance)";
    };
    Eigen::VectorXd a, b;
    const auto pairs = [&](const Term& t, const std::vector<std::pair<int, int>>& close, const Eigen::MatrixXd& x,
                           const std::vector<int>* columns) {
      // columns: x's bodies (ascending) where x holds only those.
      const auto column = [&](int body) {
        return columns ? std::lower_bound(columns->begin(), columns->end(), body) - columns->begin() : Eigen::Index{body};
      };
      for (const auto& [i, j] : close) {
        a = x.col(column(i));
        b = x.col(column(j));
        consider(t, geometry_.distance(a, b), i + 1, j + 1);
      }
    };
    for (const Term& t : terms_) {
      const PotentialSpec& spec = scene_.potentials[t.index];
      if (const auto* central = std::get_if<CentralCotangentSpec>(&spec)) {
        const Eigen::VectorXd centre = integrator.to_local(central->center);
        const Eigen::MatrixXd& x = all_points();
        for (Eigen::Index i = 0; i < x.cols(); ++i) {
          a = x.col(i);
          consider(t, geometry_.distance(a, centre), static_cast<int>(i) + 1, 0);
        }
        continue;
      }
      // The pairs from the lists the forces keep, where they hold them: one neighbour structure
      // per step (issue #27), and the points of those pairs' bodies alone; else the geometry's
      // own search.
      std::vector<std::pair<int, int>> close;
      if (integrator.listed_close_pairs(t.floor, close)) {
        std::vector<int> bodies;
        for (const auto& [i, j] : close) bodies.insert(bodies.end(), {i, j});
        std::sort(bodies.begin(), bodies.end());
        bodies.erase(std::unique(bodies.begin(), bodies.end()), bodies.end());
        pairs(t, close, integrator.points_of(bodies, local), &bodies);
      } else {
        pairs(t, geometry_.close_pairs(all_points(), t.floor), all_points(), nullptr);
      }
      if (scene_.space.kind == SpaceKind::sphere && std::holds_alternative<CotangentGravitySpec>(spec)) {
        pairs(t, geometry_.close_pairs(all_points(), t.floor, /*antipodal=*/true), all_points(), nullptr);
      }
    }
    return detail;
  }

 private:
  struct Term {
    std::size_t index;
    double floor;
  };
  const Scene& scene_;
  const Geometry& geometry_;
  std::vector<Term> terms_;
};

/// Whether the scene's thermostat is brownian: overdamped dynamics conserve nothing, so its
/// energy guard is off (non-finite states are still caught).
bool brownian(const Scene& scene) { return scene.thermostat && scene.thermostat->kind == "brownian"; }

/// What the energy guard judges at s: the energy, or with a thermostat the conserved quantity
/// E + conserved_offset() (the energy itself moves by the heat the thermostat puts in; a step too
/// large shows in the conserved quantity as in the energy of an NVE run). Brownian: the energy
/// (its guard is off).
double guarded_value(const Scene& scene, const Snapshot& s) {
  return s.thermostat && !brownian(scene) ? s.conserved : s.energy;
}

double guard_threshold(const Scene& scene) {
  if (brownian(scene)) return 0.0;  // off (sesi::EnergyGuard: relative <= 0)
  return scene.integrator.energy_guard.value_or(sesi::EnergyGuard<double>::default_relative);
}

/// The energy guard of the scene (sesi::EnergyGuard), on the scale K0 + |V0| of its initial state.
/// Across ranks (Snapshot::gather) every rank calls it: rank 0 sums over the bodies in body order
/// (one process's bits) from blocks the other ranks serve, and hands the sum to them.
sesi::EnergyGuard<double> energy_guard(const Scene& scene, const Geometry& geometry, const Snapshot& s) {
  double kinetic = 0.0;
  const auto add = [&](const BodyBlock& block) {
    const auto q = block.q(), p = block.p();
    for (Eigen::Index k = 0; k < block.count; ++k) {
      const double m = scene.bodies[static_cast<std::size_t>(block.first + k)].mass;
      kinetic += geometry.kinetic_energy(q.col(k), p.col(k), m);
    }
  };
  if (!s.gather) {
    for_each_block(s, field_q | field_p, add);
  } else if (s.gather->root()) {
    const ServedUntil served(s);
    for_each_block(s, field_q | field_p, add);
  } else {
    s.gather->serve(s);
  }
  if (s.gather) kinetic = s.gather->shared(kinetic);
  return sesi::EnergyGuard<double>(guarded_value(scene, s), kinetic + std::abs(s.energy - kinetic),
                                   guard_threshold(scene));
}

/// A thermostatted run's observables of the integrator's state at time t into s (its energy
/// already there): the schedule's target, the temperatures, the heat and the conserved quantity.
/// The configurational sums (a gradient and a Laplacian pass, more than the energy's) only where
/// `row` says the state is an output row; else NaN until configurational() fills them in.
void observe_thermostat(const Scene& scene, Integrator& integrator, double t, Snapshot& s, bool row) {
  if (!scene.thermostat) return;
  s.thermostat = true;
  s.temperature = scene.thermostat->temperature_at(t);
  s.kinetic_temperature = integrator.kinetic_temperature();
  s.configurational = row ? integrator.configurational_sums()
                          : std::array<double, 2>{std::nan(""), std::nan("")};
  s.heat = integrator.heat();
  s.conserved = s.energy + integrator.conserved_offset();
}

/// A run on a topology: the image record of the integrator's state into s, beside its wrapped
/// points (Snapshot::image_counts on an E^n box; words and unwrapped points on an H^2 surface).
void observe_topology(const Scene& scene, Integrator& integrator, Snapshot& s) {
  if (!scene.space.box.empty()) {
    s.image_counts = integrator.image_counts();
  } else if (scene.space.genus > 0) {
    s.words = integrator.words();
    s.unwrapped = integrator.unwrapped_points();
  }
}

/// The step sizes: |dt| everywhere but the last step, which ends exactly at t_end. Times are
/// k dt, or t0 + (k - k0) dt for a run that goes on from a time t0 off that grid (RunStart).
struct Schedule {
  long steps;
  double dt, last_h, sign, t_end;
  long k0 = 0;
  double t0 = 0.0;
  bool on_grid = true;
  Schedule(double dt_, double t_end_)
      : steps(step_count(t_end_, dt_)), dt(dt_), last_h(dt_), sign(dt_ > 0 ? 1.0 : -1.0), t_end(t_end_) {
    shorten_last(static_cast<double>(steps) * std::abs(dt), t_end, steps);
  }
  /// From step k0 at time t0 (signed) to the signed time sign * t_end.
  Schedule(double dt_, double t_end_, long k0_, double t0_)
      : steps(0), dt(dt_), last_h(dt_), sign(dt_ > 0 ? 1.0 : -1.0), t_end(t_end_), k0(k0_), t0(t0_),
        on_grid(t0_ == static_cast<double>(k0_) * dt_) {
    if (on_grid) {
      steps = step_count(t_end, dt);
      shorten_last(static_cast<double>(steps) * std::abs(dt), t_end, steps);
    } else {
      const double left = t_end - sign * t0;  // >= 0, checked by the caller
      steps = k0 + step_count(left, dt);
      shorten_last(static_cast<double>(steps - k0) * std::abs(dt), left, steps - k0);
    }
  }
  double h(long k) const { return k == steps ? last_h : dt; }
  /// Time at the end of step k (0 for k = 0).
  double time(long k) const {
    if (k == steps) return sign * t_end;
    return on_grid ? static_cast<double>(k) * dt : t0 + static_cast<double>(k - k0) * dt;
  }

 private:
  void shorten_last(double covered, double length, long count) {
    if (std::abs(covered - length) > 1e-9 * std::max(1.0, length)) {
      last_h = sign * (length - static_cast<double>(count - 1) * std::abs(dt));
    }
  }
};


/// The initial energy of the integrator's state; throws InputError when it is not finite.
double initial_energy(const Scene& scene, Integrator& integrator) {
  const double energy = integrator.energy();
  if (!std::isfinite(energy)) {
    throw InputError(Origin{scene.source}, "",
                     "the initial energy is not finite (body " +
                         std::to_string(integrator.body_with_non_finite_energy()) +
                         "): check the initial conditions against the potentials");
  }
  return energy;
}

/// The loop of every run: from step `first` of schedule, with the guard's reference given
/// (a checkpoint's, a RunStart's) or taken from the first state (fresh: that state is also
/// tracked and written). first_written: the first state is a row of the outputs already.
/// end_checkpoint: the run ends with a checkpoint (end_checkpoint_step).
RunOutcome run_steps(const Scene& scene, Integrator& integrator, RunSink& recorder, const RunControl& control,
                     const Schedule& schedule, long first, const RunStart* reference, bool fresh,
                     bool first_written, bool end_checkpoint);

/// Whether the last step is one that a longer run takes too: whole, and ending at k dt to the bit
/// (not at a t_end off the grid by round-off, which its row's t would show). A checkpoint there
/// goes on as one run; one at another last step would not.
bool last_step_on_grid(const Schedule& schedule) {
  const long last = schedule.steps;
  return schedule.on_grid && schedule.h(last) == schedule.dt &&
         schedule.time(last) == static_cast<double>(last) * schedule.dt;
}

/// The step of a finished run's last checkpoint: its last step that every longer run of the scene
/// checks too (a multiple of output_every, check_every or checkpoint_every) and takes as they do
/// (the last step only if last_step_on_grid), so that sesi resume --t-end goes on from it as one
/// run; -1 when there is none after `first`.
long end_checkpoint_step(const Schedule& schedule, long first, long every, long check_every, long checkpoint_every) {
  if (!schedule.on_grid) return -1;
  const long whole = last_step_on_grid(schedule) ? schedule.steps : schedule.steps - 1;
  long step = -1;
  for (const long m : {every, check_every, checkpoint_every}) {
    if (m > 0 && whole >= 0) step = std::max(step, whole / m * m);
  }
  return step > first ? step : -1;
}

}  // namespace

long default_check_every(int bodies) { return bodies < many_bodies ? 1 : 20; }

RunStart guard_reference(const Scene& scene, Integrator& integrator) {
  Snapshot s;
  integrator.read(s.q, s.p);
  s.energy = initial_energy(scene, integrator);
  observe_thermostat(scene, integrator, 0.0, s, false);
  const sesi::EnergyGuard<double> guard = energy_guard(scene, Geometry(scene.space), s);
  RunStart start;
  start.guard_energy = guard.initial_energy();
  start.guard_scale = guard.scale();
  return start;
}

RunOutcome run_loop(const Scene& scene, Integrator& integrator, RunSink& recorder, const RunControl& control,
                    const Checkpoint* from) {
  const Schedule schedule(*scene.integrator.dt, *scene.integrator.t_end);
  // A run that takes checkpoints ends with one, and so does every run gone on from one: a
  // finished run always goes on (sesi resume --t-end) from its end.
  const bool end_checkpoint = from != nullptr || scene.integrator.checkpoint_every > 0;
  if (!from) return run_steps(scene, integrator, recorder, control, schedule, 0, nullptr, true, true, end_checkpoint);
  RunStart reference;
  reference.guard_energy = from->guard_energy;
  reference.guard_scale = from->guard_scale;
  // A resumed run's rows and statistics up to its checkpoint are in the recorder already.
  return run_steps(scene, integrator, recorder, control, schedule, from->step, &reference, false,
                   from->step % scene.integrator.output_every == 0, end_checkpoint);
}

RunOutcome run_loop(const Scene& scene, Integrator& integrator, RunSink& sink, const RunControl& control,
                    const RunStart& start) {
  const Schedule schedule(*scene.integrator.dt, *scene.integrator.t_end, start.step, start.t);
  return run_steps(scene, integrator, sink, control, schedule, start.step, &start, false, true, false);
}

namespace {

RunOutcome run_steps(const Scene& scene, Integrator& integrator, RunSink& recorder, const RunControl& control,
                     const Schedule& schedule, long first, const RunStart* reference, bool fresh,
                     bool first_written, bool end_checkpoint) {
  const long every = scene.integrator.output_every;
  const long check_every =
      scene.integrator.check_every > 0 ? scene.integrator.check_every : default_check_every(scene.body_count());
  const long checkpoint_every = control.checkpoint ? scene.integrator.checkpoint_every : 0;

  Snapshot s;
  s.step = first;
  s.t = schedule.time(first);
  s.energy = initial_energy(scene, integrator);
  observe_thermostat(scene, integrator, s.t, s, true);
  s.momentum = integrator.momentum_map();
  if (!integrator.own_state(s)) {  // (across ranks: this rank's own bodies)
    integrator.read(s.q, s.p);
    s.x = integrator.points();
    observe_topology(scene, integrator, s);
    s.v = integrator.velocities();
  }
  if (fresh) {
    recorder.track(s.energy, s.momentum);
    if (s.thermostat) recorder.track_conserved(s.conserved);
    recorder.write_row(s);
  }

  const Geometry geometry(scene.space);
  const sesi::EnergyGuard<double> guard =
      reference ? sesi::EnergyGuard<double>(reference->guard_energy, reference->guard_scale, guard_threshold(scene))
                : energy_guard(scene, geometry, s);
  const EncounterCheck encounters(scene, geometry);
  // The checkpoint of the state after step k, with the outputs as the recorder has them now.
  const auto take_checkpoint = [&](long k) {
    const sesi::profile::Scope profiled(sesi::profile::Phase::checkpoint);
    Checkpoint c;
    c.scene = scene;
    c.scene.bodies.clear();  // the masses only: the state is the checkpoint's own
    for (const Body& b : scene.bodies) c.scene.bodies.push_back(Body{b.mass, {}, {}});
    c.guard_energy = guard.initial_energy();
    c.guard_scale = guard.scale();
    c.step = k;
    c.state = integrator.framed_state();
    c.outputs = recorder.cursor();
    c.recorder = recorder.state();
    control.checkpoint(c);
  };

  RunOutcome outcome;
  const bool last_on_grid = last_step_on_grid(schedule);
  const long end_step = control.checkpoint && end_checkpoint
                            ? end_checkpoint_step(schedule, first, every, check_every, checkpoint_every)
                            : -1;
  // outcome for a non-finite value in body bad_body (1-based), named where it went bad.
  const auto set_non_finite = [&](int bad_body) {
    outcome.reason = StopReason::non_finite;
    outcome.failed_body = bad_body;
    const FramedState state = integrator.framed_state();
    outcome.detail = state.embedded
                         ? non_finite_detail(state.x, state.v, bad_body, s.energy, "embedding point", "velocity")
                         : non_finite_detail(state.q, state.p, bad_body, s.energy);
  };
  // Whether the state after step k (finite: the caller checked) passes the run's checks: its
  // energy and momentum map (into s), the close-encounter floor, then the energy guard (an
  // encounter also spoils the energy). On a failure, outcome says which.
  const auto passes_checks = [&](long k) {
    const sesi::profile::Scope profiled(sesi::profile::Phase::checks);
    int bad_body = 0;
    try {
      s.energy = integrator.energy();
      if (std::isfinite(s.energy)) {
        s.momentum = integrator.momentum_map();
        // At every check (the guard judges the conserved quantity); the configurational sums at
        // the output rows (a last state known good between rows gets them at the run's end).
        observe_thermostat(scene, integrator, schedule.time(k), s, k % every == 0 || k == schedule.steps);
      } else {
        bad_body = std::max(1, integrator.body_with_non_finite_energy());
      }
    } catch (const InvariantFailure& e) {
      outcome.reason = StopReason::invariant_failed;
      outcome.detail = std::string("a library invariant failed: ") + e.what();
      return false;
    }
    if (bad_body != 0) {
      set_non_finite(bad_body);
      return false;
    }
    if (encounters.active()) {
      const std::string detail = encounters.check(integrator);
      if (!detail.empty()) {
        outcome.reason = StopReason::close_encounter;
        outcome.detail = std::move(detail);
        return false;
      }
    }
    const double judged = guarded_value(scene, s);
    const auto verdict = guard.check(k, schedule.time(k), judged);
    if (verdict.status == sesi::GuardStatus::energy_error_exceeded) {
      outcome.reason = StopReason::energy_guard;
      const std::string change = format_short(std::abs(judged - guard.initial_energy()));
      outcome.detail = (s.thermostat ? "conserved-quantity error exceeded: |C - C0| = " + change +
                                           " (C = E + the thermostat's conserved offset)"
                                     : "energy error exceeded: |E - E0| = " + change) +
                       ", " + format_short(verdict.error) + " times the initial energy scale " +
                       format_short(guard.scale()) + " (energy_guard = " + format_short(guard.relative()) + ")";
      return false;
    }
    return true;
  };
  const auto fail_at = [&](long k) {
    outcome.failed_step = k;
    outcome.failed_t = schedule.time(k);
  };
  // The last state that passed a check, and whether it is a row already. Checks (energy,
  // momentum map, guard, close encounters) run every check_every steps, at every output row, at
  // every checkpoint and at the last step; finiteness after every step. A failure names the step
  // where it was found and this last step known good, and no row is written past it.
  Snapshot good = std::move(s);  // (s's whole-run matrices are formed again at each check)
  bool good_written = first_written;
  // The whole state after step k, which passed its checks, into s (rows and the final state).
  // The last good state's copy is dropped first: it is superseded, and so a run holds one
  // copy of the state at a time, not two. Across ranks each rank holds its own bodies' columns
  // (Integrator::own_state), and rank 0 gathers them in blocks as it writes them: no rank holds
  // every body's (80 bytes a body on S^2, 80 MB at 10^6 bodies).
  const auto take_state = [&](long k) {
    for (Eigen::MatrixXd* m : {&good.q, &good.p, &good.x, &good.v, &good.unwrapped}) m->resize(0, 0);
    good.image_counts.resize(0, 0);
    good.words = {};
    good.ids = {};
    s.step = k;
    s.t = schedule.time(k);
    if (integrator.own_state(s)) return;
    s.x = integrator.points();
    observe_topology(scene, integrator, s);
    integrator.read(s.q, s.p);
    s.v = integrator.velocities();
  };
  // The profile covers the steps: from here to the loop's end (not the first row, nor the last
  // row written after the loop for a state known good between rows).
  long stepped = first;  // the last step taken (the profile's count)
  if (control.profile) sesi::profile::start(sesi::parallel::threads());
  // Across ranks (RunControl::agree): a check passes when it passes on rank 0; a rank that
  // judged otherwise drops the failure it recorded (only rank 0's outcome is reported).
  const auto checked = [&](long k) {
    if (!control.agree) return passes_checks(k);
    const RunOutcome before = outcome;
    const bool mine = passes_checks(k);
    const bool verdict = control.agree(mine);
    if (verdict && !mine) outcome = before;
    return verdict;
  };
  const auto interrupted = [&] {
    const bool mine = control.interrupted && control.interrupted->load(std::memory_order_relaxed);
    return control.any ? control.any(mine) : mine;
  };
  for (long k = first + 1; k <= schedule.steps; ++k) {
    if (interrupted()) {
      // The run stops after step k - 1 (finite), checked here if it was not: the stop, the
      // outputs' last row and the checkpoint are all at that one step.
      const long last = k - 1;
      const bool unchecked = good.step != last;
      if (unchecked && !checked(last)) {
        fail_at(last);
        break;
      }
      outcome.reason = StopReason::interrupted;
      outcome.detail = "interrupted by a signal";
      // With the rows and statistics an uninterrupted run has by then: the stop row and this
      // check come after (a longer run need not check this step).
      if (control.checkpoint) take_checkpoint(last);
      if (unchecked) {
        take_state(last);
        recorder.track(s.energy, s.momentum);
        if (s.thermostat) recorder.track_conserved(s.conserved);
        good_written = false;
        std::swap(good, s);
      }
      break;
    }
    const bool regular_row = k % every == 0;
    const bool row = regular_row || k == schedule.steps;
    // Checkpoints at multiples of checkpoint_every, and at the run's end checkpoint (a step every
    // longer run checks too), never at a last step that a longer run does not take as it is: so a
    // longer run (sesi resume --t-end) goes on from any of them as if it had been one run.
    const bool checkpoint = ((checkpoint_every > 0 && k % checkpoint_every == 0) || k == end_step) &&
                            (k != schedule.steps || last_on_grid);
    const bool check = row || checkpoint || k % check_every == 0;
    if (scene.thermostat) {
      // The temperature at the step's midpoint: the step is symmetric about it (its two halves
      // mirror each other), so a schedule's ramp enters it as the midpoint rule, to second order
      // like the step itself; the end points would lag or lead a ramp by h/2.
      integrator.set_temperature(scene.thermostat->temperature_at(schedule.time(k - 1) + 0.5 * schedule.h(k)));
      // The noise's step key is the run's step count (so a resumed run, a run cut into pieces
      // and one run draw the same numbers).
      integrator.set_thermostat_step(static_cast<std::uint64_t>(k - 1));
    }
    try {
      stepped = k;
      integrator.step(schedule.time(k - 1), schedule.h(k));
    } catch (const InvariantFailure& e) {
      outcome.reason = StopReason::invariant_failed;
      outcome.detail = std::string("a library invariant failed: ") + e.what();
      fail_at(k);
      break;
    }
    int non_finite_body = 0;
    {
      const sesi::profile::Scope profiled(sesi::profile::Phase::checks);
      non_finite_body = integrator.first_non_finite_body();
    }
    if (const int bad_body = non_finite_body; bad_body != 0) {
      set_non_finite(bad_body);
      fail_at(k);
      break;
    }
    if (check && !checked(k)) {
      fail_at(k);
      break;
    }
    if (check) {
      const sesi::profile::Scope profiled(sesi::profile::Phase::output);  // rows, statistics (and checkpoints)
      take_state(k);
      recorder.track(s.energy, s.momentum);
      if (s.thermostat) recorder.track_conserved(s.conserved);
      // A checkpoint's outputs hold the regular rows only: the last step's extra row is cut on
      // resume, since a longer run does not write it.
      if (checkpoint && !regular_row) take_checkpoint(k);
      if (row) recorder.write_row(s);
      if (checkpoint && regular_row) take_checkpoint(k);
      good_written = row;
      std::swap(good, s);
    }
    if (control.progress) control.progress->update(k, schedule.time(k));
    if (control.after_step) control.after_step(k);
  }
  if (control.profile) {
    outcome.profile = sesi::profile::stop();
    outcome.profile->steps = stepped - first;
  }
  // The outputs end at the last state known good: a row if it is not one yet, and the summary's
  // final state.
  outcome.steps_done = good.step;
  // The integrator still holds that state unless a failure was found after it (failed_step): then
  // its row has no configurational temperature (NaN).
  if (!good_written && good.thermostat && outcome.failed_step == 0) {
    good.configurational = integrator.configurational_sums();
  }
  if (!good_written) recorder.write_row(good);
  recorder.set_final(std::move(good));
  return outcome;
}

}  // namespace

}  // namespace sesi::program
