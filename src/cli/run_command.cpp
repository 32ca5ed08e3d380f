#include "run_command.hpp"

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#if defined(__GLIBC__)
#include <malloc.h>
#endif

#include <sesi/parallel.hpp>

#include "auto_method.hpp"
#include "checkpoint.hpp"
#include "domain_integrator.hpp"
#include "errors.hpp"
#include "integrator.hpp"
#include "output_dir.hpp"
#include "paper_scene.hpp"
#include "progress.hpp"
#include "ranks.hpp"
#include "recorder.hpp"
#include "run_loop.hpp"
#include "scene_reader.hpp"
#include "signals.hpp"
#include "validate.hpp"

namespace sesi::program {

namespace {

/// Command-line values replace the scene's, checked by the same rules.
void apply_overrides(Scene& scene, const RunOptions& options) {
  const Origin option{};
  IntegratorSpec& in = scene.integrator;
  if (options.method) {
    check_method_or_auto(*options.method, option, "--method");
    in.method = *options.method;
  }
  if (options.tolerance) {  // --tolerance alone means --method auto
    check_tolerance(*options.tolerance, option, "--tolerance");
    if (options.method && *options.method != "auto") {
      throw InputError(option, "--tolerance", "only with --method auto (the method and step are then chosen "
                                              "to meet it), not with --method " + *options.method);
    }
    in.method = "auto";
    in.tolerance = options.tolerance;
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
  if (options.checkpoint_every) {
    check_checkpoint_every(*options.checkpoint_every, option, "--checkpoint-every");
    in.checkpoint_every = *options.checkpoint_every;
  }
  if (options.neighbour_skin) {
    check_neighbour_skin(*options.neighbour_skin, option, "--neighbour-skin");
    in.neighbour_skin = *options.neighbour_skin;
  }
  if (options.trajectory_format) {
    in.trajectory_format = parse_trajectory_format(*options.trajectory_format, option, "--trajectory-format");
  }
  const Origin file{scene.source, in.line};
  // The thermostat: --temperature and --seed change the scene's [thermostat]; none is added (a
  // thermostat and its friction or relaxation time are the user's choice, as in LAMMPS's fixes).
  if (options.temperature || options.seed) {
    const std::string_view flag = options.temperature ? "--temperature" : "--seed";
    if (!scene.thermostat) {
      throw InputError(option, flag,
                       "the scene has no [thermostat] table; add one to choose the thermostat and its friction or "
                       "relaxation time (e.g. kind = \"langevin\", temperature = 1.0, gamma = 1.0; "
                       "docs/scene-format.md)");
    }
  }
  if (options.temperature) {
    check_temperature(*options.temperature, scene.thermostat->kind, option, "--temperature");
    scene.thermostat->schedule = {{0.0, *options.temperature}};
  }
  if (options.seed) {
    // Read here, not by the argument parser, which wraps integers past 2^64 around.
    long long seed = -1;
    const std::string& text = *options.seed;
    const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), seed);
    if (error != std::errc() || end != text.data() + text.size()) {
      throw InputError(option, "--seed", "expected an integer from 0 to 2^63 - 1 (the noise's key), got '" +
                                             cut_input(text) + "'");
    }
    check_seed(seed, option, "--seed");
    if (scene.thermostat->kind == "nose-hoover") {
      throw InputError(option, "--seed", "a nose-hoover thermostat is deterministic: it has no noise to seed");
    }
    scene.thermostat->seed = static_cast<std::uint64_t>(seed);
  }
  const bool method_flag = options.method || options.tolerance;  // --tolerance means --method auto
  check_thermostat_method(scene, method_flag ? option : file,
                          options.method ? "--method" : options.tolerance ? "--tolerance" : "integrator.method");
  check_topology_method(scene, options.method ? option : file, options.method ? "--method" : "integrator.method");
  if (in.method == "auto") {
    if (!in.tolerance) {
      throw InputError(file, "integrator.tolerance",
                       "method \"auto\" needs a tolerance, the target max relative energy error (give it in "
                       "[integrator] or with --tolerance)");
    }
  } else if (in.tolerance) {
    throw InputError(file, "integrator.tolerance",
                     "only with method = \"auto\" (the method and step are then chosen to meet it); the "
                     "method is " + in.method);
  }
  if (!in.dt && in.method != "auto") {
    throw InputError(file, "integrator.dt", "missing required key (give it in [integrator] or with --dt)");
  }
  if (!in.t_end) {
    throw InputError(file, "integrator.t_end", "missing required key (give it in [integrator] or with --t-end)");
  }
  if (in.dt) {
    check_step_count(*in.t_end, *in.dt, options.dt || options.t_end ? option : file,
                     options.dt || options.t_end ? "--dt/--t-end" : "integrator");
  }
  resolve_auto(scene);  // method auto: pilot runs, then the method and step (nothing written)
  check_step_count(*in.t_end, *in.dt, file, "integrator");
}

std::string describe_space(const SpaceSpec& space) {
  static const char* const symbols[] = {"S", "H", "E"};
  return std::string(space_name(space.kind)) + " " + symbols[static_cast<int>(space.kind)] + "^" +
         std::to_string(space.dim);
}

/// "langevin, kT = 1, gamma = 0.5, seed 3" or "nose-hoover, kT from 2 (t = 0) to 0.5 (t = 10) in 3
/// knots, tau = 1, chain 3".
std::string describe_thermostat(const ThermostatSpec& th) {
  std::string text = th.kind + ", kT ";
  if (th.schedule.size() == 1) {
    text += "= " + format_number(th.schedule.front().second);
  } else {
    text += "from " + format_number(th.schedule.front().second) + " (t = " + format_number(th.schedule.front().first) +
            ") to " + format_number(th.schedule.back().second) + " (t = " + format_number(th.schedule.back().first) +
            ") in " + std::to_string(th.schedule.size()) + " knots";
  }
  const auto keys = thermostat_keys(th.kind);
  const auto takes = [&](std::string_view key) { return std::find(keys.begin(), keys.end(), key) != keys.end(); };
  if (takes("gamma")) text += ", gamma = " + format_number(th.gamma);
  if (takes("tau")) text += ", tau = " + format_number(th.tau);
  if (takes("chain")) text += ", chain " + std::to_string(th.chain);
  if (takes("seed")) text += ", seed " + std::to_string(th.seed);
  return text;
}

void print_report(const Scene& scene, const Recorder& recorder, const RunOutcome& outcome, double wall,
                  const std::filesystem::path& dir, int ranks) {
  const InvariantStats& inv = recorder.invariants();
  const std::string across = ranks > 1 ? " on " + std::to_string(ranks) + " ranks" : std::string();
  std::printf("%s: %s, %d bodies, method %s, dt = %s, %ld steps to t = %s in %.3f s%s\n", scene.name.c_str(),
              describe_space(scene.space).c_str(), scene.body_count(), scene.integrator.method.c_str(),
              format_number(*scene.integrator.dt).c_str(), outcome.steps_done,
              format_number(*scene.integrator.t_end).c_str(), wall, across.c_str());
  if (const auto& a = scene.integrator.auto_choice) {
    std::printf("  method auto (tolerance %s): %s\n", format_number(a->tolerance).c_str(), a->reason.c_str());
  }
  if (const auto& th = scene.thermostat) std::printf("  thermostat %s\n", describe_thermostat(*th).c_str());
  if (scene.thermostat) {
    // A thermostat changes the energy on purpose: its error is that of the conserved quantity.
    std::printf("  energy %.17g -> %.17g, heat from the thermostat %.6g\n", inv.energy_initial, inv.energy_final,
                inv.heat);
    if (inv.thermostat_rows > 0) {
      std::printf("  mean kinetic temperature %.6g, configurational %.6g (over %ld rows)\n",
                  inv.sum_kinetic_temperature / static_cast<double>(inv.thermostat_rows),
                  inv.sum_grad_squared / inv.sum_laplacian, inv.thermostat_rows);
    }
    if (std::isfinite(inv.conserved_initial)) {
      std::printf("  conserved quantity (energy + the thermostat's offset): max |drift| %.3e\n",
                  inv.max_abs_conserved_drift);
    } else {
      std::printf("  conserved quantity: none (brownian dynamics)\n");
    }
  } else {
    std::printf("  energy %.17g, max |error| %.3e (relative %.3e)\n", inv.energy_initial,
                inv.max_abs_energy_error, inv.max_rel_energy_error);
  }
  std::printf("  momentum map: max |drift| %.3e\n", inv.max_momentum_drift);
  const std::vector<double> exact = recorder.max_exact_error();
  for (std::size_t b = 0; b < exact.size(); ++b) {
    std::printf("  body %zu: max distance from the exact solution %.3e\n", b + 1, exact[b]);
  }
  std::printf("  outputs in %s\n", dir.string().c_str());
  std::fflush(stdout);
}


/// profile.csv (docs/benchmarks.md, "Profile of a step"): per phase a row of totals (thread
/// "all") and a row per thread of its busy time in sesi::parallel's loops, then the same for the
/// whole step (phase "step"); '#' lines first say what each column means.
std::string profile_csv(const sesi::profile::Report& r, const Scene& scene) {
  using sesi::profile::Phase;
  std::string text;
  char line[512];
  const auto add = [&](const char* format, auto... values) {
    std::snprintf(line, sizeof line, format, values...);
    text += line;
  };
  add("# sesi profile of a run's steps (sesi run --profile): scene %s, %d bodies, %d threads, %ld steps\n",
      scene.name.c_str(), scene.body_count(), r.threads, r.steps);
  text +=
      "# phase: a part of the step; other = step time inside no other phase; step = the whole window (the "
      "steps, from the first to the last; a resumed run's own steps only)\n"
      "# thread: all = the phase's totals; 0..T-1 = that thread's part (0 the thread that runs the steps)\n"
      "# calls: times the phase was entered (thread all; steps for phase step), chunks of parallel loops run "
      "(thread k)\n"
      "# wall_seconds: wall time in the phase on the stepping thread, inner phases excluded (they add up to "
      "step)\n"
      "# loop_seconds: wall time of the sesi::parallel loops inside it (on the stepping thread)\n"
      "# busy_seconds: time threads spent running those loops' chunks (thread all: summed over threads)\n"
      "# serial_seconds: wall_seconds - loop_seconds, the work no other thread can share (Amdahl's serial part)\n"
      "# share: wall_seconds / the step's wall_seconds\n";
  const double serial = r.serial();
  add("# serial fraction: %.6f (serial_seconds / wall_seconds of phase step)\n", r.serial_fraction());
  text += "phase,thread,calls,wall_seconds,loop_seconds,busy_seconds,serial_seconds,share\n";
  double loops = 0.0;
  std::vector<double> busy(static_cast<std::size_t>(r.threads), 0.0);
  std::vector<long long> chunks(static_cast<std::size_t>(r.threads), 0);
  for (int k = 0; k < sesi::profile::phase_count; ++k) {
    const sesi::profile::PhaseTotals& p = r.phases[k];
    double all = 0.0;
    for (int t = 0; t < r.threads; ++t) {
      all += p.busy[t];
      busy[t] += p.busy[t];
      chunks[t] += p.chunks[t];
    }
    loops += p.loop_wall;
    add("%s,all,%lld,%.9f,%.9f,%.9f,%.9f,%.6f\n", sesi::profile::name(static_cast<Phase>(k)), p.calls, p.wall,
        p.loop_wall, all, p.serial, r.wall > 0 ? p.wall / r.wall : 0.0);
    for (int t = 0; t < r.threads; ++t) {
      add("%s,%d,%lld,,,%.9f,,\n", sesi::profile::name(static_cast<Phase>(k)), t, p.chunks[t], p.busy[t]);
    }
  }
  double all = 0.0;
  for (const double b : busy) all += b;
  add("step,all,%ld,%.9f,%.9f,%.9f,%.9f,%.6f\n", r.steps, r.wall, loops, all, serial, r.wall > 0 ? 1.0 : 0.0);
  for (int t = 0; t < r.threads; ++t) add("step,%d,%lld,,,%.9f,,\n", t, chunks[t], busy[t]);
  return text;
}

/// The profile's short table on stderr: the phases that took time, and the serial fraction.
void print_profile(const sesi::profile::Report& r, const Scene& scene, const std::filesystem::path& csv) {
  using sesi::profile::Phase;
  std::fprintf(stderr, "sesi: profile of %ld steps, %d bodies, %d threads (%s):\n", r.steps, scene.body_count(),
               r.threads, csv.string().c_str());
  std::fprintf(stderr, "  %-11s %12s %8s %12s\n", "phase", "wall s", "% step", "serial s");
  for (int k = 0; k < sesi::profile::phase_count; ++k) {
    const sesi::profile::PhaseTotals& p = r.phases[k];
    if (p.wall <= 0.0) continue;
    std::fprintf(stderr, "  %-11s %12.6f %7.2f%% %12.6f\n", sesi::profile::name(static_cast<Phase>(k)), p.wall,
                 r.wall > 0 ? 100.0 * p.wall / r.wall : 0.0, p.serial);
  }
  std::fprintf(stderr, "  %-11s %12.6f %7.2f%% %12.6f\n", "step", r.wall, r.wall > 0 ? 100.0 : 0.0, r.serial());
  std::fprintf(stderr, "  serial fraction %.2f%% (time outside parallel loops / step time)\n",
               100.0 * r.serial_fraction());
}

/// The sink of the ranks but rank 0 of a run across ranks: rank 0 writes the outputs, and these
/// ranks serve it their own bodies' columns of each row and of the final state as it writes them
/// (Snapshot::gather).
class ServingSink final : public RunSink {
 public:
  void track(double, const Eigen::VectorXd&) override {}
  void write_row(const Snapshot& s) override {
    if (s.gather) s.gather->serve(s);
  }
  void set_final(Snapshot last) override { final_ = std::move(last); }
  /// While rank 0 writes the summary (Recorder::finish, or release_final where it is not reached).
  void serve_final() const {
    if (final_.gather) final_.gather->serve(final_);
  }

 private:
  Snapshot final_;
};

/// Refuse to run when a launcher started this process as one of several but MPI is not in use
/// (a sesi built without MPI, or srun without --mpi=pmix): each would run the whole scene.
void refuse_without_mpi(const Ranks& ranks, std::string_view command) {
  const long launched = Ranks::launched_processes();
  if (ranks.distributed() || launched <= 1) return;
  throw InputError(Origin{}, command,
                   "started as one of " + std::to_string(launched) +
                       " processes (mpirun, srun) without MPI in use (a sesi built without MPI: SESI_BUILD_MPI, "
                       "libopenmpi-dev; or srun without --mpi=pmix), so each would run the whole scene; start one "
                       "process, or use an MPI build");
}

/// Across ranks, the end of a phase before any step: status is this rank's (exit_ok: it went
/// well) and message its error. Every rank learns every rank's status; the first rank that
/// failed prints its message (rank 0 when it failed: a scene's errors are the same on every rank,
/// and only rank 0 touches the output directory), and every rank returns that rank's status, so
/// that all exit alike; exit_ok when none failed.
int settle(const Ranks& ranks, int status, const std::string& message) {
  std::vector<double> all;
  std::vector<int> counts;
  ranks.all_gather({static_cast<double>(status)}, all, counts);
  for (std::size_t r = 0; r < all.size(); ++r) {
    if (static_cast<int>(all[r]) == exit_ok) continue;
    if (static_cast<int>(r) == ranks.rank()) print_error(message);
    return static_cast<int>(all[r]);
  }
  return exit_ok;
}

/// A phase before any step, run on every rank: exit_ok, or the status every rank stops with
/// (settle). In one process its errors go to main as before (InputError: exit status 2).
template <class Phase>
int on_every_rank(const Ranks& ranks, Phase&& phase) {
  if (!ranks.distributed()) {
    phase();
    return exit_ok;
  }
  int status = exit_ok;
  std::string message;
  try {
    phase();
  } catch (const InputError& e) {
    status = exit_bad_input;
    message = e.what();
  } catch (const std::exception& e) {
    status = exit_internal;
    message = e.what();
  }
  return settle(ranks, status, message);
}

/// The run of scene into staging, from its start or from a checkpoint (in from_dir): outputs,
/// checkpoints, publishing and the closing report. Returns the exit status.
/// Across ranks (docs/parallel.md) every rank calls it: rank 0 with the staging directory, the
/// others with none; rank 0 writes the outputs and reports, the others keep nothing, and all
/// return rank 0's status.
int execute(const Ranks& ranks, Scene& scene, StagingDir* staging, bool quiet, bool profile,
            const Checkpoint* from = nullptr, const std::filesystem::path& from_dir = {}) {
  const bool root = ranks.root();
  const bool euclidean = scene.space.kind == SpaceKind::euclidean;
  const int ambient = euclidean ? scene.dim() : scene.dim() + 1;
  const long steps = step_count(*scene.integrator.t_end, *scene.integrator.dt);
  std::optional<Recorder> recorder;
  std::optional<ProgressBar> progress;
  // The outputs (rank 0's): a resumed run's fail here when they are not what the checkpoint says.
  if (const int status = on_every_rank(ranks, [&] {
        if (!root) return;
        if (from) {
          recorder.emplace(scene, staging->path(), momentum_names(ambient, euclidean), *from, from_dir);
        } else {
          recorder.emplace(scene, staging->path(), momentum_names(ambient, euclidean));
        }
        progress.emplace(steps, *scene.integrator.t_end, ProgressBar::wanted(quiet));
      });
      status != exit_ok) {
    return status;
  }

  // --threads: per rank.
  sesi::parallel::set_threads(scene.integrator.threads);
  std::unique_ptr<Integrator> integrator;
  // A scene or method that a run across ranks does not support yet is refused here (InputError).
  if (const int status = on_every_rank(ranks, [&] {
        integrator = ranks.distributed() ? make_domain_integrator(scene, ranks) : make_integrator(scene);
        if (from) integrator->restore(from->state);  // every rank the whole state
      });
      status != exit_ok) {
    return status;
  }
  // The integrator holds the state now: the scene's initial conditions are not read again (its
  // masses are), and at 10^6 bodies they are two small allocations a body (~64 MB). glibc keeps
  // freed small blocks in the process (the integrator's large arrays are mapped apart): handed
  // back to the system here (27 MB less at the peak of a rank of a 10^6-body run on 2 ranks).
  for (Body& b : scene.bodies) {
    b.q.resize(0);
    b.p.resize(0);
  }
#if defined(__GLIBC__)
  malloc_trim(0);
#endif
  long checkpoint_step = -1;  // the last checkpoint written by this run
  const auto checkpoint = [&](const Checkpoint& c) {
    // Rank 0 writes it; the other ranks take it (the integrator's framed_state is a collective
    // call) and keep nothing.
    if (!root) return;
    write_checkpoint(c, staging->path(), staging->target());
    checkpoint_step = c.step;
  };
  ServingSink serving;
  RunSink& sink = recorder ? static_cast<RunSink&>(*recorder) : serving;
  RunControl control;
  control.interrupted = &signals::stop_requested();
  control.progress = progress ? &*progress : nullptr;
  control.checkpoint = checkpoint;
  control.profile = profile;
  if (ranks.distributed()) {
    control.agree = [&ranks](bool verdict) { return ranks.from_root(verdict); };
    control.any = [&ranks](bool value) { return ranks.any(value); };
  }
  const auto start = std::chrono::steady_clock::now();
  RunOutcome outcome;
  if (!ranks.distributed()) {
    outcome = run_loop(scene, *integrator, sink, control, from);
  } else {
    try {
      outcome = run_loop(scene, *integrator, sink, control, from);
    } catch (const InputError& e) {
      // Before any step (the initial energy is not finite): the same on every rank.
      return settle(ranks, exit_bad_input, e.what());
    } catch (const std::exception& e) {
      // One rank's failure that the others cannot see (rank 0's outputs cannot be written): the
      // others wait in a collective call, so all end now; the last checkpoint stays.
      print_error((root ? std::string() : "rank " + std::to_string(ranks.rank()) + ": ") + e.what());
      ranks.abort(exit_internal);
    }
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  // Rank 0: the checkpoint kept, the summary, publishing and the closing report.
  const auto finish = [&]() -> int {
    // A resumed run that took no checkpoint of its own (one resumed at its end, or stopped before
    // its next) keeps the one it went on from, with the settings now in force: the outputs never
    // lose their checkpoint.
    if (from && checkpoint_step < 0) checkpoint(*from);
    progress->finish();
    recorder->finish(outcome, wall, ranks.size());
    // profile.csv: rank 0's steps.
    if (outcome.profile) {
      write_file_atomically(staging->path() / "profile.csv", profile_csv(*outcome.profile, scene));
    }
    const std::filesystem::path dir = staging->publish(outcome.complete());
    if (outcome.profile) print_profile(*outcome.profile, scene, dir / "profile.csv");

    // A stopped run's checkpoint is at the step it stopped after (run_loop): one step number.
    const std::string kept =
        checkpoint_step < 0 ? std::string()
        : checkpoint_step == outcome.steps_done
            ? "; resume from its checkpoint there with: sesi resume " + dir.string()
            : "; resume from its checkpoint (step " + std::to_string(checkpoint_step) + ") with: sesi resume " +
                  dir.string();
    // (A thermostat changes the energy on purpose: its tolerance bounded the pilots' NVE error.)
    if (const auto& a = scene.integrator.auto_choice;
        a && !scene.thermostat && recorder->invariants().max_rel_energy_error > 10 * a->tolerance) {
      std::fprintf(stderr,
                   "sesi: warning: %s: method auto: the run's max relative energy error %s is more than 10x the "
                   "tolerance %s (its pilot runs of %s time units did not meet what the run met); choose a smaller "
                   "tolerance, or a method and dt\n",
                   scene.name.c_str(), format_short(recorder->invariants().max_rel_energy_error).c_str(),
                   format_number(a->tolerance).c_str(), format_number(a->pilot_t_end).c_str());
    }
    switch (outcome.reason) {
      case StopReason::completed:
        if (!quiet) print_report(scene, *recorder, outcome, wall, dir, ranks.size());
        return exit_ok;
      case StopReason::interrupted:
        print_error(scene.name + ": interrupted after step " + std::to_string(outcome.steps_done) + " (t = " +
                    format_number(static_cast<double>(outcome.steps_done) * *scene.integrator.dt) +
                    "); the outputs so far are in " + dir.string() + ", marked incomplete" + kept);
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
                dir.string() + ", marked incomplete" +
                (checkpoint_step < 0 ? std::string()
                                     : ", with the last good checkpoint (step " + std::to_string(checkpoint_step) + ")"));
    return exit_run_failed;
  };
  if (!root) {
    serving.serve_final();
    return static_cast<int>(ranks.from_root(static_cast<long>(exit_ok)));
  }
  if (!ranks.distributed()) return finish();
  // Across ranks every rank exits with rank 0's status, even after an error here.
  int status = exit_internal;
  try {
    status = finish();
  } catch (const InputError& e) {
    print_error(e.what());
    status = exit_bad_input;
  } catch (const std::exception& e) {
    print_error(e.what());
    status = exit_internal;
  }
  recorder->release_final();  // (where finish() failed before the summary)
  return static_cast<int>(ranks.from_root(static_cast<long>(status)));
}

/// Where a checkpoint in source goes on to: a stopped run's own directory; for "DIR.incomplete"
/// (a stopped re-run that left DIR's complete outputs alone) and for a killed run's staging
/// directory ".DIR.sesi-XXXXXX", DIR.
std::filesystem::path resume_target(const std::filesystem::path& source) {
  const std::string name = source.filename().string();
  // DIR.incomplete, or DIR.incomplete-N when that held a complete run (output_dir.hpp).
  static constexpr std::string_view incomplete = ".incomplete";
  if (const std::size_t at = name.rfind(incomplete); at != std::string::npos && at > 0) {
    const std::string_view rest = std::string_view(name).substr(at + incomplete.size());
    if (rest.empty() || (rest.size() > 1 && rest[0] == '-' &&
                         rest.find_first_not_of("0123456789", 1) == std::string_view::npos)) {
      return source.parent_path() / name.substr(0, at);
    }
  }
  static constexpr std::string_view staging = ".sesi-";
  // A killed run's staging directory inside a mount point DIR: DIR/.sesi-XXXXXX (output_dir.hpp).
  if (name.size() == staging.size() + 6 && name.starts_with(staging)) return source.parent_path();
  const std::size_t at = name.rfind(staging);
  if (name.size() > 1 && name.front() == '.' && at != std::string::npos && at > 1 &&
      name.size() - at - staging.size() == 6) {
    return source.parent_path() / name.substr(1, at - 1);
  }
  return source;
}

/// The directory whose checkpoint `sesi resume DIR` goes on from: DIR itself, else the staging
/// directory of a killed run into DIR that holds the checkpoint with the latest step.
std::filesystem::path checkpoint_source(const std::filesystem::path& dir) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (fs::exists(dir / checkpoint_file_name, ec)) return dir;
  fs::path parent = dir.parent_path();
  if (parent.empty()) parent = ".";
  fs::path best;
  long best_step = -1;
  // Beside DIR (".DIR.sesi-XXXXXX"), or inside it when it is a mount point (".sesi-XXXXXX").
  for (const auto& [where, prefix] : {std::pair{parent, "." + dir.filename().string() + ".sesi-"},
                                      std::pair{dir, std::string(".sesi-")}}) {
    for (const fs::directory_entry& entry : fs::directory_iterator(where, ec)) {
      const std::string name = entry.path().filename().string();
      if (!name.starts_with(prefix) || !fs::exists(entry.path() / checkpoint_file_name, ec)) continue;
      try {
        const long step = read_checkpoint(entry.path() / checkpoint_file_name).step;
        if (step > best_step) {
          best_step = step;
          best = entry.path();
        }
      } catch (const InputError&) {
        // not a usable checkpoint: the directory is left as it is
      }
    }
  }
  return best.empty() ? dir : best;
}

}  // namespace

int run_command(const RunOptions& options) {
  // Across MPI ranks (`mpirun -np K sesi run`, docs/parallel.md) every rank runs this: each reads
  // and checks the scene itself; rank 0 alone touches the output directory.
  Ranks ranks = Ranks::start();
  refuse_without_mpi(ranks, "run");
  std::optional<Scene> scene;
  if (const int status = on_every_rank(ranks, [&] {
        if (options.out_given && options.out.empty()) {  // not the default, ./sesi-out/<scene name>
          throw InputError(Origin{}, "--out", "expected a directory, got an empty path");
        }
        scene = options.scene_path.empty() ? paper_scene() : read_scene_file(options.scene_path);
        apply_overrides(*scene, options);
      });
      status != exit_ok) {
    return status;
  }
  const std::filesystem::path target =
      options.out.empty() ? std::filesystem::path("sesi-out") / scene->name : std::filesystem::path(options.out);
  signals::begin_run();  // from here a signal stops the run between steps, with a checkpoint
  std::optional<StagingDir> staging;
  if (const int status = on_every_rank(ranks, [&] {
        if (ranks.root()) staging.emplace(target, options.out.empty() ? "output directory" : "--out");
      });
      status != exit_ok) {
    return status;
  }
  return execute(ranks, *scene, staging ? &*staging : nullptr, options.quiet, options.profile);
}

int resume_command(const ResumeOptions& options) {
  Ranks ranks = Ranks::start();  // as in run_command: every rank reads the checkpoint itself
  refuse_without_mpi(ranks, "resume");
  std::filesystem::path source;
  std::optional<Checkpoint> checkpoint;
  if (const int status = on_every_rank(ranks, [&] {
        source = checkpoint_source(options.dir);
        checkpoint = read_checkpoint(source / checkpoint_file_name);
        Scene& scene = checkpoint->scene;
        const Origin option{};
        check_method(scene.integrator.method, Origin{(source / checkpoint_file_name).string()}, "method");
        if (options.t_end) {
          check_t_end(*options.t_end, option, "--t-end");
          check_step_count(*options.t_end, *scene.integrator.dt, option, "--dt/--t-end");
          scene.integrator.t_end = options.t_end;
        }
        const long steps = step_count(*scene.integrator.t_end, *scene.integrator.dt);
        if (steps < checkpoint->step) {
          throw InputError(option, options.t_end ? "--t-end" : "t_end",
                           "the checkpoint is at step " + std::to_string(checkpoint->step) + " (t = " +
                               format_number(static_cast<double>(checkpoint->step) * *scene.integrator.dt) +
                               "), after the end of the run (" + std::to_string(steps) + " steps)");
        }
        if (options.threads) {
          check_threads(*options.threads, option, "--threads");
          scene.integrator.threads = static_cast<int>(*options.threads);
        }
      });
      status != exit_ok) {
    return status;
  }
  Scene& scene = checkpoint->scene;
  signals::begin_run();
  const std::filesystem::path target = resume_target(source);
  std::optional<StagingDir> staging;
  if (const int status = on_every_rank(ranks, [&] {
        if (!ranks.root()) return;
        const bool beside = source.parent_path() == target.parent_path() || source.parent_path() == target;
        staging.emplace(target, "sesi resume", beside ? source : std::filesystem::path());
      });
      status != exit_ok) {
    return status;
  }
  const int status =
      execute(ranks, scene, staging ? &*staging : nullptr, options.quiet, options.profile, &*checkpoint, source);
  // A killed run's staging directory or DIR.incomplete, now gone on from into DIR.
  if (ranks.root() && status == exit_ok && source != staging->target()) remove_superseded(source);
  return status;
}

}  // namespace sesi::program
