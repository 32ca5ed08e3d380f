// No allocation per step (issue #2): after a first step has sized the stepper's workspace, a step
// allocates nothing, for fixed-size and Eigen::Dynamic charts, both forms and several methods.
//
// Two counters, so that neither route to the heap goes unseen: this test's own executable
// replaces the global operator new (std::vector and any other C++ allocation), and Eigen's
// run-time malloc check (EIGEN_RUNTIME_NO_MALLOC, defined before Eigen is included) reports every
// heap allocation of an Eigen object through eigen_assert, redirected here to a counter. The last
// test case checks that both counters see an allocation when there is one.
#include <cmath>
#include <cstddef>
#include <cstdlib>
#include <new>
#include <numbers>
#include <random>
#include <vector>

namespace alloc_counter {
inline bool counting = false;
inline long news = 0;         // operator new calls while counting
inline long eigen_mallocs = 0;  // Eigen heap allocations while counting
inline void eigen_assert_failed() { ++eigen_mallocs; }
}  // namespace alloc_counter

#define EIGEN_RUNTIME_NO_MALLOC
// Eigen's own asserts stay quiet unless they fail; a failure while counting is a heap allocation
// refused by set_is_malloc_allowed(false) (Eigen's only assertion that can fire in this test).
#define eigen_assert(x) ((x) ? static_cast<void>(0) : ::alloc_counter::eigen_assert_failed())

#include <doctest/doctest.h>

#include "common.hpp"

// The thermostats need Random123's headers (tests/core/CMakeLists.txt sets the flag where found).
#if SESI_ALLOC_THERMOSTATS
#include <sesi/thermostat.hpp>
#endif

// ---- the replaced global allocation functions ------------------------------------------------

namespace {
void* counted(std::size_t size) {
  if (alloc_counter::counting) ++alloc_counter::news;
  if (void* p = std::malloc(size == 0 ? 1 : size)) return p;
  throw std::bad_alloc();
}
void* counted_aligned(std::size_t size, std::align_val_t align) {
  if (alloc_counter::counting) ++alloc_counter::news;
  const auto a = static_cast<std::size_t>(align);
  const std::size_t rounded = (size + a - 1) / a * a;
  if (void* p = std::aligned_alloc(a, rounded == 0 ? a : rounded)) return p;
  throw std::bad_alloc();
}
}  // namespace

void* operator new(std::size_t size) { return counted(size); }
void* operator new[](std::size_t size) { return counted(size); }
void* operator new(std::size_t size, const std::nothrow_t&) noexcept {
  try {
    return counted(size);
  } catch (...) {
    return nullptr;
  }
}
void* operator new[](std::size_t size, const std::nothrow_t&) noexcept {
  try {
    return counted(size);
  } catch (...) {
    return nullptr;
  }
}
void* operator new(std::size_t size, std::align_val_t a) { return counted_aligned(size, a); }
void* operator new[](std::size_t size, std::align_val_t a) { return counted_aligned(size, a); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }

namespace {

using namespace coretest;
namespace co = sesi::coefficients;

struct Counts {
  long news = 0, eigen = 0;
};

/// Run f with both counters on.
template <class F>
Counts count(F&& f) {
  alloc_counter::news = 0;
  alloc_counter::eigen_mallocs = 0;
  Eigen::internal::set_is_malloc_allowed(false);
  alloc_counter::counting = true;
  f();
  alloc_counter::counting = false;
  Eigen::internal::set_is_malloc_allowed(true);
  return {alloc_counter::news, alloc_counter::eigen_mallocs};
}

/// One step to size the workspace, then 20 counted steps of stepper.
template <class Stepper, class Sys>
void check_no_allocation_of(Stepper stepper, const Sys& sys, sesi::State<typename Sys::Chart> x) {
  using Scalar = typename Sys::Scalar;
  const Scalar tau = Scalar(0.05);
  stepper.do_step(sys, x, Scalar(0), tau);
  const Counts c = count([&] {
    for (int k = 1; k <= 20; ++k) stepper.do_step(sys, x, Scalar(k) * tau, tau);
  });
  CHECK(c.news == 0);
  CHECK(c.eigen == 0);
}

/// One step to size the workspace, then 20 counted steps.
template <class Method, class Sys>
void check_no_allocation(const Sys& sys, sesi::State<typename Sys::Chart> x) {
  using Scalar = typename Sys::Scalar;
  Method stepper;
  const Scalar tau = Scalar(0.05);
  stepper.do_step(sys, x, Scalar(0), tau);
  const Counts c = count([&] {
    for (int k = 1; k <= 20; ++k) stepper.do_step(sys, x, Scalar(k) * tau, tau);
  });
  INFO(Method::table::name);
  CHECK(c.news == 0);
  CHECK(c.eigen == 0);
}

template <class Chart>
void check_chart(int dim) {
  const auto sys = make_scene<Chart>(dim);
  const auto x0 = initial_state(sys);
  check_no_allocation<sesi::Strang<Chart>>(sys, x0);
  check_no_allocation<sesi::Composition<co::Yoshida4, Chart, sesi::Splitting::kick_drift_kick>>(
      sys, x0);
  // Without a potential (no kick at all).
  const sesi::System<Chart> free(sys.chart(), sys.masses());
  check_no_allocation<sesi::Yoshida4<Chart>>(free, x0);
}

#if SESI_ALLOC_THERMOSTATS
/// Every thermostat kind (issue #25), without re-charting: wrapped in sesi::Recharting these steps
/// allocate (one operator new in 20 steps on S^3, about 5 Eigen allocations a step on the dynamic
/// chart), which is re-charting's, not the thermostat's.
template <class Chart>
void check_thermostats(int dim) {
  const auto sys = make_scene<Chart>(dim);
  const auto x0 = initial_state(sys);
  using Kind = sesi::ThermostatKind;
  for (const Kind kind : {Kind::langevin, Kind::nose_hoover, Kind::csvr, Kind::brownian}) {
    INFO("thermostat kind " << static_cast<int>(kind));
    sesi::ThermostatParams<double> p;
    p.kind = kind;
    p.kT = 0.5;
    p.gamma = 2.0;
    p.tau = 0.5;
    p.seed = 3;
    check_no_allocation_of(sesi::Thermostatted<Chart>(sesi::Thermostat<Chart>(p)), sys, x0);
  }
}
#endif

}  // namespace

#if SESI_ALLOC_THERMOSTATS
TEST_CASE("alloc: no allocation per step with a thermostat") {
  check_thermostats<sesi::Sphere<3, double>>(3);
  check_thermostats<sesi::Hyperbolic<2, double>>(2);
  check_thermostats<sesi::Euclidean<3, double>>(3);
  check_thermostats<sesi::Sphere<Eigen::Dynamic, double>>(3);
}
#endif

TEST_CASE("alloc: no allocation per step on fixed-size charts") {
  check_chart<sesi::Sphere<3, double>>(3);
  check_chart<sesi::Hyperbolic<2, double>>(2);
  check_chart<sesi::Euclidean<3, double>>(3);
}

TEST_CASE("alloc: no allocation per step on Eigen::Dynamic charts") {
  check_chart<sesi::Sphere<Eigen::Dynamic, double>>(3);
  check_chart<sesi::Hyperbolic<Eigen::Dynamic, double>>(4);
  check_chart<sesi::Euclidean<Eigen::Dynamic, double>>(3);
}

// Many bodies through a Verlet list (issue #27): the world points of a Lennard-Jones run on S^2
// (rows mode), fed to a Verlet list through several rebuilds after a warm-up, on one thread and on
// two: an update, rebuild included, allocates nothing (NeighbourIndex keeps its buffers'
// capacities with a slack). Counted on the list itself: a whole step also resizes System's pair
// buffers (w.mirror, w.pair_dw, w.pair_omc) when a rebuild finds more pairs, which is System's.
TEST_CASE("alloc: no allocation in Verlet list updates and rebuilds (Lennard-Jones on S^2)") {
  using Chart = sesi::Sphere<2, double>;
  using Scene = sesi::System<Chart, sesi::LennardJones<double>>;
  const int n = 2000;
  // Density 1/2 (radius from 4 pi R^2 = n / 0.5): a Fibonacci lattice, no pair in the repulsive core.
  const Chart chart(std::sqrt(n / 0.5 / (4.0 * std::numbers::pi)));
  const Scene sys(chart, std::vector<double>(static_cast<std::size_t>(n), 1.0), sesi::LennardJones<double>{});
  REQUIRE(sys.by_rows());
  sesi::State<Chart> x(2, n);
  std::mt19937_64 rng(7);
  std::normal_distribution<double> normal;
  const double golden = std::numbers::pi * (3.0 - std::sqrt(5.0)), R = chart.radius();
  Eigen::Vector3d y, v;
  Eigen::Vector2d q, p;
  for (int b = 0; b < n; ++b) {
    const double z = 1.0 - (2.0 * b + 1.0) / n, r = std::sqrt(1.0 - z * z);
    y << R * r * std::cos(golden * b), R * r * std::sin(golden * b), R * z;
    for (int k = 0; k < 3; ++k) v[k] = normal(rng);
    v -= (v.dot(y) / (R * R)) * y;
    chart.chart(y, q);
    chart.momentum(q, v, 1.0, p);
    x.q.col(b) = q;
    x.p.col(b) = p;
  }
  // The run's world points, every step.
  const double tau = 0.005, range = 2.5;
  const int steps = 150;
  std::vector<Eigen::Matrix<double, 3, Eigen::Dynamic>> frames;
  sesi::Strang<Chart> stepper;
  for (int k = 0; k < steps; ++k) {
    stepper.do_step(sys, x, k * tau, tau);
    Eigen::Matrix<double, 3, Eigen::Dynamic> X(3, n);
    for (int b = 0; b < n; ++b) {
      q = x.q.col(b);
      chart.embed(q, y);
      X.col(b) = y;
    }
    frames.push_back(std::move(X));
  }
  REQUIRE(x.q.allFinite());
  for (const int threads : {1, 2}) {
    INFO("threads " << threads);
    sesi::parallel::set_threads(threads);
    sesi::VerletList<Chart> list;
    const int warm = 50;  // the first third: through two rebuilds, so that the buffers have their size
    for (int k = 0; k < warm; ++k) list.update(chart, frames[static_cast<std::size_t>(k)], range);
    const long before = list.builds();
    CHECK(before >= 3);
    const Counts c = count([&] {
      for (int k = warm; k < steps; ++k) list.update(chart, frames[static_cast<std::size_t>(k)], range);
    });
    const long rebuilds = list.builds() - before;
    MESSAGE("threads ", threads, ": ", rebuilds, " list rebuilds in ", steps - warm, " counted updates");
    CHECK(rebuilds >= 2);  // the counted updates went through rebuilds
    CHECK(list.visit_order().size() == static_cast<std::size_t>(n));
    CHECK(c.news == 0);
    CHECK(c.eigen == 0);
  }
  sesi::parallel::set_threads(0);
}

TEST_CASE("alloc: the counters see allocations") {
  const Counts c = count([] {
    Eigen::VectorXd v(16);  // one Eigen heap allocation
    v.setZero();
    // One operator new: called directly and kept through a volatile pointer, since compilers may
    // elide a new-expression (clang does) but not this.
    void* volatile p = ::operator new(16);
    ::operator delete(p);
  });
  CHECK(c.eigen == 1);
  CHECK(c.news == 1);
}
