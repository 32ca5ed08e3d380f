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
#include <limits>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Core>

#include <sesi/coefficients.hpp>
#include <sesi/diagnostics.hpp>
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
        return embedding<sesi::reference::GeodesicComposition<co::Strang, Chart>>(param, times,
                                                                                  obs);
      case Method::geodesic4:
        return embedding<sesi::reference::GeodesicComposition<co::Yoshida4, Chart>>(param, times,
                                                                                    obs);
      case Method::geodesic6:
        return embedding<sesi::reference::GeodesicComposition<co::Yoshida6, Chart>>(param, times,
                                                                                    obs);
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
    row.method = std::string(m.name);
    row.order = m.order;
    row.dt_or_tol = param;
    Recorder rec{this, nullptr, {}};
    run(m.id, param, times_, rec);
    row.max_energy_error = rec.max_de;
    row.max_momentum_drift = rec.max_dj;
    double best = std::numeric_limits<double>::infinity(), worst = 0;
    sesi::reference::NoObserver none;
    const std::span<const double> no_times;
    int repeats = s_.repeats;
    for (int r = 0; r < repeats; ++r) {
      const auto start = std::chrono::steady_clock::now();
      const Outcome out = run(m.id, param, no_times, none);
      const double secs =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      best = std::min(best, secs);
      worst = std::max(worst, secs);
      if (r == 0) {
        row.steps = out.steps;
        row.force_evals = out.evals;
        row.final_error = distance(out.points, reference);
        if (secs > s_.run_budget / 2) break;  // a long run is its own average
        if (secs < 0.05 && repeats < 2 * s_.repeats) repeats = 2 * s_.repeats;  // noisy: more
      }
    }
    row.wall_seconds = best;
    return worst;
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

  template <class Table, class Obs>
  Outcome composition(double dt, std::span<const double> times, Obs& obs) const {
    StateT x = x0_;
    auto run = [&](auto&& st) {
      return long(sesi::reference::integrate_fixed(st, sys_, x, 0.0, s_.t_end, dt, times, obs));
    };
    long steps = 0;
    switch (form_) {
      case SesiForm::seed:
        steps = run(sesi::Composition<Table, Chart>());
        break;
      case SesiForm::program:
        steps = run(sesi::Composition<Table, Chart, sesi::Splitting::kick_drift_kick>());
        break;
      case SesiForm::program_recharting:
        steps = run(sesi::RechartingComposition<Table, Chart>(sesi::RechartPolicy<double>{}));
        break;
    }
    return {sesi::embedding_points(sys_, x), steps, steps * long(Table::stages)};
  }

  template <class Stepper, class Obs, class Evals>
  Outcome chart_fixed(Stepper& st, double dt, std::span<const double> times, Obs& obs,
                      Evals evals) const {
    StateT x = x0_;
    const long steps = long(sesi::reference::integrate_fixed(st, sys_, x, 0.0, s_.t_end, dt, times, obs));
    return {sesi::embedding_points(sys_, x), steps, long(evals())};
  }

  template <class Stepper, class Obs>
  Outcome embedding(double dt, std::span<const double> times, Obs& obs) const {
    if constexpr (quadric) {
      auto e = sesi::reference::to_embedded(sys_, x0_);
      Stepper st;
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

}  // namespace sesi::program::bench
