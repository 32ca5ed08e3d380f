// Pole grazing (issue #5): orbits passing 1e-3, 1e-6 and 1e-9 rad from a chart pole of S^2 and
// S^3, integrated with re-charting, against the same orbit tilted 45 degrees away from the pole
// (the initial world state rotated by an orthogonal matrix), same method and step. Free motion
// is compared with the exact great circle; a cotangent-gravity pair with a tight reference run
// (Kahan-Li 8 at 1/8 of the step, rotated: the dynamics is invariant under rotations).
#include <doctest/doctest.h>

#include <numbers>

#include "common.hpp"

namespace {

using stab::givens;
using stab::Mat;
using stab::report;
using stab::Vec;
using S = double;

/// A chart pole and how an orbit approaches it: the pole point `pole` (a point of the chart's
/// singular set), the unit offset direction `offset` (tangent at the pole, pointing away from
/// the singular set) and the direction of motion `motion` at closest approach.
struct Pole {
  Vec<S> pole, offset, motion;
  std::string name;
};

/// The pole q_1 = 0 of S^n (x = e_{n+1}), approached from a generic direction (rotations that
/// fix e_{n+1} keep the distance to it).
Pole main_pole(int n) {
  const int a = n + 1;
  Mat<S> g = givens<S>(a, 0, 1, 0.7);
  if (n >= 3) g = g * givens<S>(a, 1, 2, 0.5) * givens<S>(a, 0, 2, 0.3);
  Pole p{Vec<S>::Unit(a, a - 1), g.col(0), g.col(1), "pole q1=0"};
  return p;
}
/// On S^3, the singular circle of the second angle (sin q_2 = 0: x_1 = x_2 = 0), at q_1 = 0.8,
/// crossed transversally.
Pole inner_pole() {
  Vec<S> s = Vec<S>::Zero(4);
  s[2] = std::sin(0.8);
  s[3] = std::cos(0.8);
  Mat<S> g = givens<S>(4, 0, 1, 0.7);  // rotations in (x_1, x_2) keep the circle
  return Pole{s, g.col(0), g.col(1), "circle q2=0"};
}

/// The orthogonal map taking the orthonormal triple (a, b, c) to (A, B, C), completed on the
/// orthogonal complements by Householder QR.
Mat<S> map_triple(const Vec<S>& a, const Vec<S>& b, const Vec<S>& c, const Vec<S>& A,
                  const Vec<S>& B, const Vec<S>& C) {
  const int n = static_cast<int>(a.size());
  auto complete = [n](const Vec<S>& x, const Vec<S>& y, const Vec<S>& z) {
    Mat<S> lead(n, 3);
    lead << x, y, z;
    Mat<S> q(n, n);
    sesi::detail::complete_orthonormal(lead, q);
    return q;
  };
  return complete(A, B, C) * complete(a, b, c).transpose();
}

struct Pair {
  double graze = 0, tilted = 0, plain = 0;
  long recharts = 0;
};

/// Free motion on S^n, R = 1, speed 1, for time 3 centred on the closest approach delta.
template <int N, template <class> class Method>
Pair free_orbit(const Pole& pole, double delta, double dt, sesi::RechartPolicy<S> policy) {
  using Chart = sesi::Sphere<N, S>;
  const auto sys = sesi::System(Chart(1.0), std::vector<S>{1.0});
  const double t_half = 1.5;
  const long steps = std::lround(2 * t_half / dt);
  Pair out;
  for (int mode = 0; mode < 3; ++mode) {  // grazing + re-charting, tilted + re-charting, plain
    const double off = delta + (mode == 1 ? std::numbers::pi / 4 : 0.0);
    const Vec<S> c = std::cos(off) * pole.pole + std::sin(off) * pole.offset;
    auto at = [&](double t) { return Vec<S>(std::cos(t) * c + std::sin(t) * pole.motion); };
    auto vel = [&](double t) { return Vec<S>(-std::sin(t) * c + std::cos(t) * pole.motion); };
    auto x = stab::from_world(sys, Mat<S>(at(-t_half)), Mat<S>(vel(-t_half)));
    if (mode < 2) {
      stab::Rech<Method, Chart> st(policy);
      sesi::rechart(sys, x, policy);
      stab::run(st, sys, x, dt, steps);
      if (mode == 0) out.recharts = st.recharts();
    } else {
      Method<Chart> st;
      stab::run(st, sys, x, dt, steps);
    }
    const double err = stab::max_distance(sys.chart(), sesi::embedding_points(sys, x),
                                          Mat<S>(at(t_half)));
    (mode == 0 ? out.graze : mode == 1 ? out.tilted : out.plain) = err;
  }
  return out;
}

/// A cotangent-gravity pair on S^n (masses 1 and 0.3, G = 1, separation 0.5, orbiting while
/// drifting), for time 4. Body 0 is made to pass delta from the pole at t = 2.
template <int N, template <class> class Method>
Pair gravity_pair(const Pole& pole, double delta, double dt, sesi::RechartPolicy<S> policy) {
  using Chart = sesi::Sphere<N, S>;
  constexpr int a = N + 1;
  const auto sys = sesi::System(Chart(1.0), std::vector<S>{1.0, 0.3}, sesi::CotangentGravity<S>{1.0});
  const double t_end = 4.0;
  const long steps = std::lround(t_end / dt);
  // The base scene in a generic orientation.
  const double d = 0.5, vrel = 1.6, drift = 0.8;
  auto e = [](int i) { return Vec<S>(Vec<S>::Unit(a, i)); };
  Mat<S> X(a, 2), V(a, 2);
  X.col(0) = e(a - 1);
  X.col(1) = std::cos(d) * e(a - 1) + std::sin(d) * e(0);
  V.col(0) = (-vrel * 0.3 / 1.3) * e(1) + drift * e(0);
  V.col(1) = (vrel / 1.3) * e(1) + drift * (std::cos(d) * e(0) - std::sin(d) * e(a - 1));
  if (N >= 3) {
    V.col(0) += 0.3 * e(2);
    V.col(1) += 0.3 * e(2);
  }
  Mat<S> g = givens<S>(a, 0, 1, 0.7) * givens<S>(a, 1, a - 1, 0.9) * givens<S>(a, 0, a - 1, 0.4);
  if (N >= 3) g = g * givens<S>(a, 1, 2, 0.5);
  X = g * X;
  V = g * V;
  // Reference: Kahan-Li 8 at dt/8 with re-charting, at t_end/2 and t_end.
  auto reference = [&](double t, Mat<S>& xo, Mat<S>& vo) {
    auto x = stab::from_world(sys, X, V);
    stab::Rech<sesi::KahanLi8, Chart> st;
    sesi::rechart(sys, x, st.policy());
    stab::run(st, sys, x, dt / 8, std::lround(t / (dt / 8)));
    xo = sesi::embedding_points(sys, x);
    vo = sesi::embedding_velocities(sys, x);
  };
  Mat<S> xm, vm, xe, ve;
  reference(t_end / 2, xm, vm);
  reference(t_end, xe, ve);
  // The point at delta from body 0 at t_end/2, normal to its velocity, is taken to the pole.
  const Vec<S> xa = xm.col(0), va = vm.col(0).normalized();
  Mat<S> lead(a, 2);
  lead << xa, va;
  Mat<S> basis(a, a);
  sesi::detail::complete_orthonormal(lead, basis);
  const Vec<S> normal = basis.col(2);
  const Vec<S> p = std::cos(delta) * xa + std::sin(delta) * normal;
  const Vec<S> toward = (xa - xa.dot(p) * p).normalized();
  const Vec<S> along = (va - va.dot(p) * p - va.dot(toward) * toward).normalized();
  const Mat<S> q_graze = map_triple(p, toward, along, pole.pole, pole.offset, pole.motion);
  // Tilt: rotate by 45 degrees in the (pole, offset) plane, away from the singular set.
  Mat<S> lead3(a, 2);
  lead3 << pole.pole, pole.offset;
  Mat<S> b3(a, a);
  sesi::detail::complete_orthonormal(lead3, b3);
  const Mat<S> tilt = b3 * givens<S>(a, 1, 0, std::numbers::pi / 4) * b3.transpose();
  Pair out;
  for (int mode = 0; mode < 3; ++mode) {
    const Mat<S> q = mode == 1 ? Mat<S>(tilt * q_graze) : q_graze;
    auto x = stab::from_world(sys, Mat<S>(q * X), Mat<S>(q * V));
    if (mode < 2) {
      stab::Rech<Method, Chart> st(policy);
      sesi::rechart(sys, x, policy);
      stab::run(st, sys, x, dt, steps);
      if (mode == 0) out.recharts = st.recharts();
    } else {
      Method<Chart> st;
      stab::run(st, sys, x, dt, steps);
    }
    const double err =
        stab::max_distance(sys.chart(), sesi::embedding_points(sys, x), Mat<S>(q * xe));
    (mode == 0 ? out.graze : mode == 1 ? out.tilted : out.plain) = err;
  }
  return out;
}

template <int N, template <class> class Method>
void check(const char* kind, const char* method, const Pole& pole, double dt,
           sesi::RechartPolicy<S> policy, bool assert_bound = true) {
  for (const double delta : {1e-3, 1e-6, 1e-9}) {
    const Pair r = std::string(kind) == "free" ? free_orbit<N, Method>(pole, delta, dt, policy)
                                               : gravity_pair<N, Method>(pole, delta, dt, policy);
    char label[160];
    std::snprintf(label, sizeof label, "poles S^%d %s %s %s dt=%g min_sine=%g delta=%g", N, kind,
                  pole.name.c_str(), method, dt, double(policy.min_sine), delta);
    report(std::string(label) + " graze error", r.graze);
    report(std::string(label) + " tilted error", r.tilted);
    report(std::string(label) + " ratio", r.graze / r.tilted);
    report(std::string(label) + " plain chart (no re-charting) ratio", r.plain / r.tilted);
    report(std::string(label) + " re-chartings", double(r.recharts));
    if (assert_bound) {
      CHECK(r.graze <= 10 * r.tilted);
      CHECK(r.recharts >= 1);
    }
  }
}

/// The default policy (min_sine = 1/2), and min_sine = 1/4, reported without the bound for the
/// order-8 methods, which need the chart's 1/sin^2 factors below 4 (docs/stability.md: with 1/4
/// they lose orders of magnitude in the band 1/4 < sin q < 1/2).
const sesi::RechartPolicy<S> default_policy{};
sesi::RechartPolicy<S> quarter_policy() {
  sesi::RechartPolicy<S> p;
  p.min_sine = S(1) / 4;
  return p;
}

}  // namespace

TEST_CASE("pole grazing: free motion on S^2 and S^3, against the exact great circle") {
  for (const Pole& pole : {main_pole(2)}) {
    check<2, sesi::Strang>("free", "sesi2", pole, 0.01, default_policy);
    check<2, sesi::Yoshida4>("free", "sesi4", pole, 0.05, default_policy);
    check<2, sesi::Yoshida6>("free", "sesi6", pole, 0.1, default_policy);
    check<2, sesi::KahanLi8>("free", "sesi8-kahan-li", pole, 0.1, default_policy);
    check<2, sesi::KahanLi8>("free", "sesi8-kahan-li", pole, 0.1, quarter_policy(), false);
  }
  for (const Pole& pole : {main_pole(3), inner_pole()}) {
    check<3, sesi::Strang>("free", "sesi2", pole, 0.01, default_policy);
    check<3, sesi::Yoshida4>("free", "sesi4", pole, 0.05, default_policy);
    check<3, sesi::Yoshida6>("free", "sesi6", pole, 0.1, default_policy);
    check<3, sesi::KahanLi8>("free", "sesi8-kahan-li", pole, 0.1, default_policy);
    check<3, sesi::KahanLi8>("free", "sesi8-kahan-li", pole, 0.1, quarter_policy(), false);
  }
}

TEST_CASE("pole grazing: a cotangent-gravity pair on S^2 and S^3, against a tight reference") {
  for (const Pole& pole : {main_pole(2)}) {
    check<2, sesi::Strang>("pair", "sesi2", pole, 0.01, default_policy);
    check<2, sesi::Yoshida4>("pair", "sesi4", pole, 0.02, default_policy);
    check<2, sesi::Yoshida6>("pair", "sesi6", pole, 0.05, default_policy);
    check<2, sesi::KahanLi8>("pair", "sesi8-kahan-li", pole, 0.05, default_policy);
    check<2, sesi::KahanLi8>("pair", "sesi8-kahan-li", pole, 0.05, quarter_policy(), false);
  }
  for (const Pole& pole : {main_pole(3), inner_pole()}) {
    check<3, sesi::Strang>("pair", "sesi2", pole, 0.01, default_policy);
    check<3, sesi::Yoshida4>("pair", "sesi4", pole, 0.02, default_policy);
    check<3, sesi::Yoshida6>("pair", "sesi6", pole, 0.05, default_policy);
    check<3, sesi::KahanLi8>("pair", "sesi8-kahan-li", pole, 0.05, default_policy);
    check<3, sesi::KahanLi8>("pair", "sesi8-kahan-li", pole, 0.05, quarter_policy(), false);
  }
}

TEST_CASE("pole grazing: without re-charting the same orbit fails the bound") {
  // The bound can fail: in the plain chart, a pass 1e-3 from the pole costs orders of magnitude.
  const Pair r = free_orbit<2, sesi::Strang>(main_pole(2), 1e-3, 0.01, default_policy);
  report("poles S^2 free sesi2 dt=0.01 delta=0.001 plain chart / tilted", r.plain / r.tilted);
  CHECK(r.plain > 10 * r.tilted);
  const Pair p = gravity_pair<2, sesi::Strang>(main_pole(2), 1e-3, 0.01, default_policy);
  report("poles S^2 pair sesi2 dt=0.01 delta=0.001 plain chart / tilted", p.plain / p.tilted);
  CHECK(p.plain > 10 * p.tilted);
}
