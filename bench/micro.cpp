// Micro-benchmarks of the pieces of a step (Google Benchmark), on the seed's scene
// (include/sesi/scenes/paper.hpp: three bodies on S^2). After the runs it prints ratios of
// times measured in this same run: the two forms of the base step, a step against one force
// evaluation, an odeint dopri5 step (six right-hand sides) against a SESI 2 step, and a homing
// against a turn. docs/benchmarks.md quotes them; `make microbench` runs it.
#include <benchmark/benchmark.h>

#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include <boost/numeric/odeint/stepper/runge_kutta_dopri5.hpp>
#include <sesi/odeint.hpp>
#include <sesi/scenes/paper.hpp>
#include <sesi/sesi.hpp>

namespace {

namespace paper = sesi::scenes::paper;
using Chart = paper::Chart<double>;
using Form = sesi::Splitting;

template <class Table, Form F>
void BM_step(benchmark::State& state) {
  const auto sys = paper::make_system<double>();
  auto x = paper::initial_state<double>();
  sesi::Composition<Table, Chart, F> st;
  const double dt = paper::Constants<double>::tau;
  double t = 0;
  for (auto _ : state) {
    st.do_step(sys, x, t, dt);
    t += dt;
    benchmark::DoNotOptimize(x.p.data());
  }
}
BENCHMARK(BM_step<sesi::coefficients::Strang, Form::drift_kick_drift>)->Name("step/sesi2/drift-kick-drift");
BENCHMARK(BM_step<sesi::coefficients::Strang, Form::kick_drift_kick>)->Name("step/sesi2/kick-drift-kick");
BENCHMARK(BM_step<sesi::coefficients::Yoshida4, Form::drift_kick_drift>)->Name("step/sesi4/drift-kick-drift");
BENCHMARK(BM_step<sesi::coefficients::Yoshida4, Form::kick_drift_kick>)->Name("step/sesi4/kick-drift-kick");

/// One force evaluation as a kick (trig refresh, embedding, pair gradients, pull-back).
void BM_kick(benchmark::State& state) {
  const auto sys = paper::make_system<double>();
  auto x = paper::initial_state<double>();
  auto w = sys.make_workspace();
  for (auto _ : state) {
    sys.kick(x, 0.0, w);
    benchmark::DoNotOptimize(x.p.data());
  }
}
BENCHMARK(BM_kick)->Name("force/kick");

/// A fixed step of odeint's Dormand-Prince 5(4) on the chart ODE (the seed's RK45).
void BM_dopri5(benchmark::State& state) {
  const auto sys = paper::make_system<double>();
  const auto x0 = paper::initial_state<double>();
  sesi::odeint::chart_ode ode(sys);
  std::vector<double> y;
  sesi::reference::to_flat(x0, y);
  boost::numeric::odeint::runge_kutta_dopri5<std::vector<double>> st;
  const double dt = paper::Constants<double>::tau;
  double t = 0;
  for (auto _ : state) {
    st.do_step(std::ref(ode), y, t, dt);
    t += dt;
    benchmark::DoNotOptimize(y.data());
  }
}
BENCHMARK(BM_dopri5)->Name("step/dopri5");

/// Re-charting one body of S^2: a turn (rank-one frame update) and a homing (a new frame from
/// the body's point and velocity, QR completion, chart and momenta recomputed).
template <bool Home>
void BM_rechart(benchmark::State& state) {
  const Chart chart(1.0);
  Chart::Point q(2), p(2), qo(2), po(2);
  q << 0.3, 1.0;
  p << -0.8, 0.4;
  Chart::Ambient x(3), v(3);
  chart.embed(q, x);
  chart.velocity(q, p, 1.0, v);
  sesi::State<Chart>::Frame change(3, 3), frame = sesi::State<Chart>::Frame::Identity();
  const sesi::RechartPolicy<double> policy;
  for (auto _ : state) {
    if constexpr (Home) {
      chart.home(x, v, 1.0, policy, change, qo, po);
    } else {
      chart.turn(q, change);
    }
    frame = (frame * change).eval();
    benchmark::DoNotOptimize(frame.data());
  }
}
BENCHMARK(BM_rechart<false>)->Name("rechart/turn");
BENCHMARK(BM_rechart<true>)->Name("rechart/home");

/// The console report, keeping each benchmark's CPU time per iteration for the ratios (CPU
/// time, not wall time: on a shared machine waiting for a core is not the code's cost).
class Recorder : public benchmark::ConsoleReporter {
 public:
  void ReportRuns(const std::vector<Run>& runs) override {
    for (const Run& r : runs) {
      if (r.run_type == Run::RT_Iteration) times[r.benchmark_name()] = r.GetAdjustedCPUTime();
    }
    ConsoleReporter::ReportRuns(runs);
  }
  std::map<std::string, double> times;
};

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  Recorder recorder;
  benchmark::RunSpecifiedBenchmarks(&recorder);
  benchmark::Shutdown();
  const auto& t = recorder.times;
  const auto ratio = [&](const char* what, const char* a, const char* b) {
    const auto ia = t.find(a), ib = t.find(b);
    if (ia == t.end() || ib == t.end()) return;  // filtered out
    std::printf("ratio %-48s %8.3f  (%s / %s)\n", what, ia->second / ib->second, a, b);
  };
  std::printf("\nRatios of times measured in this run:\n");
  ratio("kick-drift-kick / drift-kick-drift, sesi2", "step/sesi2/kick-drift-kick", "step/sesi2/drift-kick-drift");
  ratio("kick-drift-kick / drift-kick-drift, sesi4", "step/sesi4/kick-drift-kick", "step/sesi4/drift-kick-drift");
  ratio("sesi2 step / one force evaluation", "step/sesi2/drift-kick-drift", "force/kick");
  ratio("sesi4 step / sesi2 step (3 stages)", "step/sesi4/drift-kick-drift", "step/sesi2/drift-kick-drift");
  ratio("dopri5 step / sesi2 step", "step/dopri5", "step/sesi2/drift-kick-drift");
  ratio("dopri5 step / sesi4 step", "step/dopri5", "step/sesi4/drift-kick-drift");
  ratio("homing / turn", "rechart/home", "rechart/turn");
  return 0;
}
