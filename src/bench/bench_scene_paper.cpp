// `sesi bench --scene paper`: the seed's three bodies on S^2 (shared/paper-scene.md) against the
// exact solution (sesi/scenes/paper.hpp), and the data of the seed's two figures.
#include <chrono>
#include <cstdio>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include <sesi/scenes/paper.hpp>

#include "bench_harness.hpp"
#include "bench_scenes.hpp"
#include "errors.hpp"

namespace sesi::program::bench {

namespace {

namespace paper = sesi::scenes::paper;
using PaperSystem = decltype(paper::make_system<double>());

/// Exact positions of the three bodies at t (ambient x bodies).
Eigen::MatrixXd exact_points(double t) {
  const paper::Exact exact;
  Eigen::MatrixXd X(3, 3);
  for (int b = 0; b < 3; ++b) X.col(b) = exact.position(b, t).cast<double>();
  return X;
}

std::ofstream open_csv(const std::string& path) {
  std::ofstream out(path);
  if (!out) throw InputError("cannot write " + path);
  out.precision(17);
  return out;
}

}  // namespace

Result bench_paper(const Settings& settings) {
  const auto sys = paper::make_system<double>();
  // By default the program's kick-drift-kick form (no re-charting needed: the bodies stay far
  // from the poles); the seed's figures below keep the seed's own form.
  const SesiForm form = settings.form.value_or(SesiForm::program);
  Harness<PaperSystem> h(sys, paper::initial_state<double>(), settings, Eigen::MatrixXd(), form);
  Result r;
  r.notes.push_back("scene: paper (the seed's three bodies on S^2, shared/paper-scene.md)");
  r.notes.push_back("reference: exact solution (sesi/scenes/paper.hpp, long double)");
  r.notes.push_back(describe(form));
  r.notes.push_back("momentum: all components of the momentum map (L_z, -L_y, L_x)");
  if (!settings.horizons.empty()) {
    r.rows = horizon_sweep(sys, paper::initial_state<double>(), settings, Eigen::MatrixXd(), form);
    return r;
  }
  r.rows = h.sweep_all(exact_points(settings.t_end));
  return r;
}

void paper_fig1(const std::string& dir, double t_end, int repeats) {
  const auto sys = paper::make_system<double>();
  const double tau = paper::Constants<double>::tau;
  Settings s;
  s.t_end = t_end;
  s.samples = static_cast<int>(std::lround(t_end / tau));  // every step
  s.repeats = repeats;
  Harness<PaperSystem> h(sys, paper::initial_state<double>(), s, Eigen::MatrixXd(), SesiForm::seed);
  using H = Harness<PaperSystem>;
  std::vector<TraceRow> trace;
  auto out = open_csv(dir + "/seed_fig1_times.csv");
  out << "# sesi bench --figure seed-fig1: tau = " << tau << ", T = " << t_end
      << "; wall_seconds is the minimum of " << repeats << " runs without observer\n";
  out << "# dopri5: odeint controlled + dense output, abs tol 1e-6, rel tol 1e-3 (MATLAB ode45's "
         "defaults; the seed used a 'commercially available' RK45)\n";
  out << "method,dt_or_tol,steps,force_evals,wall_seconds,max_energy_error\n";
  sesi::reference::NoObserver none;
  const std::span<const double> no_times;
  auto time_runs = [&](auto&& once) {
    double best = std::numeric_limits<double>::infinity();
    for (int k = 0; k < repeats; ++k) {
      const auto start = std::chrono::steady_clock::now();
      once();
      best = std::min(best, std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    }
    return best;
  };
  // dopri5 at the seed's (MATLAB's default) tolerances.
  {
    sesi::odeint::tolerances<double> tol;
    tol.absolute = 1e-6;
    tol.relative = 1e-3;
    tol.initial_step = 1e-3;
    H::Recorder rec{&h, &trace, "dopri5"};
    sesi::odeint::integrate_dopri5(sys, h.initial_state(), 0.0, t_end, tol, std::span<const double>(h.times()), rec);
    sesi::odeint::result<paper::Chart<double>> res;
    const double secs = time_runs([&] { res = sesi::odeint::integrate_dopri5(sys, h.initial_state(), 0.0, t_end, tol); });
    out << "dopri5,1e-3," << res.steps << ',' << res.evaluations << ',' << secs << ',' << rec.max_de << '\n';
  }
  for (Method m : {Method::implicit_midpoint, Method::sesi2, Method::sesi4}) {
    const MethodSpec* spec = nullptr;
    for (const MethodSpec& c : all_methods())
      if (c.id == m) spec = &c;
    H::Recorder rec{&h, &trace, std::string(spec->name)};
    h.run(m, tau, std::span<const double>(h.times()), rec);
    Outcome o;
    const double secs = time_runs([&] { o = h.run(m, tau, no_times, none); });
    out << spec->name << ',' << tau << ',' << o.steps << ',' << o.evals << ',' << secs << ','
        << rec.max_de << '\n';
  }
  auto csv = open_csv(dir + "/seed_fig1.csv");
  csv << "# sesi bench --figure seed-fig1: body 1 on the seed's scene, tau = " << tau
      << "; momentum map components M12, M13, M23 = (L_z, -L_y, L_x)\n";
  csv << "method,t,x,y,z,energy_error,dM12,dM13,dM23\n";
  const paper::Exact exact;
  for (double t : h.times()) {
    const auto p = exact.position(0, t);
    csv << "exact," << t << ',' << double(p[0]) << ',' << double(p[1]) << ',' << double(p[2])
        << ",0,0,0,0\n";
  }
  for (const TraceRow& r : trace) {
    csv << r.method << ',' << r.t << ',' << r.x << ',' << r.y << ',' << r.z << ',' << r.energy_error;
    for (double d : r.momentum_error) csv << ',' << d;
    csv << '\n';
  }
}

namespace {
template <class Table>
void convergence_of(const Harness<PaperSystem>& h, std::ofstream& csv) {
  std::vector<double> steps;
  for (int n = 10; n <= 10 * 4096; n *= 2) steps.push_back(10.0 / n);
  using StateT = sesi::State<paper::Chart<double>>;
  StateT previous = h.template composition_state<Table>(steps[0]);
  for (std::size_t i = 1; i < steps.size(); ++i) {
    const StateT next = h.template composition_state<Table>(steps[i]);
    const double diff = std::sqrt((next.q - previous.q).squaredNorm() + (next.p - previous.p).squaredNorm());
    csv << Table::name << ',' << Table::order << ',' << steps[i - 1] << ',' << diff << '\n';
    previous = next;
  }
}
}  // namespace

void paper_convergence(const std::string& dir) {
  const auto sys = paper::make_system<double>();
  Settings s;
  s.t_end = 10.0;
  s.samples = 1;
  Harness<PaperSystem> h(sys, paper::initial_state<double>(), s, Eigen::MatrixXd(), SesiForm::seed);
  auto csv = open_csv(dir + "/convergence.csv");
  csv << "# sesi bench --figure convergence: |x_dt(10) - x_{dt/2}(10)|, x = (theta, phi, p_theta, "
         "p_phi) of all bodies (Euclidean norm), seed's scene\n";
  csv << "method,order,dt,difference\n";
  convergence_of<co::Strang>(h, csv);
  convergence_of<co::Yoshida4>(h, csv);
  convergence_of<co::Suzuki4>(h, csv);
  convergence_of<co::McLachlan4>(h, csv);
  convergence_of<co::Yoshida6>(h, csv);
  convergence_of<co::KahanLi6>(h, csv);
  convergence_of<co::McLachlan8>(h, csv);
  convergence_of<co::KahanLi8>(h, csv);
}

}  // namespace sesi::program::bench
