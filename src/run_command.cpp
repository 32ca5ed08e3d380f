#include "run_command.hpp"

#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>

#include <sesi/parallel.hpp>

#include "errors.hpp"
#include "integrator.hpp"
#include "output_dir.hpp"
#include "paper_scene.hpp"
#include "progress.hpp"
#include "recorder.hpp"
#include "run_loop.hpp"
#include "scene_reader.hpp"
#include "validate.hpp"

namespace sesi::program {

namespace {

std::atomic<bool> interrupted{false};
static_assert(std::atomic<bool>::is_always_lock_free, "the signal handler needs a lock-free flag");

extern "C" void on_signal(int) { interrupted.store(true, std::memory_order_relaxed); }

/// SIGINT and SIGTERM stop the run between steps while this lives.
class SignalGuard {
 public:
  SignalGuard() {
    struct sigaction action {};
    action.sa_handler = on_signal;
    sigemptyset(&action.sa_mask);
    sigaction(SIGINT, &action, &old_int_);
    sigaction(SIGTERM, &action, &old_term_);
  }
  ~SignalGuard() {
    sigaction(SIGINT, &old_int_, nullptr);
    sigaction(SIGTERM, &old_term_, nullptr);
  }
  SignalGuard(const SignalGuard&) = delete;
  SignalGuard& operator=(const SignalGuard&) = delete;

 private:
  struct sigaction old_int_ {}, old_term_ {};
};

/// Command-line values replace the scene's, checked by the same rules.
void apply_overrides(Scene& scene, const RunOptions& options) {
  const Origin option{};
  IntegratorSpec& in = scene.integrator;
  if (options.method) {
    check_method(*options.method, option, "--method");
    in.method = *options.method;
  }
  if (options.dt) {
    check_dt(*options.dt, option, "--dt");
    in.dt = options.dt;
  }
  if (options.t_end) {
    check_t_end(*options.t_end, option, "--t-end");
    in.t_end = options.t_end;
  }
  if (options.output_every) {
    check_output_every(*options.output_every, option, "--output-every");
    in.output_every = *options.output_every;
  }
  if (options.threads) {
    check_threads(*options.threads, option, "--threads");
    in.threads = static_cast<int>(*options.threads);
  }
  if (options.check_every) {
    check_check_every(*options.check_every, option, "--check-every");
    in.check_every = *options.check_every;
  }
  if (options.neighbour_skin) {
    check_neighbour_skin(*options.neighbour_skin, option, "--neighbour-skin");
    in.neighbour_skin = *options.neighbour_skin;
  }
  if (options.trajectory_format) {
    in.trajectory_format = parse_trajectory_format(*options.trajectory_format, option, "--trajectory-format");
  }
  const Origin file{scene.source, in.line};
  if (!in.dt) throw InputError(file, "integrator.dt", "missing required key (give it in [integrator] or with --dt)");
  if (!in.t_end) {
    throw InputError(file, "integrator.t_end", "missing required key (give it in [integrator] or with --t-end)");
  }
  check_step_count(*in.t_end, *in.dt, options.dt || options.t_end ? option : file,
                   options.dt || options.t_end ? "--dt/--t-end" : "integrator");
}

std::string describe_space(const SpaceSpec& space) {
  static const char* const symbols[] = {"S", "H", "E"};
  return std::string(space_name(space.kind)) + " " + symbols[static_cast<int>(space.kind)] + "^" +
         std::to_string(space.dim);
}

void print_report(const Scene& scene, const Recorder& recorder, const RunOutcome& outcome, double wall,
                  const std::filesystem::path& dir) {
  const InvariantStats& inv = recorder.invariants();
  std::printf("%s: %s, %d bodies, method %s, dt = %s, %ld steps to t = %s in %.3f s\n", scene.name.c_str(),
              describe_space(scene.space).c_str(), scene.body_count(), scene.integrator.method.c_str(),
              format_number(*scene.integrator.dt).c_str(), outcome.steps_done,
              format_number(*scene.integrator.t_end).c_str(), wall);
  std::printf("  energy %.17g, max |error| %.3e (relative %.3e)\n", inv.energy_initial,
              inv.max_abs_energy_error, inv.max_rel_energy_error);
  std::printf("  momentum map: max |drift| %.3e\n", inv.max_momentum_drift);
  const std::vector<double> exact = recorder.max_exact_error();
  for (std::size_t b = 0; b < exact.size(); ++b) {
    std::printf("  body %zu: max distance from the exact solution %.3e\n", b + 1, exact[b]);
  }
  std::printf("  outputs in %s\n", dir.string().c_str());
  std::fflush(stdout);
}

}  // namespace

int run_command(const RunOptions& options) {
  Scene scene = options.scene_path.empty() ? paper_scene() : read_scene_file(options.scene_path);
  apply_overrides(scene, options);
  const std::filesystem::path target =
      options.out.empty() ? std::filesystem::path("sesi-out") / scene.name : std::filesystem::path(options.out);
  StagingDir staging(target, options.out.empty() ? "output directory" : "--out");

  const bool euclidean = scene.space.kind == SpaceKind::euclidean;
  const int ambient = euclidean ? scene.dim() : scene.dim() + 1;
  Recorder recorder(scene, staging.path(), momentum_names(ambient, euclidean));
  const long steps = step_count(*scene.integrator.t_end, *scene.integrator.dt);
  ProgressBar progress(steps, *scene.integrator.t_end, ProgressBar::wanted(options.quiet));
  interrupted.store(false);
  const SignalGuard signals;

  sesi::parallel::set_threads(scene.integrator.threads);
  const auto integrator = make_integrator(scene);
  const auto start = std::chrono::steady_clock::now();
  const RunOutcome outcome = run_loop(scene, *integrator, recorder, RunControl{&interrupted, &progress, {}});
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  progress.finish();
  recorder.finish(outcome, wall);
  const std::filesystem::path dir = staging.publish(outcome.reason == StopReason::completed);

  switch (outcome.reason) {
    case StopReason::completed:
      if (!options.quiet) print_report(scene, recorder, outcome, wall, dir);
      return exit_ok;
    case StopReason::interrupted:
      print_error(scene.name + ": interrupted after step " + std::to_string(outcome.steps_done) +
                  "; the outputs so far are in " + dir.string() + ", marked incomplete");
      return exit_interrupted;
    case StopReason::non_finite:
    case StopReason::invariant_failed:
    case StopReason::energy_guard:
    case StopReason::close_encounter:
      break;
  }
  print_error(scene.name + ": " + outcome.detail + " at step " + std::to_string(outcome.failed_step) +
              " (t = " + format_number(outcome.failed_t) + ")" +
              (outcome.failed_body > 0 ? ", body " + std::to_string(outcome.failed_body) : std::string()) +
              "; last step known good: " + std::to_string(outcome.steps_done) + "; the outputs up to it are in " +
              dir.string() + ", marked incomplete");
  return exit_run_failed;
}

}  // namespace sesi::program
