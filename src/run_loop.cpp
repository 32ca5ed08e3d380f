#include "run_loop.hpp"

#include <cmath>
#include <string>

#include "errors.hpp"
#include "progress.hpp"
#include "validate.hpp"

namespace sesi::program {

namespace {

/// The first body (1-based) whose coordinates or momenta are not finite, or 0.
int first_non_finite_body(const Eigen::MatrixXd& q, const Eigen::MatrixXd& p) {
  for (Eigen::Index b = 0; b < q.cols(); ++b) {
    if (!q.col(b).allFinite() || !p.col(b).allFinite()) return static_cast<int>(b) + 1;
  }
  return 0;
}

/// The step sizes: |dt| everywhere but the last step, which ends exactly at t_end.
struct Schedule {
  long steps;
  double dt, last_h, sign, t_end;
  Schedule(double dt_, double t_end_)
      : steps(step_count(t_end_, dt_)), dt(dt_), last_h(dt_), sign(dt_ > 0 ? 1.0 : -1.0), t_end(t_end_) {
    const double covered = static_cast<double>(steps) * std::abs(dt);
    if (std::abs(covered - t_end) > 1e-9 * std::max(1.0, t_end)) {
      last_h = sign * (t_end - static_cast<double>(steps - 1) * std::abs(dt));
    }
  }
  double h(long k) const { return k == steps ? last_h : dt; }
  /// Time at the end of step k (0 for k = 0).
  double time(long k) const { return k == steps ? sign * t_end : static_cast<double>(k) * dt; }
};

}  // namespace

RunOutcome run_loop(const Scene& scene, Integrator& integrator, Observables& observe, Recorder& recorder,
                    const RunControl& control) {
  const Schedule schedule(*scene.integrator.dt, *scene.integrator.t_end);
  const long every = scene.integrator.output_every;

  Snapshot s;
  integrator.read(s.q, s.p);
  observe.set_state(s.q, s.p);
  s.energy = observe.energy();
  if (!std::isfinite(s.energy)) {
    throw InputError(Origin{scene.source}, "",
                     "the initial energy is not finite (body " +
                         std::to_string(observe.body_with_non_finite_energy()) +
                         "): check the initial conditions against the potentials");
  }
  s.momentum = observe.momentum_map();
  s.x = observe.points();
  recorder.track(s.energy, s.momentum);
  recorder.write_row(s);

  RunOutcome outcome;
  Snapshot good = s;         // the last finite state
  bool good_written = true;  // ... and whether it is a row already
  for (long k = 1; k <= schedule.steps; ++k) {
    if (control.interrupted && control.interrupted->load(std::memory_order_relaxed)) {
      outcome.reason = StopReason::interrupted;
      outcome.detail = "interrupted by a signal";
      break;
    }
    int bad_body = 0;
    try {
      integrator.step(schedule.time(k - 1), schedule.h(k));
      integrator.read(s.q, s.p);
      bad_body = first_non_finite_body(s.q, s.p);
      if (bad_body == 0) {
        observe.set_state(s.q, s.p);
        s.energy = observe.energy();
        if (std::isfinite(s.energy)) {
          s.momentum = observe.momentum_map();
        } else {
          bad_body = std::max(1, observe.body_with_non_finite_energy());
        }
      }
    } catch (const InvariantFailure& e) {
      outcome.reason = StopReason::invariant_failed;
      outcome.detail = std::string("a library invariant failed: ") + e.what();
    }
    if (bad_body != 0) {
      outcome.reason = StopReason::non_finite;
      outcome.failed_body = bad_body;
      outcome.detail = "the state became non-finite";
    }
    if (outcome.reason != StopReason::completed) {
      outcome.failed_step = k;
      outcome.failed_t = schedule.time(k);
      break;
    }
    s.step = k;
    s.t = schedule.time(k);
    recorder.track(s.energy, s.momentum);
    outcome.steps_done = k;
    good_written = k % every == 0 || k == schedule.steps;
    if (good_written) {
      s.x = observe.points();
      recorder.write_row(s);
    }
    std::swap(good, s);
    if (control.progress) control.progress->update(k, good.t);
  }
  // The last finite state closes the outputs: as a row if it is not one yet, and in the summary.
  observe.set_state(good.q, good.p);
  good.x = observe.points();
  good.v = observe.velocities();
  if (!good_written) recorder.write_row(good);
  recorder.set_final(std::move(good));
  return outcome;
}

}  // namespace sesi::program
