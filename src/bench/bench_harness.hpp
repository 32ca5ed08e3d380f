#pragma once
/// @file bench_harness.hpp
/// The work-precision harness of `sesi bench` (issue #4), templated on the system; each scene's
/// file (bench_scene_*.cpp) instantiates it once, so the instantiations compile in parallel.
///
/// Fair measurement (issue #4, "Fair measurement"):
///  - every run of a method is done twice: a timed run with no observer (no diagnostics, no
///    output), repeated `repeats` times, the minimum wall time reported; and an error run,
///    identical but observing the state at the common times t_end * j / samples;
///  - fixed-step runs use reference::integrate_fixed (the step never changes for sampling: the
///    two runs are bit for bit the same); dopri5 and Bulirsch-Stoer sample through odeint's
///    dense output (same steps as the timed run but for the last one); rk78 has no dense output
///    in odeint, so its error run shortens the steps that straddle a sample time;
///  - final_error is measured on the timed run's final state: the largest geodesic distance of a
///    body from its reference position (exact solution or reference run, stated in the CSV);
///  - max_energy_error: max over the samples of |E(t) - E(0)|; max_momentum_drift: max over the
///    samples of the Euclidean norm of the change of the conserved momentum-map components
///    (sesi::momentum_map, diagnostics.hpp), both computed in double on the chart state (the
///    embedding methods' states are mapped to the chart by reference::to_chart).

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <functional>
#include <limits>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Core>

#include <sesi/coefficients.hpp>
#include <sesi/diagnostics.hpp>
#include <sesi/processed.hpp>
#include <sesi/recharting.hpp>
#include <sesi/reference/embedding.hpp>
#include <sesi/reference/implicit.hpp>
#include <sesi/reference/integrate.hpp>
#include <sesi/reference/odeint.hpp>
#include <sesi/reference/tao.hpp>
#include <sesi/stepper.hpp>

#include "bench_types.hpp"

namespace sesi::program::bench {

namespace co = sesi::coefficients;

/// Where a run ends: the bodies' embedding points (ambient x bodies), steps and force
/// evaluations (potential-gradient evaluations: kicks of the compositions, right-hand sides of
/// the ODE methods, force evaluations of the embedding methods).
struct Outcome {
  Eigen::MatrixXd points;
  long steps = 0;
  long evals = 0;
};

template <class Sys>
class Harness {
 public:
  using Chart = typename Sys::Chart;
  using StateT = sesi::State<Chart>;
  static constexpr bool quadric = sesi::reference::QuadricChart<Chart>;

  /// @param conserved rows select the conserved components of the momentum map (empty: all).
  /// @param form which form of the SESI compositions the sesi* rows run (SesiForm).
  Harness(const Sys& sys, StateT x0, Settings settings, Eigen::MatrixXd conserved,
          SesiForm form)
      : sys_(sys), x0_(std::move(x0)), s_(std::move(settings)),
        conserved_(std::move(conserved)), form_(form) {
    e0_ = sys_.energy(x0_);
    j0_ = sesi::momentum_map(sys_, x0_);
    for (int j = 0; j <= s_.samples; ++j) times_.push_back(s_.t_end * j / s_.samples);
  }

  double initial_energy() const { return e0_; }

  /// Run method id with step (or tolerance) param from 0 to t_end, observing at `times`.
  template <class Obs>
  Outcome run(Method id, double param, std::span<const double> times, Obs& obs) const {
    switch (id) {
      case Method::sesi2: return composition<co::Strang>(param, times, obs);
      case Method::sesi4: return composition<co::Yoshida4>(param, times, obs);
      case Method::sesi4_suzuki: return composition<co::Suzuki4>(param, times, obs);
      case Method::sesi4_mclachlan: return composition<co::McLachlan4>(param, times, obs);
      case Method::sesi6: return composition<co::Yoshida6>(param, times, obs);
      case Method::sesi6_kahan_li: return composition<co::KahanLi6>(param, times, obs);
      case Method::sesi8: return composition<co::McLachlan8>(param, times, obs);
      case Method::sesi8_kahan_li: return composition<co::KahanLi8>(param, times, obs);
      case Method::sesi6_processed: return processed<co::Blanes6Processed>(param, times, obs);
      case Method::sesi8_processed:
        return processed<co::BlanesCasasMurua8Processed>(param, times, obs);
      case Method::sesi10_processed:
        return processed<co::BlanesCasasMurua10Processed>(param, times, obs);
      case Method::dopri5:
        return odeint_result(
            sesi::odeint::integrate_dopri5(sys_, x0_, 0.0, s_.t_end, tolerance(param), times, obs));
      case Method::rk78:
        return odeint_result(sesi::odeint::integrate_fehlberg78(sys_, x0_, 0.0, s_.t_end,
                                                                tolerance(param), times, obs));
      case Method::bulirsch_stoer:
        return odeint_result(sesi::odeint::integrate_bulirsch_stoer(
            sys_, x0_, 0.0, s_.t_end, tolerance(param), times, obs));
      case Method::rk4:
        return odeint_result(
            sesi::odeint::integrate_rk4(sys_, x0_, 0.0, s_.t_end, param, times, obs));
      case Method::implicit_midpoint: {
        sesi::reference::ImplicitMidpoint<Chart> st;
        return chart_fixed(st, param, times, obs, [&] { return st.statistics().evaluations; });
      }
      case Method::gauss4: {
        sesi::reference::Gauss4<Chart> st;
        return chart_fixed(st, param, times, obs, [&] { return st.statistics().evaluations; });
      }
      case Method::tao2: {
        sesi::reference::Tao2<Chart> st;
        return chart_fixed(st, param, times, obs, [&] { return st.evaluations(); });
      }
      case Method::tao4: {
        sesi::reference::Tao4<Chart> st;
        return chart_fixed(st, param, times, obs, [&] { return st.evaluations(); });
      }
      case Method::rattle:
        return embedding<sesi::reference::RattleComposition<co::Strang, Chart>>(param, times, obs);
      case Method::geodesic2:
        return geodesic<co::Strang>(param, times, obs);
      case Method::geodesic4:
        return geodesic<co::Yoshida4>(param, times, obs);
      case Method::geodesic6:
        return geodesic<co::Yoshida6>(param, times, obs);
      case Method::geodesic6_kahan_li:
        return geodesic<co::KahanLi6>(param, times, obs);
      case Method::geodesic8:
        return geodesic<co::McLachlan8>(param, times, obs);
      case Method::geodesic8_kahan_li:
        return geodesic<co::KahanLi8>(param, times, obs);
      case Method::geodesic6_processed:
        return embedding_processed<co::Blanes6Processed>(param, times, obs);
      case Method::geodesic8_processed:
        return embedding_processed<co::BlanesCasasMurua8Processed>(param, times, obs);
      case Method::geodesic10_processed:
        return embedding_processed<co::BlanesCasasMurua10Processed>(param, times, obs);
    }
    throw std::logic_error("unknown method");
  }

  /// Observer of the error runs: energy and momentum-map errors at each sample; optionally a
  /// trace of every sample (seed-fig1).
  struct Recorder {
    const Harness* h;
    std::vector<TraceRow>* trace = nullptr;
    std::string name;
    double max_de = 0, max_dj = 0;
    long count = 0;
    void operator()(const StateT& x, double t) {
      const double de = std::abs(h->sys_.energy(x) - h->e0_);
      const Eigen::VectorXd dj = sesi::momentum_map(h->sys_, x) - h->j0_;
      const double djn = h->conserved_.rows() > 0 ? (h->conserved_ * dj).norm() : dj.norm();
      if (!std::isfinite(de) || !std::isfinite(djn)) {
        max_de = max_dj = std::numeric_limits<double>::infinity();
      } else {
        max_de = std::max(max_de, de);
        max_dj = std::max(max_dj, djn);
      }
      ++count;
      if (trace) {
        TraceRow r;
        r.method = name;
        r.t = t;
        const auto X = sesi::embedding_points(h->sys_, x);
        r.x = X(0, 0);
        r.y = X.rows() > 1 ? X(1, 0) : 0.0;
        r.z = X.rows() > 2 ? X(2, 0) : 0.0;
        r.energy_error = h->sys_.energy(x) - h->e0_;
        r.momentum_error.assign(dj.data(), dj.data() + dj.size());
        trace->push_back(std::move(r));
      }
    }
    template <class C>
    void operator()(const sesi::reference::EmbeddedState<C>& e, double t) {
      (*this)(sesi::reference::to_chart(h->sys_, e), t);
    }
  };

  /// Largest geodesic distance of a body from its reference position.
  double distance(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) const {
    // (H^n's distance maps a NaN chord to 0: a diverged run must not look exact.)
    if (!a.allFinite()) return std::numeric_limits<double>::infinity();
    double worst = 0;
    typename Chart::Ambient x(sys_.ambient_dim()), y(sys_.ambient_dim());
    for (int k = 0; k < a.cols(); ++k) {
      x = a.col(k);
      y = b.col(k);
      const double d = sys_.chart().distance(x, y);
      if (!std::isfinite(d)) return std::numeric_limits<double>::infinity();
      worst = std::max(worst, d);
    }
    return worst;
  }

  /// The work-precision sweep of every method of the settings against reference positions
  /// (ambient x bodies at t_end).
  std::vector<Row> sweep_all(const Eigen::MatrixXd& reference) const {
    std::vector<Row> rows;
    for (const MethodSpec* m : s_.methods) {
      if (m->family == Family::embedding && !quadric) {
        std::fprintf(stderr, "sesi bench: %s skipped (embedding methods need S^n or H^n)\n",
                     std::string(m->name).c_str());
        continue;
      }
      for (double param : sweep(*m, s_)) {
        Row row;
        double seconds = 0;
        try {
          seconds = measure(*m, param, reference, row);
        } catch (const std::exception& e) {
          std::fprintf(stderr, "sesi bench: %s at %g failed (%s); row left out\n",
                       std::string(m->name).c_str(), param, e.what());
          continue;
        }
        if (!std::isfinite(row.final_error) || !std::isfinite(row.max_energy_error)) {
          std::fprintf(stderr, "sesi bench: %s at %g diverged; row left out\n",
                       std::string(m->name).c_str(), param);
        } else {
          rows.push_back(row);
          std::fprintf(stderr, "  %-16s %-10.4g steps %-9ld evals %-10ld %9.3e s  err %.2e  dE %.2e\n",
                       row.method.c_str(), param, row.steps, row.force_evals, row.wall_seconds,
                       row.final_error, row.max_energy_error);
        }
        if (seconds > s_.run_budget) break;  // finer steps cost more still
      }
    }
    return rows;
  }

  /// One row: the error run, then the timed repeats. Returns the slowest single run's seconds.
  double measure(const MethodSpec& m, double param, const Eigen::MatrixXd& reference,
                 Row& row) const {
    observe(m, param, row);
    return time_runs(m, param, &reference, s_.repeats, true, row);
  }

  /// The error run of a row: max energy error and momentum drift over the sample times.
  void observe(const MethodSpec& m, double param, Row& row) const {
    row.method = std::string(m.name);
    row.order = m.order;
    row.dt_or_tol = param;
    row.t_end = s_.t_end;
    Recorder rec{this, nullptr, {}};
    if (m.id == Method::rk78 && !s_.horizons.empty()) {
      rk78_on_own_steps(param, rec);
    } else {
      run(m.id, param, times_, rec);
    }
    row.max_energy_error = rec.max_de;
    row.max_momentum_drift = rec.max_dj;
    row.samples = rec.count;
  }

  /// Timed runs without observer, `repeats` of them (with more_when_short twice as many when the
  /// first takes under 0.05 s; one when it takes over half the run budget); keeps the minimum in
  /// row.wall_seconds (lowering it, when the row was timed before). The first sets steps,
  /// evaluations and, given a reference, the final error. Returns the slowest run's seconds.
  double time_runs(const MethodSpec& m, double param, const Eigen::MatrixXd* reference,
                   int repeats, bool more_when_short, Row& row) const {
    double best = row.timed_runs > 0 ? row.wall_seconds : std::numeric_limits<double>::infinity();
    double worst = 0;
    sesi::reference::NoObserver none;
    const std::span<const double> no_times;
    const int wanted = repeats;
    for (int r = 0; r < repeats; ++r) {
      const auto start = std::chrono::steady_clock::now();
      const Outcome out = run(m.id, param, no_times, none);
      const double secs =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      best = std::min(best, secs);
      worst = std::max(worst, secs);
      ++row.timed_runs;
      if (r == 0) {
        row.steps = out.steps;
        row.force_evals = out.evals;
        row.final_error = reference ? distance(out.points, *reference)
                                    : std::numeric_limits<double>::quiet_NaN();
        if (secs > s_.run_budget / 2) break;  // a long run is its own average
        if (more_when_short && secs < 0.05 && repeats < 2 * wanted) repeats = 2 * wanted;  // noisy
      }
    }
    row.wall_seconds = best;
    return worst;
  }

  /// The horizon sweep's runs of one method at this harness's t_end (docs/benchmarks.md, "Long
  /// horizons"): the steps (tolerances) of --dts (--tols) from the coarsest, or else the
  /// method's ladder, coarser from its start while a run reaches the largest level, then finer
  /// until a run reaches the smallest level; either way finer runs stop after a run longer than
  /// the run budget (or one predicted to take three budgets), and on the ladder after three
  /// rungs without a smaller error (a round-off floor). Every run is timed once; the fastest
  /// run reaching each level gets the remaining timed repeats.
  std::vector<Row> horizon_runs(const MethodSpec& m) const {
    std::vector<Row> rows;
    if (m.family == Family::embedding && !quadric) {
      std::fprintf(stderr, "sesi bench: %s skipped (embedding methods need S^n or H^n)\n",
                   std::string(m.name).c_str());
      return rows;
    }
    const double largest = *std::max_element(s_.levels.begin(), s_.levels.end());
    const double smallest = *std::min_element(s_.levels.begin(), s_.levels.end());
    double last_seconds = 0, before_seconds = 0;
    // One run; false when it failed or diverged (no row).
    auto attempt = [&](double param) -> const Row* {
      Row row;
      try {
        observe(m, param, row);
        if (std::isfinite(row.max_energy_error)) {
          before_seconds = last_seconds;
          last_seconds = time_runs(m, param, nullptr, 1, false, row);
        }
      } catch (const std::exception& e) {
        std::fprintf(stderr, "sesi bench: %s at %g failed (%s); no row\n",
                     std::string(m.name).c_str(), param, e.what());
        return nullptr;
      }
      if (!std::isfinite(row.max_energy_error)) {
        std::fprintf(stderr, "sesi bench: %s at %g diverged; no row\n",
                     std::string(m.name).c_str(), param);
        return nullptr;
      }
      std::fprintf(stderr, "  T %-8g %-16s %-10.4g steps %-10ld %9.3e s  dE %.2e\n", s_.t_end,
                   row.method.c_str(), param, row.steps, row.wall_seconds, row.max_energy_error);
      rows.push_back(row);
      return &rows.back();
    };
    // Finer runs only cost more: stop after a long one, or before one predicted too long.
    auto over_budget = [&] {
      if (last_seconds > s_.run_budget) return true;
      return before_seconds > 0 && last_seconds > s_.run_budget / 4 &&
             last_seconds * (last_seconds / before_seconds) > 3 * s_.run_budget;
    };
    const std::vector<double>& given = m.family == Family::adaptive ? s_.tols : s_.dts;
    if (!given.empty()) {
      std::vector<double> params = given;
      std::sort(params.begin(), params.end(), std::greater<>());
      for (double p : params) {
        const Row* r = attempt(p);
        if ((r && r->max_energy_error <= smallest) || over_budget()) break;
      }
    } else {
      const Ladder ladder = horizon_ladder(m);
      // Coarser while the start already reaches the largest level (cheaper runs might too).
      const Row* r = attempt(ladder.param(ladder.k_start));
      const double start_seconds = r ? r->wall_seconds : 0;
      for (int k = ladder.k_start - 1; r && r->max_energy_error <= largest && k >= ladder.k_min; --k)
        r = attempt(ladder.param(k));
      last_seconds = start_seconds;  // the finer rungs go on from the start
      before_seconds = 0;
      double best = std::numeric_limits<double>::infinity();
      int stale = 0;
      for (const Row& row : rows) best = std::min(best, row.max_energy_error);
      // Until a run succeeds (the start may be past a scene's stability limit, e.g. a close
      // pericentre), failures go finer for up to one decade of the step; after that, three rungs
      // without a smaller error end the walk.
      int failed = 0;
      for (int k = ladder.k_start + 1; best > smallest && k <= ladder.k_max; ++k) {
        if (over_budget()) break;
        r = attempt(ladder.param(k));
        const double e = r ? r->max_energy_error : std::numeric_limits<double>::infinity();
        if (!std::isfinite(best)) {
          if (!r && ++failed > ladder.per_decade) break;  // diverges at every step tried
        } else if (e < 0.9 * best) {
          stale = 0;
        } else if (++stale >= 3) {
          break;  // no gain from finer steps: round-off (or a diverging method)
        }
        best = std::min(best, e);
      }
    }
    // The remaining repeats for the fastest run reaching each level.
    std::vector<std::size_t> winners;
    for (double level : s_.levels) {
      std::size_t w = rows.size();
      for (std::size_t i = 0; i < rows.size(); ++i)
        if (rows[i].max_energy_error <= level &&
            (w == rows.size() || rows[i].wall_seconds < rows[w].wall_seconds))
          w = i;
      if (w < rows.size() && std::find(winners.begin(), winners.end(), w) == winners.end())
        winners.push_back(w);
    }
    for (std::size_t w : winners) {
      Row& row = rows[w];
      const int total = row.wall_seconds < 0.05 ? 2 * s_.repeats : s_.repeats;
      if (row.wall_seconds <= s_.run_budget / 2 && total > row.timed_runs)
        time_runs(m, row.dt_or_tol, nullptr, total - row.timed_runs, false, row);
    }
    std::sort(rows.begin(), rows.end(),
              [](const Row& a, const Row& b) { return a.dt_or_tol > b.dt_or_tol; });
    return rows;
  }

  /// rk78's error run in the horizon sweep: the timed run's own steps (odeint's
  /// integrate_adaptive, observed after every step), each sample time at the first step boundary
  /// at or after it. (Shortening steps to land on the times, as run() does, makes a run whose
  /// steps exceed the sample spacing far more accurate than the timed one.)
  template <class Obs>
  Outcome rk78_on_own_steps(double tol, Obs& obs) const {
    namespace ode = boost::numeric::odeint;
    using Flat = std::vector<double>;
    sesi::odeint::chart_ode<Sys> f(sys_);
    Flat y = f.flat(x0_);
    StateT x;
    std::size_t j = 0;
    auto at_step = [&](const Flat& yk, double t) {
      bool due = false;
      for (; j < times_.size() && times_[j] <= t; ++j) due = true;
      if (due) {
        f.unflat(yk, x);
        obs(static_cast<const StateT&>(x), t);
      }
    };
    const auto tol_ = tolerance(tol);
    const long steps = long(ode::integrate_adaptive(
        ode::make_controlled(tol_.absolute, tol_.relative, ode::runge_kutta_fehlberg78<Flat, double>()),
        std::ref(f), y, 0.0, s_.t_end, tol_.initial_step, at_step));
    f.unflat(y, x);
    if (j < times_.size()) obs(static_cast<const StateT&>(x), s_.t_end);  // round-off at the end
    return {sesi::embedding_points(sys_, x), steps, long(f.evaluations())};
  }

  /// Reference positions at t_end from the order-8 composition sesi8-kahan-li with step
  /// t_end / n; *estimate = their distance from the run with step 2 t_end / n.
  Eigen::MatrixXd reference_run(long n, double* estimate) const {
    sesi::reference::NoObserver none;
    const Outcome fine = composition<co::KahanLi8>(s_.t_end / double(n), {}, none);
    const Outcome coarse = composition<co::KahanLi8>(s_.t_end / double(n / 2), {}, none);
    *estimate = distance(fine.points, coarse.points);
    return fine.points;
  }

  const std::vector<double>& times() const { return times_; }
  const Sys& system() const { return sys_; }
  const StateT& initial_state() const { return x0_; }

  /// The final chart state of a composition (convergence figure).
  template <class Table>
  StateT composition_state(double dt) const {
    StateT x = x0_;
    sesi::Composition<Table, Chart> st;
    sesi::reference::integrate_fixed(st, sys_, x, 0.0, s_.t_end, dt);
    return x;
  }

 private:
  static sesi::odeint::tolerances<double> tolerance(double tol) {
    sesi::odeint::tolerances<double> t;
    t.absolute = tol;
    t.relative = tol;
    t.initial_step = 1e-3;
    return t;
  }
  Outcome odeint_result(const sesi::odeint::result<Chart>& r) const {
    return {sesi::embedding_points(sys_, r.state), long(r.steps), long(r.evaluations)};
  }

  // The compositions, processed and geodesic methods run on the engines of runtime tables (the
  // program's): one engine per form for every table, stepping bit for bit as the fixed table's
  // (tests/program/integrators/test_runtime_composition.cpp, tests/core/processed.cpp), so that a
  // scene compiles a few engines instead of a few per table.
  using Dkd = sesi::Composition<co::Runtime, Chart>;
  using Kdk = sesi::Composition<co::Runtime, Chart, sesi::Splitting::kick_drift_kick>;
  using ProcessedDkd = sesi::Processed<co::Runtime, Chart>;
  using ProcessedKdk = sesi::Processed<co::Runtime, Chart, sesi::Splitting::kick_drift_kick>;

  template <class Table, class Obs>
  Outcome composition(double dt, std::span<const double> times, Obs& obs) const {
    StateT x = x0_;
    auto run = [&](auto&& st) {
      return long(sesi::reference::integrate_fixed(st, sys_, x, 0.0, s_.t_end, dt, times, obs));
    };
    long steps = 0;
    switch (form_) {
      case SesiForm::seed:
        steps = run(Dkd::template of<Table>());
        break;
      case SesiForm::program:
        steps = run(Kdk::template of<Table>());
        break;
      case SesiForm::program_recharting:
        steps = run(sesi::RechartingComposition<co::Runtime, Chart>(sesi::RechartPolicy<double>{},
                                                                    Kdk::template of<Table>()));
        break;
    }
    return {sesi::embedding_points(sys_, x), steps, steps * long(Table::stages)};
  }

  /// A processed method (sesi/processed.hpp) in the form of the sesi* rows: the state enters the
  /// kernel's variables once, and every observed state (and the final one) is post-processed, as
  /// `sesi run` outputs it; each costs the processor's stages, counted in the evaluations.
  template <class Table, class Obs>
  Outcome processed(double dt, std::span<const double> times, Obs& obs) const {
    switch (form_) {
      case SesiForm::seed: return processed_run<Table>(ProcessedDkd::template of<Table>(), dt, times, obs);
      case SesiForm::program:
        return processed_run<Table>(ProcessedKdk::template of<Table>(), dt, times, obs);
      case SesiForm::program_recharting:
        return processed_run<Table>(sesi::RechartingProcessed<co::Runtime, Chart>(
                                        sesi::RechartPolicy<double>{}, ProcessedKdk::template of<Table>()),
                                    dt, times, obs);
    }
    throw std::logic_error("unknown form");
  }

  /// A processed geodesic method (reference::GeodesicProcessed), read as processed() reads.
  template <class Table, class Obs>
  Outcome embedding_processed(double dt, std::span<const double> times, Obs& obs) const {
    if constexpr (quadric) {
      return processed_run<Table>(sesi::reference::GeodesicProcessed<co::Runtime, Chart>::template of<Table>(),
                                  sesi::reference::to_embedded(sys_, x0_), dt, times, obs);
    } else {
      throw std::logic_error("embedding methods need S^n or H^n");
    }
  }

  template <class Table, class Stepper, class Obs>
  Outcome processed_run(Stepper st, double dt, std::span<const double> times, Obs& obs) const {
    return processed_run<Table>(std::move(st), x0_, dt, times, obs);
  }

  /// The processed run of Table's method from x0 (a chart or an embedded state): enter, step,
  /// read through post_process, leave.
  template <class Table, class Stepper, class State0, class Obs>
  Outcome processed_run(Stepper st, const State0& x0, double dt, std::span<const double> times, Obs& obs) const {
    using S = typename Stepper::state_type;
    S x = x0, y = x0;
    long reads = 0;
    auto read = [&](const S& z, double t) {
      st.post_process(sys_, z, y);
      ++reads;
      obs(static_cast<const S&>(y), t);
    };
    st.pre_process(sys_, x, dt);
    const long steps = long(sesi::reference::integrate_fixed(st, sys_, x, 0.0, s_.t_end, dt, times, read));
    st.leave(sys_, x);
    long entries = 2 + reads;  // P once, P^{-1} at the end and at each read
    if constexpr (requires { st.reentries(); }) entries += 2 * st.reentries();
    Eigen::MatrixXd points;
    if constexpr (std::is_same_v<S, StateT>) {
      points = sesi::embedding_points(sys_, x);
    } else {
      points = x.x;
    }
    return {points, steps, steps * long(Table::kernel::stages) + entries * long(Table::processor_stages)};
  }

  template <class Stepper, class Obs, class Evals>
  Outcome chart_fixed(Stepper& st, double dt, std::span<const double> times, Obs& obs,
                      Evals evals) const {
    StateT x = x0_;
    const long steps = long(sesi::reference::integrate_fixed(st, sys_, x, 0.0, s_.t_end, dt, times, obs));
    return {sesi::embedding_points(sys_, x), steps, long(evals())};
  }

  /// A geodesic method: the geodesic splitting with Table's weights (on the runtime table's engine).
  template <class Table, class Obs>
  Outcome geodesic(double dt, std::span<const double> times, Obs& obs) const {
    if constexpr (quadric) {
      return embedding(sesi::reference::GeodesicComposition<co::Runtime, Chart>::template of<Table>(), dt,
                       times, obs);
    } else {
      throw std::logic_error("embedding methods need S^n or H^n");
    }
  }

  template <class Stepper, class Obs>
  Outcome embedding(double dt, std::span<const double> times, Obs& obs) const {
    if constexpr (quadric) {
      return embedding(Stepper(), dt, times, obs);
    } else {
      throw std::logic_error("embedding methods need S^n or H^n");
    }
  }

  template <class Stepper, class Obs>
  Outcome embedding(Stepper st, double dt, std::span<const double> times, Obs& obs) const {
    if constexpr (quadric) {
      auto e = sesi::reference::to_embedded(sys_, x0_);
      const long steps = long(sesi::reference::integrate_fixed(st, sys_, e, 0.0, s_.t_end, dt, times, obs));
      return {Eigen::MatrixXd(e.x), steps, long(st.evaluations())};
    } else {
      throw std::logic_error("embedding methods need S^n or H^n");
    }
  }

  const Sys& sys_;
  StateT x0_;
  Settings s_;
  Eigen::MatrixXd conserved_;
  SesiForm form_;
  double e0_ = 0;
  Eigen::VectorXd j0_;
  std::vector<double> times_;
};

/// The horizon sweep (--horizons): every method of the settings at every horizon, each horizon
/// with its own sample times (settings.samples + 1 of them, from 0 to the horizon).
template <class Sys>
std::vector<Row> horizon_sweep(const Sys& sys, const sesi::State<typename Sys::Chart>& x0,
                               const Settings& settings, const Eigen::MatrixXd& conserved,
                               SesiForm form) {
  std::vector<Row> rows;
  for (double horizon : settings.horizons) {
    Settings s = settings;
    s.t_end = horizon;
    const Harness<Sys> h(sys, x0, s, conserved, form);
    for (const MethodSpec* m : s.methods) {
      std::vector<Row> runs = h.horizon_runs(*m);
      rows.insert(rows.end(), runs.begin(), runs.end());
    }
  }
  return rows;
}

}  // namespace sesi::program::bench
