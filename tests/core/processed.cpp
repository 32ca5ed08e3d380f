// Processed methods (issue #15, include/sesi/processed.hpp): Psi_h = P^{-1} K_h P, the kernel
// stepped and the processor applied where the state is read.
//
// What is checked, and why the bounds hold:
//  - effective order: the post-processed final states of runs at N, 2N, 4N steps differ by
//    C h^p (1 + O(h^2)), p the table's effective order, while the kernel alone (its variables read
//    as the state) is of order 4: the measured order within 0.3 of p, at step counts where it is
//    asymptotic, p + O(h^2) (measured within 0.29: 6.14 5.92 5.98 5.91 5.94; 8.29 7.79 8.00 8.18;
//    10.19 10.04 9.93 10.17 10.07; order 10 on S^3 and H^3 at N = 3, where N = 2 gives 10.42 and
//    N = 4 meets the floor). A kernel read without
//    processing, or processed the wrong way round, is of order 4, 4 or more away. Long double:
//    the tables' 15 digits leave the order conditions satisfied to about 1e-15, and the
//    differences stop falling at 1e-17 .. 1e-16 of the state (measured on these scenes at
//    2 to 8 times the steps used here); the guard keeps d2 above 10 times 1e-16 of the state and
//    30 times the round-off of the runs, and the step counts are the smallest powers of two at
//    which the runs are asymptotic.
//  - the kernel is a palindromic composition: one step of tau then one of -tau returns the state
//    within the round-off bound of tests/core/reversibility.cpp, 2 s (2n + 1)(n + 4) eps |z|.
//  - post_process(pre_process(y)) = y: P^{-1} P = id exactly in real arithmetic (S(a)^{-1} =
//    S(-a)); the same derivation with 2m base steps instead of 2s: 2m (2n + 1)(n + 4) eps |y|.
//  - the processed energy error is smaller than the kernel's own at the same step: measured on
//    the seed's scene, asserted with the margin stated there.
//  - resume(dt) after saving the kernel's variables goes on bit for bit; the runtime table steps
//    bit for bit as the compile-time one; a change of step re-enters.
//  - re-charting (S^2, bodies crossing the chart's poles): leaving the kernel's variables around
//    each re-charting keeps the effective order (RechartingProcessed).
#include <cmath>
#include <numbers>
#include <tuple>

#include <doctest/doctest.h>

#include <sesi/diagnostics.hpp>
#include <sesi/processed.hpp>
#include <sesi/scenes/paper.hpp>

#include "common.hpp"

namespace {

using namespace coretest;
namespace co = sesi::coefficients;
using Kdk = std::integral_constant<sesi::Splitting, sesi::Splitting::kick_drift_kick>;
using Dkd = std::integral_constant<sesi::Splitting, sesi::Splitting::drift_kick_drift>;

/// The post-processed state after `steps` steps of t_end/steps with a fresh Stepper.
template <class Stepper, class Sys>
sesi::State<typename Sys::Chart> run_processed(const Sys& sys, sesi::State<typename Sys::Chart> x,
                                               typename Sys::Scalar t_end, long steps) {
  using Scalar = typename Sys::Scalar;
  Stepper stepper;
  const Scalar dt = t_end / Scalar(steps);
  stepper.pre_process(sys, x, dt);
  for (long k = 0; k < steps; ++k) stepper.do_step(sys, x, Scalar(k) * dt, dt);
  sesi::State<typename Sys::Chart> y;
  stepper.post_process(sys, x, y);
  return y;
}

template <class Stepper, class Sys>
OrderMeasurement measure_processed(const Sys& sys, const sesi::State<typename Sys::Chart>& x0,
                                   typename Sys::Scalar t_end, long steps) {
  const auto a = run_processed<Stepper>(sys, x0, t_end, steps);
  const auto b = run_processed<Stepper>(sys, x0, t_end, 2 * steps);
  const auto c = run_processed<Stepper>(sys, x0, t_end, 4 * steps);
  const double d1 = static_cast<double>(distance(a, b)), d2 = static_cast<double>(distance(b, c));
  return {std::log2(d1 / d2), d1, d2, static_cast<double>(size_of(c))};
}

/// Effective order of Table's processed method, and order 4 of its kernel alone, in Form.
template <class Table, sesi::Splitting Form, class Sys>
void effective_order(const Sys& sys, const sesi::State<typename Sys::Chart>& x0,
                     typename Sys::Scalar t_end, long steps, const std::string& scene) {
  using Chart = typename Sys::Chart;
  using Scalar = typename Chart::Scalar;
  const std::string form = Form == sesi::Splitting::kick_drift_kick ? "kdk" : "dkd";
  const auto m = measure_processed<sesi::Processed<Table, Chart, Form>>(sys, x0, t_end, steps);
  MESSAGE(Table::name, " ", form, " on ", scene, ", N = ", steps, ": order ", m.order, "  d1 ", m.d1,
          " d2 ", m.d2);
  // Round-off of 4N steps of s kernel stages and two processings, and the digits' floor.
  const double roundoff = static_cast<double>(eps<Scalar>()) * m.scale *
                          double(4 * steps * Table::kernel::stages + 2 * Table::processor_stages);
  CHECK(m.d2 > 30 * roundoff);
  CHECK(m.d2 > 10 * 1e-16 * m.scale);
  CHECK(std::abs(m.order - double(Table::order)) <= 0.3);  // p + O(h^2), asymptotic at these N (above)

  // The kernel alone, its variables taken for the state: order 4.
  const auto k = measure_order<sesi::Composition<typename Table::kernel, Chart, Form>>(sys, x0, t_end, steps);
  MESSAGE(Table::name, " kernel alone ", form, " on ", scene, ": order ", k.order);
  CHECK(std::abs(k.order - 4.0) <= 0.3);
}

using ProcessedTables =
    std::tuple<co::Blanes6Processed, co::BlanesCasasMurua8Processed, co::BlanesCasasMurua10Processed>;


}  // namespace

TEST_CASE_TEMPLATE_DEFINE("processed: effective order on the seed's scene, S^3, H^3 and E^3", Table,
                          processed_orders) {
  using Real = long double;
  // N for each scene (the seed's to t = 2, the others to scene_time()).
  constexpr int p = Table::order;
  constexpr long seed = p == 8 ? 16 : 8, curved = p == 6 ? 8 : p == 8 ? 4 : 3, flat = p == 6 ? 16 : 8;
  {
    namespace paper = sesi::scenes::paper;
    const auto sys = paper::make_system<Real>();
    const auto x0 = paper::initial_state<Real>();
    effective_order<Table, sesi::Splitting::drift_kick_drift>(sys, x0, Real(2), seed, "the seed's S^2");
    effective_order<Table, sesi::Splitting::kick_drift_kick>(sys, x0, Real(2), seed, "the seed's S^2");
  }
  {
    using Chart = sesi::Sphere<3, Real>;
    const auto sys = make_scene<Chart>();
    effective_order<Table, sesi::Splitting::kick_drift_kick>(sys, initial_state(sys), scene_time<Chart>(),
                                                             curved, "S^3");
  }
  {
    using Chart = sesi::Hyperbolic<3, Real>;
    const auto sys = make_scene<Chart>();
    effective_order<Table, sesi::Splitting::kick_drift_kick>(sys, initial_state(sys), scene_time<Chart>(),
                                                             curved, "H^3");
  }
  // (E^3 at order 8: this scene's h^8 error constant is small, and the measured order is 9.4 at
  // N = 4 and 8, 8.8 at N = 16 where the differences reach the floor; not measured here.)
  if constexpr (p != 8) {
    using Chart = sesi::Euclidean<3, Real>;
    const auto sys = make_scene<Chart>();
    effective_order<Table, sesi::Splitting::drift_kick_drift>(sys, initial_state(sys), scene_time<Chart>(),
                                                              flat, "E^3");
  }
}
TEST_CASE_TEMPLATE_APPLY(processed_orders, ProcessedTables);

TEST_CASE_TEMPLATE_DEFINE("processed: the kernel is reversible, P^{-1} P = id, on S^3 and H^2", Table,
                          processed_reversible) {
  const auto check = [&]<class Chart, sesi::Splitting Form>() {
    using Scalar = typename Chart::Scalar;
    const auto sys = make_scene<Chart>();
    std::mt19937 rng(11);
    const Scalar n = Scalar(sys.dim());
    const Scalar per_stage = (Scalar(2) * n + Scalar(1)) * (n + Scalar(4)) * eps<Scalar>();
    sesi::Composition<typename Table::kernel, Chart, Form> kernel;
    for (int s = 0; s < 3; ++s) {
      const auto x0 = random_state(sys, rng);
      const Scalar tau(0.1);
      auto x = x0;
      kernel.do_step(sys, x, Scalar(0), tau);
      kernel.do_step(sys, x, tau, -tau);
      const Scalar bound = Scalar(2 * Table::kernel::stages) * per_stage * size_of(x0);
      const Scalar err = distance(x, x0);
      MESSAGE(Table::name, " kernel +tau -tau: error/bound ", double(err / bound),
              std::string(err == Scalar(0) ? " (bit for bit)" : ""));
      CHECK(err <= bound);

      sesi::Processed<Table, Chart, Form> stepper;
      auto z = x0;
      stepper.pre_process(sys, z, tau);
      CHECK(stepper.entered());
      CHECK(distance(z, x0) > Scalar(1e3) * bound);  // z is not the state
      sesi::State<Chart> y;
      stepper.post_process(sys, z, y);
      const Scalar pbound = Scalar(2 * Table::processor_stages) * per_stage * size_of(x0);
      const Scalar perr = distance(y, x0);
      MESSAGE(Table::name, " P^{-1} P: error/bound ", double(perr / pbound));
      CHECK(perr <= pbound);
      stepper.leave(sys, z);
      CHECK(!stepper.entered());
      CHECK(distance(z, y) == Scalar(0));  // leave is post_process in place
    }
  };
  check.template operator()<sesi::Sphere<3, double>, sesi::Splitting::drift_kick_drift>();
  check.template operator()<sesi::Sphere<3, double>, sesi::Splitting::kick_drift_kick>();
  check.template operator()<sesi::Hyperbolic<2, double>, sesi::Splitting::kick_drift_kick>();
}
TEST_CASE_TEMPLATE_APPLY(processed_reversible, ProcessedTables);

TEST_CASE("processed: energy error below the kernel's own on the seed's scene") {
  // Max |E - E0| over t in [0, 200] (2000 steps of 0.1, the seed's step), read after every step:
  // the processed method's from post_process, the kernel's from its own variables.
  namespace paper = sesi::scenes::paper;
  const auto sys = paper::make_system<double>();
  const auto x0 = paper::initial_state<double>();
  auto w = sys.make_workspace();
  const double e0 = sys.energy(x0, w), tau = 0.1;
  const auto measure = [&]<class Table>() {
    sesi::Processed<Table, paper::Chart<double>, sesi::Splitting::kick_drift_kick> stepper;
    auto z = x0;
    sesi::State<paper::Chart<double>> y;
    double processed = 0, kernel = 0;
    for (int k = 0; k < 2000; ++k) {
      stepper.do_step(sys, z, k * tau, tau);
      stepper.post_process(sys, z, y);
      processed = std::max(processed, std::abs(sys.energy(y, w) - e0));
      kernel = std::max(kernel, std::abs(sys.energy(z, w) - e0));
    }
    MESSAGE(Table::name, " kdk, tau 0.1: max energy error processed ", processed, ", kernel alone ", kernel,
            ", ratio ", kernel / processed);
    return std::pair{processed, kernel};
  };
  const auto [p6, k6] = measure.template operator()<co::Blanes6Processed>();
  const auto [p8, k8] = measure.template operator()<co::BlanesCasasMurua8Processed>();
  const auto [p10, k10] = measure.template operator()<co::BlanesCasasMurua10Processed>();
  // Measured (GCC 12, x86-64): see the MESSAGE lines; asserted: at least 10 times smaller.
  CHECK(p6 * 10 < k6);
  CHECK(p8 * 10 < k8);
  CHECK(p10 * 10 < k10);
}

TEST_CASE("processed: resume goes on bit for bit; runtime table = compile-time table") {
  namespace paper = sesi::scenes::paper;
  using Chart = paper::Chart<double>;
  const auto sys = paper::make_system<double>();
  const auto x0 = paper::initial_state<double>();
  const double tau = 0.1;
  using Table = co::BlanesCasasMurua8Processed;
  sesi::Processed<Table, Chart, sesi::Splitting::kick_drift_kick> whole;
  auto z = x0;
  for (int k = 0; k < 40; ++k) whole.do_step(sys, z, k * tau, tau);

  sesi::Processed<Table, Chart, sesi::Splitting::kick_drift_kick> first;
  auto saved = x0;
  for (int k = 0; k < 17; ++k) first.do_step(sys, saved, k * tau, tau);
  // A new stepper, no caches: the kernel's variables as saved.
  auto resumed = sesi::Processed<co::Runtime, Chart, sesi::Splitting::kick_drift_kick>::of<Table>();
  resumed.resume(tau);
  for (int k = 17; k < 40; ++k) resumed.do_step(sys, saved, k * tau, tau);
  CHECK(saved.q == z.q);
  CHECK(saved.p == z.p);
  sesi::State<Chart> a, b;
  whole.post_process(sys, z, a);
  resumed.post_process(sys, saved, b);
  CHECK(a.q == b.q);
  CHECK(a.p == b.p);
  CHECK(resumed.order() == 8);
  CHECK(resumed.stages() == 13);
  CHECK(resumed.processor_stages() == 20);
}

TEST_CASE("processed: a change of step re-enters; do_step enters a fresh state") {
  namespace paper = sesi::scenes::paper;
  using Chart = paper::Chart<double>;
  const auto sys = paper::make_system<double>();
  const auto x0 = paper::initial_state<double>();
  using Table = co::Blanes6Processed;
  // do_step on a fresh state = pre_process, then do_step.
  sesi::Processed<Table, Chart> a, b;
  auto za = x0, zb = x0;
  a.do_step(sys, za, 0.0, 0.1);
  b.pre_process(sys, zb, 0.1);
  b.do_step(sys, zb, 0.0, 0.1);
  CHECK(za.q == zb.q);
  CHECK(za.p == zb.p);
  // A step of 0.05 after steps of 0.1 = leaving, entering with 0.05, stepping.
  a.do_step(sys, za, 0.1, 0.05);
  CHECK(a.entered_step() == 0.05);
  b.leave(sys, zb);
  b.pre_process(sys, zb, 0.05);
  b.do_step(sys, zb, 0.1, 0.05);
  CHECK(za.q == zb.q);
  CHECK(za.p == zb.p);
  // post_process of a state not entered is the state.
  sesi::Processed<Table, Chart> fresh;
  sesi::State<Chart> y;
  fresh.post_process(sys, x0, y);
  CHECK(y.q == x0.q);
  CHECK(y.p == x0.p);
}

TEST_CASE("processed: effective order across re-chartings (bodies crossing the poles of S^2)") {
  // Two bodies joined by a spring on the unit sphere, both heading for the chart's poles
  // (examples/scenes/sphere-pole-crossing.toml), to t = 6: every run re-charts (and so leaves and
  // re-enters the kernel's variables) once. The world points and velocities of the final states
  // at N, 2N, 4N steps (their charts may differ), in long double; the measured order within 0.3
  // where it is asymptotic: 6.02 (N = 120) and 10.11 (N = 80; 10.30 at 60, and 10.91, 10.64 at
  // 90, 100, where the re-chartings fall differently). Order 8 is not asymptotic on this scene
  // above the floor (12.1, 9.3, 8.7, 8.7, 8.4, 8.3 at N = 30, 60, 120, 160, 180, 200, where the
  // differences reach 1e-16), approaching 8 from above: it is checked from below, at least
  // 8 - 0.3, which tells it from the 4 measured when the kernel's variables are re-charted
  // without leaving them (docs/scheme.md).
  using Real = long double;
  using Chart = sesi::Sphere<2, Real>;
  const auto sys = sesi::System(Chart(Real(1)), std::vector<Real>{Real(1), Real(0.5)},
                                sesi::HarmonicPair<Real>{Real(1), std::numbers::pi_v<Real> / 2});
  using Vec = Eigen::Matrix<Real, Eigen::Dynamic, 1>;
  sesi::State<Chart> x0(2, 2);
  const Chart::Ambient X[2] = {{1, 0, 0}, {0, -1, 0}}, V[2] = {{0, 0, 1}, {0.3L, 0, 0.8L}};
  for (int b = 0; b < 2; ++b) {
    Chart::Point q, p;
    sys.chart().chart(X[b], q);
    sys.chart().momentum(q, V[b], sys.mass(b), p);
    x0.q.col(b) = q;
    x0.p.col(b) = p;
  }
  const Real t_end = 6;
  const auto final_world = [&]<class Table>(long steps, long& reentries) {
    sesi::RechartingProcessed<Table, Chart> stepper;
    auto z = x0;
    const Real dt = t_end / Real(steps);
    for (long k = 0; k < steps; ++k) stepper.do_step(sys, z, Real(k) * dt, dt);
    sesi::State<Chart> y;
    stepper.post_process(sys, z, y);
    reentries = stepper.reentries();
    const auto Xs = sesi::embedding_points(sys, y);
    const auto Vs = sesi::embedding_velocities(sys, y);
    Vec out(Xs.size() + Vs.size());
    out << Xs.reshaped(), Vs.reshaped();
    return out;
  };
  const auto check = [&]<class Table>(long steps) {
    long r1 = 0, r2 = 0, r3 = 0;
    const Vec a = final_world.template operator()<Table>(steps, r1);
    const Vec b = final_world.template operator()<Table>(2 * steps, r2);
    const Vec c = final_world.template operator()<Table>(4 * steps, r3);
    const double d1 = double((a - b).cwiseAbs().maxCoeff()), d2 = double((b - c).cwiseAbs().maxCoeff());
    MESSAGE(Table::name, " across re-chartings, N = ", steps, ": order ", std::log2(d1 / d2), "  d1 ", d1,
            " d2 ", d2, ", re-entries ", r1, " ", r2, " ", r3);
    CHECK(r1 >= 1);
    CHECK(r2 >= 1);
    CHECK(r3 >= 1);
    CHECK(d2 > 10 * 1e-16);
    const double order = std::log2(d1 / d2);
    if (Table::order == 8) {
      CHECK(order >= 8 - 0.3);  // pre-asymptotic from above (see the top of the case)
    } else {
      CHECK(std::abs(order - double(Table::order)) <= 0.3);  // p + O(h^2), asymptotic at these N
    }
  };
  check.template operator()<co::Blanes6Processed>(120);
  check.template operator()<co::BlanesCasasMurua8Processed>(120);
  check.template operator()<co::BlanesCasasMurua10Processed>(80);
}
