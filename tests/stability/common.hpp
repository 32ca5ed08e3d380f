// Shared helpers of the stability tests (issue #5): world-state conversion, isometries, runs,
// energy records and the report lines that docs/stability.md quotes.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/QR>

#include <sesi/sesi.hpp>

namespace stab {

template <class S>
using Mat = Eigen::Matrix<S, Eigen::Dynamic, Eigen::Dynamic>;
template <class S>
using Vec = Eigen::Matrix<S, Eigen::Dynamic, 1>;

/// One measured figure, printed as `[stability] name = value` (docs/stability.md quotes them).
inline void report(const std::string& name, double value) {
  std::printf("[stability] %-64s = %.4g\n", name.c_str(), value);
  std::fflush(stdout);
}

template <class S>
S eps() {
  return std::numeric_limits<S>::epsilon();
}

/// Rotation by angle a in the (i, j) plane of R^dim.
template <class S>
Mat<S> givens(int dim, int i, int j, S a) {
  using std::cos;
  using std::sin;
  Mat<S> g = Mat<S>::Identity(dim, dim);
  g(i, i) = cos(a);
  g(j, j) = cos(a);
  g(i, j) = -sin(a);
  g(j, i) = sin(a);
  return g;
}

/// Lorentz boost of rapidity a along spatial axis i of R^{n,1} (time-like coordinate last).
template <class S>
Mat<S> boost(int dim, int i, S a) {
  using std::cosh;
  using std::sinh;
  Mat<S> b = Mat<S>::Identity(dim, dim);
  b(i, i) = cosh(a);
  b(dim - 1, dim - 1) = cosh(a);
  b(i, dim - 1) = sinh(a);
  b(dim - 1, i) = sinh(a);
  return b;
}

/// The state of sys whose bodies are at world points X moving with velocities V (columns),
/// through the chart's inverse map and cotangent lift (identity frames).
template <class Sys>
sesi::State<typename Sys::Chart> from_world(const Sys& sys, const Mat<typename Sys::Scalar>& X,
                                            const Mat<typename Sys::Scalar>& V) {
  using Chart = typename Sys::Chart;
  sesi::State<Chart> s(sys.dim(), sys.bodies());
  typename Chart::Point q(sys.dim()), p(sys.dim());
  typename Chart::Ambient x(sys.ambient_dim()), v(sys.ambient_dim());
  for (int b = 0; b < sys.bodies(); ++b) {
    x = X.col(b);
    v = V.col(b);
    sys.chart().chart(x, q);
    sys.chart().momentum(q, v, sys.mass(b), p);
    s.q.col(b) = q;
    s.p.col(b) = p;
  }
  return s;
}

/// `steps` steps of dt with stepper st.
template <class Stepper, class Sys, class St>
void run(Stepper& st, const Sys& sys, St& x, typename Sys::Scalar dt, long steps) {
  for (long k = 0; k < steps; ++k) st.do_step(sys, x, typename Sys::Scalar(k) * dt, dt);
}

/// Largest geodesic distance between corresponding columns of two world-point matrices.
template <class Chart, class A, class B>
double max_distance(const Chart& chart, const A& X, const B& Y) {
  typename Chart::Ambient x(chart.ambient_dim()), y(chart.ambient_dim());
  double d = 0;
  for (Eigen::Index b = 0; b < X.cols(); ++b) {
    x = X.col(b);
    y = Y.col(b);
    d = std::max(d, double(chart.distance(x, y)));
  }
  return d;
}

/// Method's table re-charted, as the library recommends (sesi::RechartingComposition).
template <template <class> class Method, class Chart>
using Rech = sesi::RechartingComposition<typename Method<Chart>::table, Chart>;

/// Energy error record of a run: max |E - E0| over the first and the last tenth of the steps.
struct Tenths {
  double first = 0, last = 0, overall = 0;
  long recharts = 0, homes = 0;
  /// last / first: bounded energy error means a ratio of order one (the tests ask <= 2).
  double growth() const { return last / first; }
};

/// Run `steps` steps, recording |E - E0| every `every` steps.
template <class Stepper, class Sys, class St>
Tenths energy_tenths(Stepper& st, const Sys& sys, St& x, typename Sys::Scalar dt, long steps,
                     long every = 1) {
  using Scalar = typename Sys::Scalar;
  auto w = sys.make_workspace();
  const Scalar e0 = sys.energy(x, w);
  Tenths r;
  const long tenth = steps / 10;
  for (long k = 0; k < steps; ++k) {
    st.do_step(sys, x, Scalar(k) * dt, dt);
    if ((k + 1) % every != 0 && k + 1 != steps) continue;
    const double e = std::abs(double(sys.energy(x, w) - e0));
    r.overall = std::max(r.overall, e);
    if (k < tenth) r.first = std::max(r.first, e);
    if (k >= steps - tenth) r.last = std::max(r.last, e);
  }
  if constexpr (requires { st.recharts(); }) {
    r.recharts = st.recharts();
    r.homes = st.homes();
  }
  return r;
}

}  // namespace stab
