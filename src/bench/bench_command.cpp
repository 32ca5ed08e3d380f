#include "bench_command.hpp"

#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <CLI/CLI.hpp>

#include "bench_scaling.hpp"
#include "bench_scenes.hpp"
#include "bench_types.hpp"
#include "errors.hpp"
#include "scene_reader.hpp"

namespace sesi::program {

namespace bench {

namespace {
// clang-format off
constexpr std::array<MethodSpec, 20> methods{{
  {Method::sesi2,             "sesi2",             2, Family::chart},
  {Method::sesi4,             "sesi4",             4, Family::chart},
  {Method::sesi4_suzuki,      "sesi4-suzuki",      4, Family::chart},
  {Method::sesi4_mclachlan,   "sesi4-mclachlan",   4, Family::chart},
  {Method::sesi6,             "sesi6",             6, Family::chart},
  {Method::sesi6_kahan_li,    "sesi6-kahan-li",    6, Family::chart},
  {Method::sesi8,             "sesi8",             8, Family::chart},
  {Method::sesi8_kahan_li,    "sesi8-kahan-li",    8, Family::chart},
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
  std::string footer = "\nMETHODS:";
  for (const bench::MethodSpec& m : bench::all_methods()) footer += " " + std::string(m.name);
  footer +=
      "\n\nOUTPUT: DIR/work_precision.csv, one row per run: method, order, dt_or_tol, steps,\n"
      "force_evals, wall_seconds (minimum of the repeats, no observer), final_error (largest\n"
      "geodesic distance from the reference position at t_end), max_energy_error and\n"
      "max_momentum_drift (over 1000 common sample times); '#' lines state the reference.\n"
      "Plots: /usr/bin/python3 tools/plot_bench.py DIR (docs/benchmarks.md).\n"
      "With --scaling: DIR/scaling.csv (default DIR sesi-out/bench/scaling), one row per point:\n"
      "n_bodies, space, dim, potential, method, threads, seconds_per_step, pairs_per_step,\n"
      "ns_per_pair, peak_rss_mb; rows 'euclidean 3' (sesi on flat E^3, same N and density) and\n"
      "'flat-periodic' (a plain 3-D cell-list loop) are the references. --methods takes sesi run's\n"
      "methods there (default sesi2). Plot: /usr/bin/python3 tools/plot_scaling.py DIR.\n";
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

void write_csv(const std::string& path, const bench::Settings& s, const bench::Result& r) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error("cannot write " + path);
  out << "# sesi bench: work-precision sweep (issue #4; docs/benchmarks.md)\n";
  for (const std::string& note : r.notes) out << "# " << note << '\n';
  char line[512];
  std::snprintf(line, sizeof line,
                "# t_end = %g, %d sample times, wall_seconds = minimum of %d timed runs "
                "(more for runs under 0.05 s), no observer in the timed runs%s\n",
                s.t_end, s.samples + 1, s.repeats, s.quick ? "; QUICK sweep" : "");
  out << line;
#ifdef NDEBUG
  out << "# build: optimised (NDEBUG)\n";
#else
  out << "# build: NOT optimised (no NDEBUG): timings are not representative\n";
#endif
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

}  // namespace

int bench_command(const BenchOptions& o) {
  if (o.scaling) return bench::scaling_command(o);
  bench::Settings s;
  s.quick = o.quick;
  s.repeats = o.repeats > 0 ? o.repeats : (o.quick ? 1 : 3);
  s.run_budget = o.quick ? 2.0 : 20.0;
  s.samples = o.quick ? 200 : 1000;
  s.methods = parse_methods(o.methods);
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
  }
  double default_t = bench::kepler_t_end;
  if (o.scene == "paper") default_t = bench::paper_t_end;
  if (!builtin) default_t = scene.integrator.t_end.value_or(bench::kepler_t_end);
  if (o.quick) default_t = std::min(default_t, bench::quick_t_end);
  s.t_end = o.t_end > 0 ? o.t_end : default_t;

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

  std::fprintf(stderr, "sesi bench: scene %s, t_end %g, %zu methods\n", name.c_str(), s.t_end,
               s.methods.size());
  bench::Result r;
  if (o.scene == "paper") {
    r = bench::bench_paper(s);
  } else if (o.scene == "kepler-s2") {
    r = bench::bench_kepler_s2(s);
  } else if (o.scene == "kepler-h2") {
    r = bench::bench_kepler_h2(s);
  } else if (scene.space.kind == SpaceKind::sphere) {
    r = bench::bench_file_sphere(scene, s);
  } else {
    r = bench::bench_file_hyperbolic(scene, s);
  }
  const std::string path = dir + "/work_precision.csv";
  write_csv(path, s, r);
  std::printf("wrote %s (%zu rows)\n", path.c_str(), r.rows.size());
  return 0;
}

}  // namespace sesi::program
