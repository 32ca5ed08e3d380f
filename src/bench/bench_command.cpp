#include "bench_command.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <sstream>

#include <CLI/CLI.hpp>

#include "bench_scaling.hpp"
#include "bench_scenes.hpp"
#include "bench_types.hpp"
#include "errors.hpp"
#include "methods.hpp"
#include "scene_reader.hpp"

namespace sesi::program {

namespace bench {

namespace {
// clang-format off
constexpr std::array<MethodSpec, 29> methods{{
  {Method::sesi2,             "sesi2",             2, Family::chart},
  {Method::sesi4,             "sesi4",             4, Family::chart},
  {Method::sesi4_suzuki,      "sesi4-suzuki",      4, Family::chart},
  {Method::sesi4_mclachlan,   "sesi4-mclachlan",   4, Family::chart},
  {Method::sesi6,             "sesi6",             6, Family::chart},
  {Method::sesi6_kahan_li,    "sesi6-kahan-li",    6, Family::chart},
  {Method::sesi8,             "sesi8",             8, Family::chart},
  {Method::sesi8_kahan_li,    "sesi8-kahan-li",    8, Family::chart},
  {Method::sesi6_processed,   "sesi6-processed",   6, Family::chart},
  {Method::sesi8_processed,   "sesi8-processed",   8, Family::chart},
  {Method::sesi10_processed,  "sesi10-processed", 10, Family::chart},
  {Method::dopri5,            "dopri5",            5, Family::adaptive},
  {Method::rk78,              "rk78",              8, Family::adaptive},
  {Method::bulirsch_stoer,    "bulirsch-stoer",    0, Family::adaptive},
  {Method::rk4,               "rk4",               4, Family::fixed_reference},
  {Method::implicit_midpoint, "implicit-midpoint", 2, Family::fixed_reference},
  {Method::gauss4,            "gauss4",            4, Family::fixed_reference},
  {Method::tao2,              "tao2",              2, Family::fixed_reference},
  {Method::tao4,              "tao4",              4, Family::fixed_reference},
  {Method::rattle,            "rattle",            2, Family::embedding},
  {Method::geodesic2,         "geodesic2",         2, Family::embedding},
  {Method::geodesic4,         "geodesic4",         4, Family::embedding},
  {Method::geodesic6,         "geodesic6",         6, Family::embedding},
  {Method::geodesic6_kahan_li, "geodesic6-kahan-li", 6, Family::embedding},
  {Method::geodesic8,         "geodesic8",         8, Family::embedding},
  {Method::geodesic8_kahan_li, "geodesic8-kahan-li", 8, Family::embedding},
  {Method::geodesic6_processed, "geodesic6-processed", 6, Family::embedding},
  {Method::geodesic8_processed, "geodesic8-processed", 8, Family::embedding},
  {Method::geodesic10_processed, "geodesic10-processed", 10, Family::embedding},
}};
// clang-format on

std::vector<double> divided(double base, std::initializer_list<int> ks) {
  std::vector<double> out;
  for (int k : ks) out.push_back(base / k);
  return out;
}
std::vector<double> decades(double from, double to, int per_decade) {
  std::vector<double> out;
  const int n = static_cast<int>(std::lround((std::log10(from) - std::log10(to)) * per_decade));
  for (int j = 0; j <= n; ++j) out.push_back(from * std::pow(10.0, -double(j) / per_decade));
  return out;
}
}  // namespace

std::span<const MethodSpec> all_methods() { return methods; }

const MethodSpec* find_method(std::string_view name) {
  for (const MethodSpec& m : methods)
    if (m.name == name) return &m;
  return nullptr;
}

std::vector<double> sweep(const MethodSpec& m, const Settings& s) {
  if (m.family == Family::adaptive && !s.tols.empty()) return s.tols;
  if (m.family != Family::adaptive && !s.dts.empty()) return s.dts;
  const double base = s.t_end / s.samples;
  if (s.quick) {
    if (m.family == Family::adaptive) return {1e-5, 1e-7, 1e-9};
    if (m.order <= 2) return divided(base, {2, 4, 8});
    if (m.order <= 4) return divided(base, {1, 2, 4});
    return divided(base, {1, 2});
  }
  switch (m.id) {
    case Method::dopri5: return decades(1e-3, 1e-13, 2);
    case Method::rk78: return decades(1e-3, 1e-14, 2);
    case Method::bulirsch_stoer: return decades(1e-3, 1e-14, 1);
    case Method::rk4: return divided(base, {1, 2, 4, 8, 16, 32, 64, 128});
    default: break;
  }
  if (m.order <= 2) return divided(base, {1, 2, 4, 8, 16, 32, 64, 128});
  if (m.order <= 4) return divided(base, {1, 2, 3, 4, 6, 8, 12, 16, 24, 32, 48});
  return divided(base, {1, 2, 3, 4, 6, 8, 12, 16, 24});
}

double Ladder::param(int k) const { return std::pow(10.0, -double(k) / per_decade); }

Ladder horizon_ladder(const MethodSpec& m) {
  Ladder l;
  if (m.family == Family::adaptive) {
    // Tolerances 1e-1 .. 1e-15 (abs = rel) in rungs of 10^(-1/4), from 1e-6.
    l.per_decade = 4;
    l.k_start = 24;
    l.k_min = 4;
    l.k_max = 60;
    return l;
  }
  // Steps 1 .. 1e-5 in rungs of 10^(-1/(4p)), from 0.1 (order 2), 0.2 (4), 0.5 (6 and up):
  // on unit-scale scenes (periods of a few time units) just above the largest default level.
  // A rung moves the error (~ dt^p) by a quarter decade, the cost by 10^(1/(4p)) (1.075 at
  // order 8): the least time to a level is overstated by at most that.
  const int p = std::max(m.order, 2);
  const double start = p <= 2 ? 0.1 : p <= 4 ? 0.2 : 0.5;
  l.per_decade = 4 * p;
  l.k_start = static_cast<int>(std::lround(-l.per_decade * std::log10(start)));
  l.k_min = 0;
  l.k_max = 5 * l.per_decade;
  return l;
}

}  // namespace bench

CLI::App* add_bench_subcommand(CLI::App& app, BenchOptions& o) {
  CLI::App* b = app.add_subcommand(
      "bench", "Work-precision sweeps of every method against the reference integrators.");
  b->add_option("--scene,-s", o.scene,
                "paper (default), kepler-s2, kepler-h2, or a scene file (S^n or H^n, n = 2, 3).")
      ->type_name("NAME|FILE");
  b->add_option("--methods,-m", o.methods, "Comma-separated methods (default: all).")
      ->type_name("LIST");
  b->add_option("--t-end", o.t_end, "Length of every run (default: the scene's).")->type_name("T");
  b->add_option("--out,-o", o.out, "Output directory (default sesi-out/bench/<scene>).")
      ->type_name("DIR");
  b->add_flag("--quick", o.quick, "A short sweep (t_end <= 20, 200 samples, 2-3 points per method; for tests).");
  b->add_option("--repeats", o.repeats,
                "Timed repeats per point (minimum reported; with --scaling, rounds over all the points, default 1).")
      ->type_name("N");
  b->add_option("--form", o.form,
                "Form of the sesi* rows: program (kick-drift-kick, as sesi run; re-charting on a "
                "scene file) or seed (drift-kick-drift, the library default). Default: program "
                "on paper and scene files, seed on the Kepler scenes.")
      ->type_name("FORM");
  b->add_option("--dts", o.dts,
                "Comma-separated fixed steps of every fixed-step method, whatever t_end (default: the "
                "sweep's dt = (t_end/1000)/k; with --horizons, a ladder per order).")
      ->type_name("LIST");
  b->add_option("--tols", o.tols,
                "Comma-separated tolerances (abs = rel) of dopri5, rk78 and bulirsch-stoer (default: "
                "their sweeps; with --horizons, a ladder).")
      ->type_name("LIST");
  b->add_option("--budget", o.budget,
                "Seconds: a method's runs stop getting finer after a run this long (default 20; 2 "
                "with --quick).")
      ->type_name("S");
  b->add_option("--horizons", o.horizons,
                "Instead of the sweep, a horizon sweep: comma-separated run lengths; writes "
                "DIR/horizons.csv (least time to each --levels energy error) and DIR/horizon_runs.csv.")
      ->type_name("LIST");
  b->add_option("--levels", o.levels,
                "--horizons: comma-separated max energy error levels (default "
                "1e-5,1e-6,1e-7,1e-8,1e-9,1e-10).")
      ->type_name("LIST");
  b->add_option("--figure", o.figure,
                "Instead of the sweep, the data of a seed figure: seed-fig1 or convergence.")
      ->type_name("NAME");
  b->add_flag("--scaling", o.scaling,
              "Instead of the sweep, seconds per step against the number of bodies, with flat references "
              "(DIR/scaling.csv; options below).");
  b->add_option("--space", o.space, "--scaling: sphere (default), hyperbolic or euclidean.")->type_name("KIND");
  b->add_option("--dim", o.dim, "--scaling: dimension of the space (default 2).")->type_name("N");
  b->add_option("--potential", o.potential, "--scaling: lennard-jones (default) or cotangent-gravity.")
      ->type_name("KIND");
  b->add_option("--n", o.sizes, "--scaling: comma-separated body counts (default 1000,3000,10000,30000,100000).")
      ->type_name("LIST");
  b->add_option("--threads,-j", o.threads, "--scaling: comma-separated thread counts (default: all cores).")
      ->type_name("LIST");
  b->add_option("--steps", o.steps, "--scaling: timed steps per point (default: about a second's worth, at least 40; gravity 4).")->type_name("N");
  b->add_option("--check-every", o.check_every,
                "--scaling: steps between the runs' checks (default: sesi run's default cadence).")
      ->type_name("N");
  b->add_option("--skin", o.skin, "--scaling: the runs' neighbour_skin (default 0.12; 0: lists rebuilt every step).")
      ->type_name("S");
  b->add_option("--center-distance", o.center_distances,
                "--scaling on H^n: comma-separated distances of the cluster's centre from the chart origin, in "
                "radii (default 0); one row per distance, the far / origin ratios printed.")
      ->type_name("LIST");
  b->add_flag("--box", o.box,
              "--scaling on E^n: the bodies in a periodic box at the same density (issue #26), with LAMMPS "
              "(lmp, mpirun -np THREADS) on the same bodies when it is installed; the ratios printed.");
  b->add_flag("--no-lammps", o.no_lammps,
              "--scaling: leave out the LAMMPS rows (made with --box, and on --space sphere --dim 2 or 3, "
              "where LAMMPS runs the E^n box at the same N and density; issue #27).");
  b->add_option("--genus", o.genera,
                "--scaling on H^2: comma-separated genera of compact surfaces holding the N bodies at the same "
                "density (R = (N / (4 pi (g - 1) rho))^(1/2)), with the E^2 box at the same N; ratios printed.")
      ->type_name("LIST");
  b->add_flag("--ranks", o.ranks,
              "--scaling on S^2 Lennard-Jones: for each T of --threads (default 2) and N of --n (default "
              "100000), `sesi run --threads T` against `mpirun -np T sesi run --threads 1` on the same scene "
              "file, seconds per step from each run's profile, peak memory and their ratios (issue #27; "
              "DIR/ranks.csv).");
  std::string footer = "\nMETHODS:";
  for (const bench::MethodSpec& m : bench::all_methods()) footer += " " + std::string(m.name);
  footer +=
      "\n\nOUTPUT: DIR/work_precision.csv, one row per run: method, order, dt_or_tol, steps,\n"
      "force_evals, wall_seconds (minimum of the repeats, no observer), final_error (largest\n"
      "geodesic distance from the reference position at t_end), max_energy_error and\n"
      "max_momentum_drift (over 1001 common sample times); '#' lines state the reference and\n"
      "the sampling. Plots: /usr/bin/python3 tools/plot_bench.py DIR (docs/benchmarks.md).\n"
      "With --horizons: DIR/horizons.csv, one row per method, horizon and level: method, order,\n"
      "horizon, level, reached (yes/no), dt_or_tol, steps, force_evals, wall_seconds (of the\n"
      "fastest run reaching max energy error <= level), max_energy_error (of that run), runs,\n"
      "best_error (smallest of any run); DIR/horizon_runs.csv every run. Default methods:\n"
      "every method of sesi run, dopri5 and rk78. Plot: /usr/bin/python3 tools/plot_horizons.py\n"
      "DIR/horizons.csv --figure PNG.\n"
      "With --scaling: DIR/scaling.csv (default DIR sesi-out/bench/scaling), one row per point:\n"
      "n_bodies, space, dim, potential, method, threads, seconds_per_step, pairs_per_step,\n"
      "ns_per_pair, peak_rss_mb; rows 'euclidean 3' (sesi on flat E^3, same N and density) and\n"
      "'flat-periodic' (a plain 3-D cell-list loop) are the references; on S^2 and S^3 (and with\n"
      "--box) rows 'lammps' time LAMMPS on the E^n box at the same N and density when lmp is on\n"
      "PATH (--no-lammps: not). --methods takes sesi run's\n"
      "methods there (default sesi2). Plot: /usr/bin/python3 tools/plot_scaling.py DIR.\n"
      "With --scaling --ranks: DIR/ranks.csv, two rows per N and T: one process of T threads and\n"
      "T MPI ranks of one thread (docs/parallel.md).\n";
  b->footer(footer);
  return b;
}

namespace {

std::vector<const bench::MethodSpec*> parse_methods(const std::string& list) {
  std::vector<const bench::MethodSpec*> out;
  if (list.empty() || list == "all") {
    for (const bench::MethodSpec& m : bench::all_methods()) out.push_back(&m);
    return out;
  }
  std::stringstream in(list);
  std::string name;
  while (std::getline(in, name, ',')) {
    if (name.empty()) continue;
    const bench::MethodSpec* m = bench::find_method(name);
    if (!m) throw InputError("--methods: unknown method '" + name + "'");
    out.push_back(m);
  }
  if (out.empty()) throw InputError("--methods: no method given");
  return out;
}

/// A comma-separated list of positive finite numbers (at most `most`), or an InputError naming
/// the option.
std::vector<double> parse_numbers(const std::string& text, const char* option, const char* what,
                                  double most = std::numeric_limits<double>::max()) {
  std::vector<double> out;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    std::size_t used = 0;
    double value = 0;
    try {
      value = std::stod(item, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used == 0 || used != item.size() || !std::isfinite(value) || !(value > 0) || value > most)
      throw InputError(std::string(option) + ": '" + item + "' is not " + what);
    out.push_back(value);
  }
  if (out.empty()) throw InputError(std::string(option) + ": empty list");
  std::sort(out.begin(), out.end(), std::greater<>());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

std::string join(const std::vector<double>& values) {
  std::string out;
  char item[32];
  for (double v : values) {
    std::snprintf(item, sizeof item, "%s%g", out.empty() ? "" : ",", v);
    out += item;
  }
  return out;
}

/// Whether the fixed step dt lands on every sample time (spacing apart), up to the round-off
/// integrate_fixed allows.
bool divides(double dt, double spacing) {
  const double k = std::round(spacing / dt);
  return k >= 1 && std::abs(k * dt - spacing) <= 1e-6 * dt;
}

bool is_adaptive(const std::string& method) {
  const bench::MethodSpec* m = bench::find_method(method);
  return m && m->family == bench::Family::adaptive;
}

/// The '#' lines on where the errors are sampled, with the rows' own sample counts (fixed steps
/// that do not divide t_end / samples observe the nearest step boundaries, integrate_fixed).
std::vector<std::string> sampling_notes(const bench::Settings& s, const std::vector<bench::Row>& rows,
                                        bool horizons) {
  std::vector<std::string> notes;
  const std::string times = horizons ? "T * j / " + std::to_string(s.samples) + " (j = 0.." +
                                           std::to_string(s.samples) + ", T the horizon)"
                                     : "t_end * j / " + std::to_string(s.samples);
  notes.push_back("errors sampled at the " + std::to_string(s.samples + 1) + " times " + times +
                  ": fixed-step runs at the step boundary nearest each (the time itself when dt "
                  "divides the spacing; else within dt/2, several times may share one, and a last "
                  "shorter step ends the run at its end time); dopri5 and bulirsch-stoer through "
                  "dense output; rk78 " +
                  std::string(horizons ? "on the timed run's own steps, at the first step boundary at "
                                         "or after each"
                                       : "through steps shortened to land on each"));
  long off = 0, fixed = 0, fewest = std::numeric_limits<long>::max();
  for (const bench::Row& r : rows) {
    if (is_adaptive(r.method)) continue;
    ++fixed;
    if (!divides(r.dt_or_tol, r.t_end / s.samples)) {
      ++off;
      fewest = std::min(fewest, r.samples);
    }
  }
  char line[256];
  if (off == 0) {
    std::snprintf(line, sizeof line, "sampling: every fixed-step run's dt divides the spacing: all "
                  "%d times observed exactly", s.samples + 1);
  } else {
    std::snprintf(line, sizeof line,
                  "sampling: %ld of %ld fixed-step runs have a dt that does not divide the spacing: "
                  "observed at the nearest step boundaries, %ld distinct times or more%s",
                  off, fixed, fewest, horizons ? " (column samples)" : "");
  }
  notes.push_back(line);
  if (!s.dts.empty()) notes.push_back("fixed steps (--dts) of every fixed-step method: " + join(s.dts));
  if (!s.tols.empty()) notes.push_back("tolerances (--tols, abs = rel): " + join(s.tols));
  return notes;
}

void write_build_note(std::ofstream& out) {
#ifdef NDEBUG
  out << "# build: optimised (NDEBUG)\n";
#else
  out << "# build: NOT optimised (no NDEBUG): timings are not representative\n";
#endif
}

void write_csv(const std::string& path, const bench::Settings& s, const bench::Result& r) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error("cannot write " + path);
  out << "# sesi bench: work-precision sweep (issue #4; docs/benchmarks.md)\n";
  for (const std::string& note : r.notes) out << "# " << note << '\n';
  for (const std::string& note : sampling_notes(s, r.rows, false)) out << "# " << note << '\n';
  char line[512];
  std::snprintf(line, sizeof line,
                "# t_end = %g, %d sample times, wall_seconds = minimum of %d timed runs "
                "(more for runs under 0.05 s), no observer in the timed runs%s\n",
                s.t_end, s.samples + 1, s.repeats, s.quick ? "; QUICK sweep" : "");
  out << line;
  write_build_note(out);
  out << "method,order,dt_or_tol,steps,force_evals,wall_seconds,final_error,max_energy_error,"
         "max_momentum_drift\n";
  for (const bench::Row& row : r.rows) {
    std::snprintf(line, sizeof line, "%s,%d,%.10g,%ld,%ld,%.6g,%.6g,%.6g,%.6g\n",
                  row.method.c_str(), row.order, row.dt_or_tol, row.steps, row.force_evals,
                  row.wall_seconds, row.final_error, row.max_energy_error,
                  row.max_momentum_drift);
    out << line;
  }
  if (!out.flush()) throw std::runtime_error("write error on " + path);
}

/// One row of horizons.csv: a method's fastest run reaching a level at a horizon (or none).
struct Reach {
  const bench::MethodSpec* method = nullptr;
  double horizon = 0, level = 0;
  const bench::Row* run = nullptr;  ///< null: no run reached the level
  long runs = 0;
  double best_error = std::numeric_limits<double>::quiet_NaN();
};

/// For every method, horizon and level (in that order), the run of least wall time reaching max
/// energy error <= level. A smaller level's candidates are a subset of a larger one's, so its
/// time is never less.
std::vector<Reach> reaches(const bench::Settings& s, const std::vector<bench::Row>& rows) {
  std::vector<Reach> out;
  for (const bench::MethodSpec* m : s.methods) {
    for (double horizon : s.horizons) {
      for (double level : s.levels) {
        Reach r{m, horizon, level};
        for (const bench::Row& row : rows) {
          if (row.method != m->name || row.t_end != horizon) continue;
          ++r.runs;
          if (!(r.best_error <= row.max_energy_error)) r.best_error = row.max_energy_error;
          if (row.max_energy_error <= level && (!r.run || row.wall_seconds < r.run->wall_seconds))
            r.run = &row;
        }
        out.push_back(r);
      }
    }
  }
  return out;
}

void write_horizons(const std::string& dir, const std::string& scene, const bench::Settings& s,
                    const bench::Result& r, const std::vector<Reach>& table) {
  auto header = [&](std::ofstream& out, const char* what) {
    out << "# sesi bench --horizons: " << what << " (issue #15; docs/benchmarks.md, Long horizons)\n";
    for (const std::string& note : r.notes) out << "# " << note << '\n';
    for (const std::string& note : sampling_notes(s, r.rows, true)) out << "# " << note << '\n';
    out << "# horizons " << join(s.horizons) << "; levels (max |E(t) - E(0)|) " << join(s.levels)
        << "; scene " << scene << (s.quick ? "; QUICK sweep" : "") << '\n';
    out << "# runs: the --dts/--tols lists from the coarsest, else per method a ladder (dt = "
           "10^(-k/(2p)) for order p, tol = 10^(-k/2)): coarser from its start while a run reaches "
           "the largest level, finer until one reaches the smallest; finer runs stop after one over "
        << s.run_budget << " s (or predicted over 3 times that) or 3 rungs without a smaller error\n";
    out << "# wall_seconds: the minimum of timed runs without observer; every run timed once, and the "
           "fastest run reaching each level "
        << s.repeats << " times in all (" << 2 * s.repeats
        << " under 0.05 s, once over half the budget); errors from a separate observed run\n";
    write_build_note(out);
  };
  const std::string runs_path = dir + "/horizon_runs.csv";
  {
    std::ofstream out(runs_path);
    if (!out) throw std::runtime_error("cannot write " + runs_path);
    header(out, "every run");
    out << "method,order,horizon,dt_or_tol,steps,force_evals,wall_seconds,timed_runs,"
           "max_energy_error,max_momentum_drift,samples\n";
    char line[512];
    for (const bench::Row& row : r.rows) {
      std::snprintf(line, sizeof line, "%s,%d,%.10g,%.10g,%ld,%ld,%.6g,%d,%.6g,%.6g,%ld\n",
                    row.method.c_str(), row.order, row.t_end, row.dt_or_tol, row.steps,
                    row.force_evals, row.wall_seconds, row.timed_runs, row.max_energy_error,
                    row.max_momentum_drift, row.samples);
      out << line;
    }
    if (!out.flush()) throw std::runtime_error("write error on " + runs_path);
  }
  const std::string path = dir + "/horizons.csv";
  std::ofstream out(path);
  if (!out) throw std::runtime_error("cannot write " + path);
  header(out, "least wall time to each max energy error level");
  out << "# reached = no: no run of the method's sweep at that horizon had max energy error <= level "
         "(best_error: the smallest it had; runs: how many runs)\n";
  out << "method,order,horizon,level,reached,dt_or_tol,steps,force_evals,wall_seconds,"
         "max_energy_error,runs,best_error\n";
  char line[512];
  for (const Reach& c : table) {
    const std::string name(c.method->name);
    if (c.run) {
      std::snprintf(line, sizeof line, "%s,%d,%.10g,%g,yes,%.10g,%ld,%ld,%.6g,%.6g,%ld,%.6g\n",
                    name.c_str(), c.method->order, c.horizon, c.level, c.run->dt_or_tol,
                    c.run->steps, c.run->force_evals, c.run->wall_seconds,
                    c.run->max_energy_error, c.runs, c.best_error);
    } else {
      std::snprintf(line, sizeof line, "%s,%d,%.10g,%g,no,nan,nan,nan,nan,nan,%ld,%.6g\n",
                    name.c_str(), c.method->order, c.horizon, c.level, c.runs, c.best_error);
    }
    out << line;
  }
  if (!out.flush()) throw std::runtime_error("write error on " + path);
}

/// The summary on stdout: per horizon and level, the fastest method of `sesi run` against rk78's
/// and dopri5's fastest; on the seed's scene, issue #15's targets.
void print_horizon_summary(const std::string& scene, const bench::Settings& s,
                           const std::vector<Reach>& table) {
  auto find = [&](std::string_view method, double horizon, double level) -> const Reach* {
    for (const Reach& c : table)
      if (c.method->name == method && c.horizon == horizon && c.level == level) return &c;
    return nullptr;
  };
  auto fastest_sesi = [&](double horizon, double level) -> const Reach* {
    const Reach* best = nullptr;
    for (const Reach& c : table)
      if (is_method(c.method->name) && c.horizon == horizon && c.level == level &&
          c.run && (!best || c.run->wall_seconds < best->run->wall_seconds))
        best = &c;
    return best;
  };
  // "t (ratio)" of a reference against the fastest sesi method; "-" when it reached nothing.
  auto against = [&](const Reach* ref, const Reach* sesi) {
    char cell[64];
    if (!ref) return std::string("(not run)");
    if (!ref->run) {
      std::snprintf(cell, sizeof cell, "no (best %.2g)", ref->best_error);
    } else if (!sesi) {
      std::snprintf(cell, sizeof cell, "%.3g s", ref->run->wall_seconds);
    } else {
      std::snprintf(cell, sizeof cell, "%.3g s (x%.2f)", ref->run->wall_seconds,
                    ref->run->wall_seconds / sesi->run->wall_seconds);
    }
    return std::string(cell);
  };
  std::printf("\nhorizon sweep, scene %s: least wall seconds to max energy error <= level; (xR): "
              "time / fastest sesi method's time\n",
              scene.c_str());
  std::printf("%9s %7s  %-34s %-24s %-24s\n", "horizon", "level", "fastest sesi (setting, s)",
              "rk78", "dopri5");
  for (double horizon : s.horizons) {
    for (double level : s.levels) {
      const Reach* sesi = fastest_sesi(horizon, level);
      char cell[96];
      if (sesi) {
        std::snprintf(cell, sizeof cell, "%s %.4g, %.3g s", std::string(sesi->method->name).c_str(),
                      sesi->run->dt_or_tol, sesi->run->wall_seconds);
      } else {
        std::snprintf(cell, sizeof cell, "none reached");
      }
      std::printf("%9g %7g  %-34s %-24s %-24s\n", horizon, level, cell,
                  against(find("rk78", horizon, level), sesi).c_str(),
                  against(find("dopri5", horizon, level), sesi).c_str());
    }
  }
  if (scene != "paper") return;
  // Issue #15 on the seed's scene: at T = 8000 and every level in [1e-10, 1e-5] that rk78
  // (dopri5) reaches, the fastest sesi method >= 3x (10x) faster; at T = 80000, 1e-9: >= 5x rk78.
  auto target = [&](double horizon, const char* ref, double want, double lo, double hi) {
    if (std::find(s.horizons.begin(), s.horizons.end(), horizon) == s.horizons.end()) return;
    std::string ratios;
    double worst = std::numeric_limits<double>::infinity();
    int compared = 0;
    for (double level : s.levels) {
      if (level < lo * (1 - 1e-12) || level > hi * (1 + 1e-12)) continue;
      const Reach* r = find(ref, horizon, level);
      if (!r || !r->run) continue;
      const Reach* sesi = fastest_sesi(horizon, level);
      const double ratio = sesi ? r->run->wall_seconds / sesi->run->wall_seconds : 0.0;
      char item[48];
      std::snprintf(item, sizeof item, "%s%g: %.2f", ratios.empty() ? "" : ", ", level, ratio);
      ratios += item;
      worst = std::min(worst, ratio);
      ++compared;
    }
    if (compared == 0) {
      std::printf("  T = %g, %s at levels %g..%g: %s reaches none of them: nothing to compare\n",
                  horizon, ref, hi, lo, ref);
    } else {
      std::printf("  T = %g, %s / fastest sesi >= %g at the levels %s reaches in [%g, %g]: %s; worst "
                  "%.2f: %s\n",
                  horizon, ref, want, ref, lo, hi, ratios.c_str(), worst, worst >= want ? "met" : "MISSED");
    }
  };
  std::printf("issue #15 targets (seed scene; at the levels of --levels):\n");
  target(8000, "rk78", 3, 1e-10, 1e-5);
  target(8000, "dopri5", 10, 1e-10, 1e-5);
  target(80000, "rk78", 5, 1e-9, 1e-9);
}

}  // namespace

int bench_command(const BenchOptions& o) {
  if (!o.horizons.empty() && (o.scaling || !o.figure.empty()))
    throw InputError("--horizons: not with --scaling or --figure");
  if (!o.horizons.empty() && o.t_end > 0)
    throw InputError("--horizons: gives the run lengths; leave out --t-end");
  if (!o.levels.empty() && o.horizons.empty()) throw InputError("--levels: only with --horizons");
  if ((!o.dts.empty() || !o.tols.empty()) && (o.scaling || !o.figure.empty()))
    throw InputError(std::string(o.dts.empty() ? "--tols" : "--dts") + ": not with --scaling or --figure");
  if (o.no_lammps && !o.scaling) throw InputError("--no-lammps: only with --scaling");
  if (o.ranks && !o.scaling) throw InputError("--ranks: only with --scaling");
  if (o.scaling) return bench::scaling_command(o);
  bench::Settings s;
  s.quick = o.quick;
  s.repeats = o.repeats > 0 ? o.repeats : (o.quick ? 1 : 3);
  if (o.budget < 0 || !std::isfinite(o.budget)) throw InputError("--budget: must be > 0 seconds");
  s.run_budget = o.budget > 0 ? o.budget : (o.quick ? 2.0 : 20.0);
  s.samples = o.quick ? 200 : 1000;
  if (!o.dts.empty()) s.dts = parse_numbers(o.dts, "--dts", "a positive step");
  if (!o.tols.empty()) s.tols = parse_numbers(o.tols, "--tols", "a tolerance in (0, 1]", 1.0);
  if (!o.horizons.empty()) {
    s.horizons = parse_numbers(o.horizons, "--horizons", "a positive run length");
    std::sort(s.horizons.begin(), s.horizons.end());
    s.levels = parse_numbers(o.levels.empty() ? "1e-5,1e-6,1e-7,1e-8,1e-9,1e-10" : o.levels,
                             "--levels", "a positive energy error level");
  }
  // The horizon sweep's default methods: every method of `sesi run` (compositions, processed and
  // geodesic methods) and the two odeint methods the targets name (the others: --methods).
  if (!s.horizons.empty() && (o.methods.empty() || o.methods == "all")) {
    for (const bench::MethodSpec& m : bench::all_methods())
      if (is_method(m.name) || m.name == "dopri5" || m.name == "rk78" || o.methods == "all")
        s.methods.push_back(&m);
  } else {
    s.methods = parse_methods(o.methods);
  }
  if (o.form == "seed") {
    s.form = bench::SesiForm::seed;
  } else if (o.form == "program") {
    s.form = bench::SesiForm::program;
  } else if (!o.form.empty()) {
    throw InputError("--form: seed or program, not '" + o.form + "'");
  }
  if (o.t_end < 0 || !std::isfinite(o.t_end)) throw InputError("--t-end: must be > 0");

  const bool builtin = o.scene == "paper" || o.scene == "kepler-s2" || o.scene == "kepler-h2";
  Scene scene;
  std::string name = o.scene;
  if (!builtin) {
    scene = read_scene_file(o.scene);
    name = scene.name;
    if (scene.space.kind == SpaceKind::euclidean || scene.dim() < 2 || scene.dim() > 3)
      throw InputError("sesi bench: scene files on S^n or H^n with n = 2 or 3 only (" +
                       o.scene + ")");
    // Its work-precision sweep runs every method, and builds the whole H^n: not a compact surface.
    if (scene.space.has_topology())
      throw InputError("sesi bench: scene files without a topology only (" + o.scene + " has genus " +
                       std::to_string(scene.space.genus) + "); time it with sesi run");
  }
  double default_t = bench::kepler_t_end;
  if (o.scene == "paper") default_t = bench::paper_t_end;
  if (!builtin) default_t = scene.integrator.t_end.value_or(bench::kepler_t_end);
  if (o.quick) default_t = std::min(default_t, bench::quick_t_end);
  s.t_end = o.t_end > 0 ? o.t_end : default_t;
  // A step longer than the (shortest) run would be one shortened step, not the one asked for.
  const double shortest = s.horizons.empty() ? s.t_end : s.horizons.front();
  if (!s.dts.empty() && s.dts.front() > shortest) {
    char msg[160];
    std::snprintf(msg, sizeof msg, "--dts: %g is longer than the run (%g)", s.dts.front(), shortest);
    throw InputError(msg);
  }

  const std::string dir = o.out.empty() ? "sesi-out/bench/" + name : o.out;
  std::filesystem::create_directories(dir);

  if (!o.figure.empty()) {
    if (o.figure == "seed-fig1") {
      bench::paper_fig1(dir, o.t_end > 0 ? o.t_end : bench::paper_t_end, s.repeats);
    } else if (o.figure == "convergence") {
      bench::paper_convergence(dir);
    } else {
      throw InputError("--figure: seed-fig1 or convergence, not '" + o.figure + "'");
    }
    std::printf("wrote %s (figure data: %s)\n", dir.c_str(), o.figure.c_str());
    return 0;
  }

  if (s.horizons.empty()) {
    std::fprintf(stderr, "sesi bench: scene %s, t_end %g, %zu methods\n", name.c_str(), s.t_end,
                 s.methods.size());
  } else {
    std::fprintf(stderr, "sesi bench: scene %s, horizons %s, levels %s, %zu methods\n", name.c_str(),
                 join(s.horizons).c_str(), join(s.levels).c_str(), s.methods.size());
  }
  auto bench_scene = [&](const bench::Settings& settings) {
    if (o.scene == "paper") return bench::bench_paper(settings);
    if (o.scene == "kepler-s2") return bench::bench_kepler_s2(settings);
    if (o.scene == "kepler-h2") return bench::bench_kepler_h2(settings);
    if (scene.space.kind == SpaceKind::sphere) return bench::bench_file_sphere(scene, settings);
    return bench::bench_file_hyperbolic(scene, settings);
  };
  if (!s.horizons.empty()) {
    // One horizon at a time, the CSVs rewritten after each: a long sweep stopped midway keeps
    // the horizons it finished (and the files list only those).
    bench::Result all;
    bench::Settings done = s;
    done.horizons.clear();
    std::vector<Reach> table;
    for (double horizon : s.horizons) {
      bench::Settings one = s;
      one.horizons = {horizon};
      bench::Result r = bench_scene(one);
      all.notes = r.notes;
      all.rows.insert(all.rows.end(), r.rows.begin(), r.rows.end());
      done.horizons.push_back(horizon);
      table = reaches(done, all.rows);
      write_horizons(dir, name, done, all, table);
    }
    std::printf("wrote %s/horizons.csv (%zu rows) and %s/horizon_runs.csv (%zu runs)\n", dir.c_str(),
                table.size(), dir.c_str(), all.rows.size());
    print_horizon_summary(name, s, table);
    return 0;
  }
  const bench::Result r = bench_scene(s);
  const std::string path = dir + "/work_precision.csv";
  write_csv(path, s, r);
  std::printf("wrote %s (%zu rows)\n", path.c_str(), r.rows.size());
  return 0;
}

}  // namespace sesi::program
