#include "auto_method.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include <sesi/parallel.hpp>

#include "errors.hpp"
#include "integrator.hpp"
#include "methods.hpp"
#include "run_loop.hpp"
#include "validate.hpp"

namespace sesi::program {

namespace {

constexpr double inf = std::numeric_limits<double>::infinity();

/// The methods auto tries: for each order the composition with the least cost to an energy
/// error in the bench's horizon sweeps (docs/benchmarks.md), the processed methods, and the
/// geodesic ones on S^n and H^n only.
constexpr std::array candidate_names{
    std::string_view{"sesi4-mclachlan"}, std::string_view{"sesi6-kahan-li"},
    std::string_view{"sesi8-kahan-li"},
    std::string_view{"sesi6-processed"}, std::string_view{"sesi8-processed"},
    std::string_view{"sesi10-processed"}, std::string_view{"geodesic4"},
    std::string_view{"geodesic6-kahan-li"}, std::string_view{"geodesic8-kahan-li"},
    std::string_view{"geodesic8-processed"}, std::string_view{"geodesic10-processed"}};

/// The pilot step aims at this fraction of the tolerance: the run's max error then lands below
/// it even where the pilot's order estimate is off by one (a factor of a few).
constexpr double aim_fraction = 0.4;
/// The cheapest candidates after the first pilots (at most refined_count, none predicted to cost
/// more than prune_factor times the cheapest) get a second pilot at their predicted step.
constexpr double prune_factor = 3.0;
constexpr std::size_t refined_count = 3;
/// Energy samples per pilot run (evenly spaced steps): the max over them is the pilot's error.
constexpr long pilot_samples = 400;
/// Pilot errors below this are round-off, not the method's: they tell nothing of its step.
constexpr double roundoff_error = 1e-13;
/// Pilot errors above this mean the step is far too large.
constexpr double too_large_error = 1e-2;

/// The dynamical time of the scene's initial state: min over bodies of L / |v| and sqrt(L / |a|),
/// L the radius (S^n, H^n) or the bodies' RMS distance from their centroid (E^n, else 1); |a|
/// from the velocity change over one tiny step. inf when nothing moves or accelerates.
double dynamical_time(const Scene& scene, double t_end) {
  Scene probe = scene;
  probe.integrator.method = "sesi2";
  const auto integrator = make_integrator(probe);
  const Eigen::MatrixXd x0 = integrator->points();
  const Eigen::MatrixXd v0 = integrator->velocities();
  double length = scene.space.radius;
  if (scene.space.kind == SpaceKind::euclidean) {
    const Eigen::VectorXd centroid = x0.rowwise().mean();
    const double rms = std::sqrt((x0.colwise() - centroid).colwise().squaredNorm().mean());
    length = rms > 0 && std::isfinite(rms) ? rms : 1.0;
  }
  double tau = inf;
  for (Eigen::Index b = 0; b < v0.cols(); ++b) {
    const double speed = v0.col(b).norm();
    if (speed > 0) tau = std::min(tau, length / speed);
  }
  const double h = 1e-6 * std::min(tau, t_end > 0 ? t_end : 1.0);
  integrator->step(0.0, h);
  const Eigen::MatrixXd v1 = integrator->velocities();
  for (Eigen::Index b = 0; b < v0.cols(); ++b) {
    const double accel = (v1.col(b) - v0.col(b)).norm() / h;
    if (accel > 0 && std::isfinite(accel)) tau = std::min(tau, std::sqrt(length / accel));
  }
  return tau;
}

/// The predicted cost of a run of `method` with step dt: steps x (stages + reads per step x
/// output stages) x stage cost. Reads are the states the run loop looks at between steps (output
/// rows and checks; a processed method post-processes each, MethodInfo::output_stages).
double run_cost(const Scene& scene, const MethodInfo& info, double span, double dt) {
  const IntegratorSpec& in = scene.integrator;
  const double steps = std::ceil(span / dt);
  long output_every = in.output_every;
  if (in.dt) output_every = std::max(1L, std::lround(std::abs(*in.dt) * static_cast<double>(in.output_every) / dt));
  const long check_every = in.check_every > 0 ? in.check_every : default_check_every(scene.body_count());
  const double reads = 1.0 / static_cast<double>(std::min(output_every, check_every));
  const double stage_cost = is_embedded_method(info.name) ? geodesic_stage_cost : 1.0;
  return steps * (info.stages + reads * info.output_stages) * stage_cost;
}

struct Pilot {
  const Scene& scene;
  double t_end;      ///< of each pilot run
  double energy0;    ///< the scene's initial energy (non-zero)
  long steps = 0;    ///< of all pilot runs

  /// The max relative energy error of `method` with step h over [0, t_end]; inf when the run
  /// failed (a non-finite energy, an error above 1, or an error thrown by the library).
  double error(std::string_view method, double h) {
    Scene s = scene;
    s.integrator.method = std::string(method);
    s.integrator.dt = h;
    s.integrator.auto_choice.reset();
    const long n = std::max(1L, static_cast<long>(std::ceil(t_end / h - 1e-9)));
    const long every = std::max(1L, n / pilot_samples);
    double worst = 0;
    try {
      const auto integrator = make_integrator(s);
      for (long k = 0; k < n; ++k) {
        integrator->step(static_cast<double>(k) * h, h);
        ++steps;
        if ((k + 1) % every != 0 && k + 1 != n) continue;
        const double e = std::abs(integrator->energy() - energy0) / std::abs(energy0);
        if (!(e <= 1.0)) return inf;  // also NaN
        worst = std::max(worst, e);
      }
    } catch (const InputError&) {
      throw;  // the scene itself is refused (e.g. a geodesic method far out): not the step's fault
    } catch (const std::exception&) {
      return inf;  // an invariant check of the library: the step is too large
    }
    return worst;
  }
};

}  // namespace

void resolve_auto(Scene& scene) {
  IntegratorSpec& in = scene.integrator;
  if (in.method != "auto") return;
  const Origin file{scene.source, in.line};
  if (!in.tolerance) {
    throw InputError(file, "integrator.tolerance",
                     "method = \"auto\" needs a tolerance (the target max relative energy error; "
                     "give it in [integrator] or with --tolerance)");
  }
  if (!in.t_end) {
    throw InputError(file, "integrator.t_end", "missing required key (give it in [integrator] or with --t-end)");
  }
  check_thermostat_method(scene, file, "integrator.method");  // not with a brownian thermostat
  const double tol = *in.tolerance;
  const double t_end = *in.t_end;
  AutoChoice choice;
  choice.tolerance = tol;
  choice.given_dt = in.dt;
  choice.given_output_every = in.output_every;
  sesi::parallel::set_threads(in.threads);
  const auto started = std::chrono::steady_clock::now();

  // A thermostat runs with sesi2 only (check_thermostat_method): auto then picks its step alone,
  // from pilot runs of the scene without the thermostat, whose energy error is the step's own (the
  // thermostatted step is the same Strang step with momentum stages between its halves).
  const bool thermostat = scene.thermostat.has_value();
  Scene nve = scene;
  nve.thermostat.reset();
  Scene probe = nve;
  probe.integrator.method = "sesi2";
  const double energy0 = make_integrator(probe)->energy();
  if (!(std::abs(energy0) > 0) || !std::isfinite(energy0)) {
    throw InputError(file, "integrator.method",
                     "method = \"auto\" meets a relative energy error, but the scene's energy is " +
                         format_number(energy0) + "; choose a method and dt");
  }
  const double tau = dynamical_time(nve, t_end);
  const double span = t_end > 0 ? t_end : 1.0;
  // Each pilot run: 20 dynamical times (a few orbits: the energy error of a symplectic method
  // oscillates with them, with its peaks at the closest approaches, and does not grow) or 1% of
  // the run if longer; the whole run if it is shorter than 40 dynamical times (a close approach
  // late in a short run would otherwise go unseen).
  const double pilot_t = span <= 40 * tau ? span : std::min(span, std::max(span / 100, 20 * tau));
  choice.pilot_t_end = pilot_t;
  Pilot pilot{nve, pilot_t, energy0};
  const double aim = aim_fraction * tol;
  const double start = std::isfinite(tau) ? tau / 8 : pilot_t / 16;

  // H^n: the geodesic methods only near the origin (their embedding coordinates lose digits
  // like eps e^{2r/R}: 1e-13 at 3 radii).
  bool geodesic_ok = scene.space.kind != SpaceKind::euclidean;
  if (scene.space.kind == SpaceKind::hyperbolic) {
    for (const Body& b : scene.bodies) geodesic_ok = geodesic_ok && b.q[0] <= 3.0;
  }

  // First pilot of each candidate: from `start`, a step whose error is above round-off and
  // below too_large_error; the step for the aim from the method's order.
  double best = inf;
  static constexpr std::array thermostat_candidates{std::string_view{"sesi2"}};
  for (std::string_view name : thermostat ? std::span<const std::string_view>(thermostat_candidates)
                                          : std::span<const std::string_view>(candidate_names)) {
    if (is_embedded_method(name) && !geodesic_ok) continue;
    // A topology: the plain compositions only (check_topology_method; the bodies are reduced into
    // the domain between steps, which a processed kernel or an embedding state does not allow).
    if (scene.space.has_topology() && !is_composition_method(name)) continue;
    const MethodInfo& info = *find_method_info(name);
    AutoCandidate c;
    c.method = std::string(name);
    c.cost = inf;
    double h = start;
    for (int tries = 0; tries < 10; ++tries) {
      const double e = pilot.error(name, h);
      if (!(e <= too_large_error)) {
        if (c.pilot_dt > 0) break;  // grown past round-off into too large: keep the last
        h /= 4;
        continue;
      }
      c.pilot_dt = h;
      c.pilot_error = e;
      if (e < roundoff_error && h < pilot_t / 4) {
        h *= 4;
        continue;
      }
      break;
    }
    if (c.pilot_dt > 0) {
      const double e = std::max(c.pilot_error, roundoff_error);
      c.dt = std::min(c.pilot_dt * std::pow(aim / e, 1.0 / info.order), span);
      c.cost = run_cost(scene, info, span, c.dt);
      best = std::min(best, c.cost);
    } else {
      c.pilot_error = inf;
    }
    choice.candidates.push_back(c);
  }
  // Second pilot of the promising ones at their predicted step; the order between the two
  // pilots (within a factor 1.5 of the method's) corrects the step, by at most 4x either way.
  std::vector<AutoCandidate*> order;
  for (AutoCandidate& c : choice.candidates) {
    if (c.cost <= prune_factor * best) order.push_back(&c);
  }
  std::stable_sort(order.begin(), order.end(), [](const AutoCandidate* a, const AutoCandidate* b) { return a->cost < b->cost; });
  if (order.size() > refined_count) order.resize(refined_count);
  for (AutoCandidate* cp : order) {
    AutoCandidate& c = *cp;
    const MethodInfo& info = *find_method_info(c.method);
    const double e2 = pilot.error(c.method, c.dt);
    c.refined = true;
    if (!(e2 <= too_large_error)) {
      c.cost = inf;
      c.pilot_dt = c.dt;
      c.pilot_error = e2;
      continue;
    }
    double order = info.order;
    const double ratio = c.pilot_dt / c.dt;
    if (std::abs(std::log(ratio)) > std::log(1.2) && c.pilot_error > roundoff_error && e2 > roundoff_error) {
      order = std::clamp(std::log(c.pilot_error / e2) / std::log(ratio), info.order / 1.5, info.order * 1.5);
    }
    const double factor = e2 > roundoff_error ? std::clamp(std::pow(aim / e2, 1.0 / order), 0.25, 4.0) : 1.0;
    c.pilot_dt = c.dt;
    c.pilot_error = e2;
    c.dt = std::min(c.dt * factor, span);
    c.cost = run_cost(scene, info, span, c.dt);
  }
  const AutoCandidate* pick = nullptr;
  for (const AutoCandidate& c : choice.candidates) {
    if (c.refined && c.cost < inf && (!pick || c.cost < pick->cost)) pick = &c;
  }
  choice.pilot_steps = pilot.steps;
  choice.pilot_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  if (!pick) {
    throw InputError(file, "integrator.tolerance",
                     "method = \"auto\": no method met a relative energy error of " + format_number(tol) +
                         " in pilot runs of " + format_number(pilot_t) + " time units; choose a method and dt");
  }
  const MethodInfo& info = *find_method_info(pick->method);

  // The step: at most the chosen one, a whole number of steps to t_end. With a given dt the
  // output interval (output_every * dt) is kept to the nearest whole number of steps (every
  // step if it is shorter than one): rounding the step to the interval instead could double the
  // cost.
  double dt = pick->dt;
  if (t_end > 0) dt = t_end / std::ceil(t_end / dt - 1e-9);
  choice.predicted_error = pick->pilot_error > roundoff_error
                               ? pick->pilot_error * std::pow(dt / pick->pilot_dt, info.order)
                               : pick->pilot_error;
  const double cost = run_cost(scene, info, span, dt);
  if (in.dt) {
    const double interval = std::abs(*in.dt) * static_cast<double>(in.output_every);
    in.output_every = std::max(1L, std::lround(interval / dt));
  }
  if (thermostat) {
    choice.reason = pick->method + " at dt " + format_number(dt) + ": a " + scene.thermostat->kind +
                    " thermostat runs with sesi2 only (its stages sit in the kick-drift-kick Strang step); the step "
                    "keeps sesi2's relative energy error, in pilot runs of the scene without its thermostat, near " +
                    format_number(aim) + " (" + format_number(aim_fraction) + " x the tolerance) over " +
                    format_number(pilot_t) + " time units; predicted cost " + format_number(std::round(cost)) +
                    " force evaluations";
  } else {
    choice.reason = pick->method + " at dt " + format_number(dt) + ": of " + std::to_string(choice.candidates.size()) +
                    " methods, the cheapest to keep the relative energy error near " + format_number(aim) + " (" +
                    format_number(aim_fraction) + " x the tolerance) in pilot runs of " + format_number(pilot_t) +
                    " time units; predicted cost " + format_number(std::round(cost)) +
                    " force evaluations (a geodesic one counted " + format_number(geodesic_stage_cost) + ")";
  }
  in.method = pick->method;
  in.dt = in.dt && *in.dt < 0 ? -dt : dt;  // a negative given step: backwards, as asked
  in.auto_choice = std::move(choice);
}

}  // namespace sesi::program
