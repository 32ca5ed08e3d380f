#include "run_loop.hpp"

#include <cmath>
#include <string>
#include <vector>

#include <sesi/guard.hpp>

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

  /// The encounter deepest below its floor among the points x (ambient x bodies; the
  /// integrator's local points, force centres moved there by its to_local), as the detail of
  /// the run's failure, or "" when none.
  std::string check(const Eigen::MatrixXd& x, const Integrator& integrator) const {
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
    const auto pair = [&](const Term& t, int i, int j) {
      a = x.col(i);
      b = x.col(j);
      consider(t, geometry_.distance(a, b), i + 1, j + 1);
    };
    for (const Term& t : terms_) {
      const PotentialSpec& spec = scene_.potentials[t.index];
      if (const auto* central = std::get_if<CentralCotangentSpec>(&spec)) {
        const Eigen::VectorXd centre = integrator.to_local(central->center);
        for (Eigen::Index i = 0; i < x.cols(); ++i) {
          a = x.col(i);
          consider(t, geometry_.distance(a, centre), static_cast<int>(i) + 1, 0);
        }
        continue;
      }
      for (const auto& [i, j] : geometry_.close_pairs(x, t.floor)) pair(t, i, j);
      if (scene_.space.kind == SpaceKind::sphere && std::holds_alternative<CotangentGravitySpec>(spec)) {
        for (const auto& [i, j] : geometry_.close_pairs(x, t.floor, /*antipodal=*/true)) pair(t, i, j);
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

/// The energy guard of the scene (sesi::EnergyGuard), on the scale K0 + |V0| of its initial state.
sesi::EnergyGuard<double> energy_guard(const Scene& scene, const Geometry& geometry, const Snapshot& s) {
  double kinetic = 0.0;
  for (Eigen::Index b = 0; b < s.q.cols(); ++b) {
    kinetic += geometry.kinetic_energy(s.q.col(b), s.p.col(b), scene.bodies[static_cast<std::size_t>(b)].mass);
  }
  const double threshold = scene.integrator.energy_guard.value_or(sesi::EnergyGuard<double>::default_relative);
  return sesi::EnergyGuard<double>(s.energy, kinetic + std::abs(s.energy - kinetic), threshold);
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

double guard_threshold(const Scene& scene) {
  return scene.integrator.energy_guard.value_or(sesi::EnergyGuard<double>::default_relative);
}

/// The loop of every run: from step `first` of schedule, with the guard's reference given
/// (a checkpoint's, a RunStart's) or taken from the first state (fresh: that state is also
/// tracked and written). first_written: the first state is a row of the outputs already.
RunOutcome run_steps(const Scene& scene, Integrator& integrator, RunSink& recorder, const RunControl& control,
                     const Schedule& schedule, long first, const RunStart* reference, bool fresh,
                     bool first_written);

}  // namespace

long default_check_every(int bodies) { return bodies < many_bodies ? 1 : 20; }

RunStart guard_reference(const Scene& scene, Integrator& integrator) {
  Snapshot s;
  integrator.read(s.q, s.p);
  s.energy = initial_energy(scene, integrator);
  const sesi::EnergyGuard<double> guard = energy_guard(scene, Geometry(scene.space), s);
  RunStart start;
  start.guard_energy = guard.initial_energy();
  start.guard_scale = guard.scale();
  return start;
}

RunOutcome run_loop(const Scene& scene, Integrator& integrator, RunSink& recorder, const RunControl& control,
                    const Checkpoint* from) {
  const Schedule schedule(*scene.integrator.dt, *scene.integrator.t_end);
  if (!from) return run_steps(scene, integrator, recorder, control, schedule, 0, nullptr, true, true);
  RunStart reference;
  reference.guard_energy = from->guard_energy;
  reference.guard_scale = from->guard_scale;
  // A resumed run's rows and statistics up to its checkpoint are in the recorder already.
  return run_steps(scene, integrator, recorder, control, schedule, from->step, &reference, false,
                   from->step % scene.integrator.output_every == 0);
}

RunOutcome run_loop(const Scene& scene, Integrator& integrator, RunSink& sink, const RunControl& control,
                    const RunStart& start) {
  const Schedule schedule(*scene.integrator.dt, *scene.integrator.t_end, start.step, start.t);
  return run_steps(scene, integrator, sink, control, schedule, start.step, &start, false, true);
}

namespace {

RunOutcome run_steps(const Scene& scene, Integrator& integrator, RunSink& recorder, const RunControl& control,
                     const Schedule& schedule, long first, const RunStart* reference, bool fresh,
                     bool first_written) {
  const long every = scene.integrator.output_every;
  const long check_every =
      scene.integrator.check_every > 0 ? scene.integrator.check_every : default_check_every(scene.body_count());
  const long checkpoint_every = control.checkpoint ? scene.integrator.checkpoint_every : 0;

  Snapshot s;
  s.step = first;
  s.t = schedule.time(first);
  integrator.read(s.q, s.p);
  s.energy = initial_energy(scene, integrator);
  s.momentum = integrator.momentum_map();
  s.x = integrator.points();
  s.v = integrator.velocities();
  if (fresh) {
    recorder.track(s.energy, s.momentum);
    recorder.write_row(s);
  }

  const Geometry geometry(scene.space);
  const sesi::EnergyGuard<double> guard =
      reference ? sesi::EnergyGuard<double>(reference->guard_energy, reference->guard_scale, guard_threshold(scene))
                : energy_guard(scene, geometry, s);
  const EncounterCheck encounters(scene, geometry);
  // The checkpoint of the state after step k, with the outputs as the recorder has them now.
  const auto take_checkpoint = [&](long k) {
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
  // The last state that passed a check, and whether it is a row already. Checks (energy,
  // momentum map, guard, close encounters) run every check_every steps, at every output row, at
  // every checkpoint and at the last step; finiteness after every step. A failure names the step
  // where it was found and this last step known good, and no row is written past it.
  Snapshot good = s;
  bool good_written = first_written;
  for (long k = first + 1; k <= schedule.steps; ++k) {
    if (control.interrupted && control.interrupted->load(std::memory_order_relaxed)) {
      outcome.reason = StopReason::interrupted;
      outcome.detail = "interrupted by a signal";
      // The state after step k - 1 (finite; its energy is checked at the resumed run's checks),
      // with the rows an uninterrupted run has written by then: the stop row comes after.
      if (control.checkpoint) take_checkpoint(k - 1);
      break;
    }
    const bool regular_row = k % every == 0;
    const bool row = regular_row || k == schedule.steps;
    // Checkpoints at multiples of checkpoint_every only (not at the last step): they are checked
    // steps of any run of the scene, however long, so a longer run (sesi resume --t-end) goes on
    // from the last one as if it had been one run.
    const bool checkpoint = checkpoint_every > 0 && k % checkpoint_every == 0;
    const bool check = row || checkpoint || k % check_every == 0;
    int bad_body = 0;
    try {
      integrator.step(schedule.time(k - 1), schedule.h(k));
      bad_body = integrator.first_non_finite_body();
      if (bad_body == 0 && check) {
        s.energy = integrator.energy();
        if (std::isfinite(s.energy)) {
          s.momentum = integrator.momentum_map();
        } else {
          bad_body = std::max(1, integrator.body_with_non_finite_energy());
        }
      }
    } catch (const InvariantFailure& e) {
      outcome.reason = StopReason::invariant_failed;
      outcome.detail = std::string("a library invariant failed: ") + e.what();
    }
    if (bad_body != 0) {
      outcome.reason = StopReason::non_finite;
      outcome.failed_body = bad_body;
      const FramedState state = integrator.framed_state();  // where the value went bad
      outcome.detail = state.embedded
                           ? non_finite_detail(state.x, state.v, bad_body, s.energy, "embedding point", "velocity")
                           : non_finite_detail(state.q, state.p, bad_body, s.energy);
    } else if (outcome.reason == StopReason::completed && check) {
      // The close-encounter floor, then the energy guard (an encounter also spoils the energy).
      s.x = integrator.points();
      if (encounters.active()) {
        const std::string detail =
            integrator.clustered() ? encounters.check(integrator.local_points(), integrator) : encounters.check(s.x, integrator);
        if (!detail.empty()) {
          outcome.reason = StopReason::close_encounter;
          outcome.detail = std::move(detail);
        }
      }
      const auto verdict = guard.check(k, schedule.time(k), s.energy);
      if (outcome.reason == StopReason::completed && verdict.status == sesi::GuardStatus::energy_error_exceeded) {
        outcome.reason = StopReason::energy_guard;
        outcome.detail = "energy error exceeded: |E - E0| = " + format_short(std::abs(s.energy - guard.initial_energy())) +
                         ", " + format_short(verdict.error) + " times the initial energy scale " +
                         format_short(guard.scale()) + " (energy_guard = " + format_short(guard.relative()) + ")";
      }
    }
    if (outcome.reason != StopReason::completed) {
      outcome.failed_step = k;
      outcome.failed_t = schedule.time(k);
      break;
    }
    if (check) {
      s.step = k;
      s.t = schedule.time(k);
      integrator.read(s.q, s.p);
      s.v = integrator.velocities();
      recorder.track(s.energy, s.momentum);
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
  // The outputs end at the last state known good: a row if it is not one yet, and the summary's
  // final state.
  outcome.steps_done = good.step;
  if (!good_written) recorder.write_row(good);
  recorder.set_final(std::move(good));
  return outcome;
}

}  // namespace

}  // namespace sesi::program
