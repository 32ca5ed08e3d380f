// sesi: the command-line program (docs/scene-format.md). Arguments here; `run` in run_command.cpp.
#include <cstdio>
#include <exception>
#include <string>

#include <CLI/CLI.hpp>

#include "analyze_command.hpp"
#include "bench_command.hpp"
#include "errors.hpp"
#include "method_list.hpp"
#include "methods.hpp"
#include "run_command.hpp"
#include "signals.hpp"
#include "sweep_command.hpp"
#include "view_command.hpp"

namespace {

using namespace sesi::program;

std::string run_footer() {
  std::string text =
      "\nMETHODS (--method, [integrator] method; machine-readable: sesi run --list-methods [--json]):\n";
  for (const MethodInfo& m : method_catalogue()) {
    char line[160];
    std::snprintf(line, sizeof line, "  %-18s order %-2d  %.*s\n", std::string(m.name).c_str(), m.order,
                  static_cast<int>(m.about.size()), m.about.data());
    text += line;
  }
  text +=
      "  auto               with tolerance (--tolerance): the method and step from pilot runs of the\n"
      "                     scene and the bench's cost model, for a target max relative energy\n"
      "                     error; summary.json says what it picked and why (docs/scheme.md)\n";
  text +=
      "  geodesic*: S^n and H^n only (refused on E^n); the state is the embedding points x and\n"
      "    velocities v, no chart. On H^n they lose digits like eps e^(2r/R) at distance r from the\n"
      "    origin (a far pair's separation: 6e-7 off at 10 radii, 3e-4 at 13, where sesi4 is 2e-9\n"
      "    off); a body beyond 15.7 radii is refused. Far out, use a sesi method (docs/scheme.md).\n";
  text +=
      "\nSCENE FILES (TOML; every key in docs/scene-format.md):\n"
      "  [space]        kind = \"sphere\" | \"hyperbolic\" | \"euclidean\", dim, radius\n"
      "  [[bodies]]     mass, and q (chart coordinates) with p (momenta), or x (embedding point)\n"
      "                 with v (tangent velocity)\n"
      "  [[potential]]  kind = \"chord-well\" (theta0, strength), \"cotangent-gravity\" (G),\n"
      "                 \"central-cotangent\" (k, center), \"harmonic-pair\" (k, d0),\n"
      "                 \"lennard-jones\" (epsilon, sigma, cutoff); singular terms also min_distance\n"
      "  [integrator]   method, tolerance (method auto), dt, t_end, output_every, energy_guard,\n"
      "                 threads, check_every, checkpoint_every, neighbour_skin, trajectory_format\n"
      "  [thermostat]   kind = \"langevin\" (gamma, seed), \"nose-hoover\" (tau, chain), \"csvr\"\n"
      "                 (tau, seed), \"brownian\" (gamma, seed); temperature = kT or a schedule\n"
      "                 [[t0, kT0], [t1, kT1], ...]; runs with method sesi2 (its default then)\n"
      "  Without SCENE: the seed paper's three bodies on S^2 with sesi4, dt = 0.1, t_end = 800.\n"
      "\nOUTPUTS (in DIR, put in place when the run ends; docs/scene-format.md says what is kept):\n"
      "  trajectory.csv   t, then per body b: b<b>_q<i>, b<b>_p<i>, b<b>_x<i>\n"
      "  trajectory.h5    instead, with trajectory_format h5md: the same numbers as H5MD\n"
      "  diagnostics.csv  t, energy, energy_error, momentum-map components\n"
      "  exact.csv        exact positions (scenes with an exact solution: the default scene)\n"
      "  summary.json     settings, energy and momentum-map errors, final state, wall time\n"
      "  checkpoint       the state to go on from (checkpoint_every and the run's end, or a\n"
      "                   signal): sesi resume DIR\n"
      "  sesi-manifest.txt  the files sesi wrote: a rerun into DIR replaces them (and keeps\n"
      "                   pictures it does not list)\n"
      "\nEXIT STATUS:\n"
      "  0 done;  2 bad scene or argument (one line on stderr, nothing written);\n"
      "  3 the run went wrong: the state became non-finite, the energy error passed the guard\n"
      "    ([integrator] energy_guard) or two bodies came below the close-encounter floor\n"
      "    (min_distance); one line names the step, time and bodies; outputs so far kept,\n"
      "    \"complete\": false in summary.json;\n"
      "  130 interrupted by SIGINT, SIGTERM or SIGHUP (likewise, with a checkpoint to resume from;\n"
      "    before the run starts, nothing written; a second signal stops at once);\n"
      "  1 other failure (e.g. a write error).\n"
      "\nA progress bar appears on stderr for runs longer than a second when stderr is a terminal.\n";
  return text;
}

}  // namespace

int main(int argc, char** argv) {
  signals::install();  // before anything is read: a signal then ends the program with nothing written
  install_check_handler();

  CLI::App app{"sesi: explicit symplectic integration of Hamiltonian dynamics on spheres S^n,\n"
               "hyperbolic spaces H^n and flat E^n (SESI, the seed paper's scheme, orders 2 to 8).",
               "sesi"};
  app.set_version_flag("--version", "sesi 0.1.0");
  app.require_subcommand(1);
  app.footer("\nRun 'sesi run --help' for scenes, methods, outputs and exit statuses; 'sesi sweep --help'\n"
             "for many variants of a scene at once, on all cores or MPI ranks (docs/sweeps.md); 'sesi analyze\n"
             "--help' for g(r), MSD and VACF of a finished run (docs/observables.md); 'sesi view --help' for\n"
             "a run in the browser (docs/view.md).");

  RunOptions options;
  std::string method;
  double dt = 0.0, t_end = 0.0;
  long output_every = 0, threads = 0, check_every = 0, checkpoint_every = 0;
  double neighbour_skin = 0;
  std::string trajectory_format;
  CLI::App* run = app.add_subcommand("run", "Run a scene and write its trajectory, diagnostics and summary.");
  run->add_option("SCENE", options.scene_path,
                  "Scene file (TOML). Without it, the seed paper's three-body scene.")
      ->type_name("FILE");
  auto* out_opt = run->add_option("--out,-o", options.out, "Output directory (default ./sesi-out/<scene name>).")
                      ->type_name("DIR");
  auto* method_opt =
      run->add_option("--method,-m", method,
                      "Integration method (see METHODS), or auto; replaces the scene's.")
          ->type_name("M");
  double tolerance = 0.0;
  auto* tolerance_opt =
      run->add_option("--tolerance", tolerance,
                      "Target max relative energy error, 1e-12 to 1e-2: method auto picks the method and "
                      "step (implies --method auto; a given dt is replaced).")
          ->type_name("TOL");
  auto* dt_opt = run->add_option("--dt", dt, "Time step, finite and non-zero (negative runs backwards).")
                     ->type_name("H");
  auto* t_end_opt = run->add_option("--t-end", t_end,
                                    "Length of the run, >= 0 (the last step is shortened to end there).")
                        ->type_name("T");
  auto* every_opt =
      run->add_option("--output-every", output_every, "Steps between output rows, >= 1.")->type_name("N");
  auto* threads_opt =
      run->add_option("--threads,-j", threads, "Threads, >= 0 (0: all cores; results do not depend on it); per rank under mpirun.")
          ->type_name("N");
  auto* check_opt = run->add_option("--check-every", check_every,
                                    "Steps between energy and encounter checks, >= 1 (output rows are always checked).")
                        ->type_name("N");
  auto* checkpoint_opt =
      run->add_option("--checkpoint-every", checkpoint_every,
                      "Steps between checkpoints (DIR/checkpoint, for sesi resume), >= 1; a signal always "
                      "writes one.")
          ->type_name("N");
  auto* skin_opt = run->add_option("--neighbour-skin", neighbour_skin,
                                   "Verlet-list skin of cutoff terms, a fraction of the cutoff from 0 to 1 (default "
                                   "0.12; 0: rebuilt every evaluation).")
                       ->type_name("S");
  auto* format_opt =
      run->add_option("--trajectory-format", trajectory_format, "Trajectory format: csv or h5md.")->type_name("F");
  double temperature = 0.0;
  auto* temperature_opt =
      run->add_option("--temperature", temperature,
                      "The thermostat's temperature kT (k_B = 1), constant: replaces the scene's (a schedule too); "
                      "needs a [thermostat] table.")
          ->type_name("KT");
  std::string seed;
  auto* seed_opt = run->add_option("--seed", seed,
                                   "The thermostat's noise seed, 0 to 2^63 - 1 (langevin, csvr, brownian); needs a "
                                   "[thermostat] table.")
                       ->type_name("N");
  run->add_flag("--quiet,-q", options.quiet, "No report on stdout and no progress bar.");
  run->add_flag("--profile", options.profile,
                "Time the steps' phases per thread: DIR/profile.csv, and a table on stderr (results unchanged).");
  bool list_methods = false, list_json = false;
  auto* list_opt = run->add_flag("--list-methods", list_methods,
                                 "Print the methods, one name per line, and run nothing.");
  auto* json_opt = run->add_flag("--json", list_json,
                                 "With --list-methods: one JSON object, each method's name, order, family, "
                                 "processed, stages, output_stages, spaces and about.");
  run->footer(run_footer());
  ResumeOptions resume_options;
  double resume_t_end = 0.0;
  long resume_threads = 0;
  CLI::App* resume = app.add_subcommand(
      "resume", "Go on with a stopped run from its checkpoint; its outputs are extended as if it had not stopped.");
  resume->add_option("DIR", resume_options.dir,
                     "The stopped run's output directory (a killed run's checkpoint beside it is found too).")
      ->type_name("DIR")
      ->required();
  auto* resume_t_end_opt =
      resume->add_option("--t-end", resume_t_end, "A later end of the run (default: the run's own).")->type_name("T");
  auto* resume_threads_opt =
      resume->add_option("--threads,-j", resume_threads, "Threads, >= 0 (0: all cores; results do not depend on it); per rank under mpirun.")
          ->type_name("N");
  resume->add_flag("--quiet,-q", resume_options.quiet, "No report on stdout and no progress bar.");
  resume->add_flag("--profile", resume_options.profile,
                   "Time the resumed steps' phases per thread: DIR/profile.csv, and a table on stderr.");
  BenchOptions bench_options;
  CLI::App* bench = add_bench_subcommand(app, bench_options);
  SweepOptions sweep_options;
  CLI::App* sweep = add_sweep_subcommand(app, sweep_options);
  AnalyzeOptions analyze_options;
  CLI::App* analyze = add_analyze_subcommand(app, analyze_options);
  ViewOptions view_options;
  CLI::App* view = add_view_subcommand(app, view_options);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);  // --help, --version
    print_error(e.what());
    return exit_bad_input;
  }
  options.out_given = out_opt->count() > 0;
  if (method_opt->count() > 0) options.method = method;
  if (tolerance_opt->count() > 0) options.tolerance = tolerance;
  if (dt_opt->count() > 0) options.dt = dt;
  if (t_end_opt->count() > 0) options.t_end = t_end;
  if (every_opt->count() > 0) options.output_every = output_every;
  if (threads_opt->count() > 0) options.threads = threads;
  if (check_opt->count() > 0) options.check_every = check_every;
  if (checkpoint_opt->count() > 0) options.checkpoint_every = checkpoint_every;
  if (resume_t_end_opt->count() > 0) resume_options.t_end = resume_t_end;
  if (resume_threads_opt->count() > 0) resume_options.threads = resume_threads;
  if (format_opt->count() > 0) options.trajectory_format = trajectory_format;
  if (skin_opt->count() > 0) options.neighbour_skin = neighbour_skin;
  if (temperature_opt->count() > 0) options.temperature = temperature;
  if (seed_opt->count() > 0) options.seed = seed;

  if (run->parsed() && (list_methods || list_json)) {
    if (!list_methods) {
      print_error("--json: only with --list-methods");
      return exit_bad_input;
    }
    for (const CLI::Option* o : run->get_options()) {
      if (o != list_opt && o != json_opt && o->count() > 0) {
        print_error("--list-methods: takes no scene and no other option but --json (got " + o->get_name() + ")");
        return exit_bad_input;
      }
    }
    std::fputs(method_list_text(list_json).c_str(), stdout);
    return std::fflush(stdout) == 0 ? exit_ok : exit_internal;
  }

  try {
    if (bench->parsed()) return bench_command(bench_options);
    if (sweep->parsed()) return sweep_command(sweep_options);
    if (analyze->parsed()) return analyze_command(analyze_options);
    if (view->parsed()) return view_command(view_options);
    if (resume->parsed()) return resume_command(resume_options);
    return run_command(options);
  } catch (const InputError& e) {
    print_error(e.what());
    return exit_bad_input;
  } catch (const std::exception& e) {
    print_error(e.what());
    return exit_internal;
  }
}
