#pragma once
/// @file bench_types.hpp
/// `sesi bench` (issue #4): the methods it compares, its settings and one CSV row per run.
/// Compiled once (bench_command.cpp); the templated harness is bench_harness.hpp.

#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace sesi::program::bench {

enum class Method {
  sesi2, sesi4, sesi4_suzuki, sesi4_mclachlan, sesi6, sesi6_kahan_li, sesi8, sesi8_kahan_li,
  sesi6_processed, sesi8_processed, sesi10_processed, dopri5, rk78, bulirsch_stoer, rk4,
  implicit_midpoint, gauss4, tao2, tao4, rattle, geodesic2, geodesic4, geodesic6,
  geodesic6_kahan_li, geodesic8, geodesic8_kahan_li, geodesic6_processed, geodesic8_processed,
  geodesic10_processed
};

enum class Family { chart, adaptive, fixed_reference, embedding };

struct MethodSpec {
  Method id;
  std::string_view name;  ///< as on the command line and in the CSV
  int order;
  Family family;
};

/// Every method, in CSV order.
std::span<const MethodSpec> all_methods();
/// The method called name, or nullptr.
const MethodSpec* find_method(std::string_view name);

/// One run of one method at one step (or tolerance).
struct Row {
  std::string method;
  int order = 0;
  double dt_or_tol = 0;
  long steps = 0;
  long force_evals = 0;
  double wall_seconds = 0;
  double final_error = 0;
  double max_energy_error = 0;
  double max_momentum_drift = 0;
  double t_end = 0;       ///< the run's length (the horizon, with --horizons)
  long samples = 0;       ///< distinct times the error run observed (a step boundary each)
  int timed_runs = 0;     ///< timed repeats behind wall_seconds
};

/// Which form of the base step the sesi* rows run (sesi/stepper.hpp, docs/scheme.md).
enum class SesiForm {
  seed,                ///< drift-kick-drift, the seed's form, the library default; no re-charting
  program,             ///< kick-drift-kick, as `sesi run` steps; no re-charting
  program_recharting,  ///< kick-drift-kick with re-charting: exactly what `sesi run` does
};

/// The CSV's `# sesi rows:` note for a form.
inline const char* describe(SesiForm f) {
  switch (f) {
    case SesiForm::seed: return "sesi rows: drift-kick-drift form (the seed's), no re-charting";
    case SesiForm::program: return "sesi rows: kick-drift-kick form, as sesi run steps, no re-charting";
    case SesiForm::program_recharting:
      return "sesi rows: kick-drift-kick form with re-charting, as sesi run steps";
  }
  return "";
}

struct Settings {
  double t_end = 0;         ///< length of every run
  int samples = 1000;       ///< common observation times: t_end * j / samples, j = 0..samples
  int repeats = 3;          ///< timed repeats (the minimum is reported)
  bool quick = false;       ///< a short sweep (ctest)
  double run_budget = 20;   ///< seconds: a sweep stops refining after a run this long
  /// --form: the form of the sesi* rows (program: with re-charting on scene files); none: the
  /// scene's own choice.
  std::optional<SesiForm> form;
  std::vector<const MethodSpec*> methods;
  std::vector<double> dts;       ///< --dts: every fixed-step method's steps (empty: its sweep)
  std::vector<double> tols;      ///< --tols: every adaptive method's tolerances (empty: its sweep)
  std::vector<double> horizons;  ///< --horizons: run lengths of the horizon sweep (empty: none)
  std::vector<double> levels;    ///< --levels: max energy error levels of the horizon sweep
};

/// One sample of a traced run (seed-fig1): body 1's position, the energy error and the
/// momentum-map error (all components).
struct TraceRow {
  std::string method;
  double t = 0;
  double x = 0, y = 0, z = 0;
  double energy_error = 0;
  std::vector<double> momentum_error;
};

/// What a scene's bench returns: the rows and the comment lines for the CSV header.
struct Result {
  std::vector<Row> rows;
  std::vector<std::string> notes;
};

/// Sweep parameters of a method: steps dt = base / k (fixed-step methods; base = t_end /
/// samples, so that every sample time is a grid point), or tolerances (adaptive ones); --dts
/// and --tols replace them.
std::vector<double> sweep(const MethodSpec& m, const Settings& s);

/// The default steps (tolerances) of the horizon sweep: param(k) = 10^(-k / per_decade) for
/// integers k in [k_min, k_max], started at k_start. Fixed steps of order p take 4p rungs per
/// decade (the energy error ~ dt^p then moves by about a quarter decade per rung); tolerances 4.
struct Ladder {
  int per_decade = 2;
  int k_start = 0, k_min = 0, k_max = 0;
  double param(int k) const;
};
Ladder horizon_ladder(const MethodSpec& m);

}  // namespace sesi::program::bench
