// The cluster frame on H^n (issue #12, item 3): interacting bodies and force centres far from
// the chart origin, integrated in a frame moved to them (State::cluster, docs/charts.md).
//
// Each system (a harmonic pair, a Lennard-Jones cluster of three, a central-cotangent orbit) is
// built near the origin and moved to distance D by an exact isometry, the boost C_D of rapidity D
// (entries cosh D, sinh D): the far state is the near one with cluster frame C_D, its force centre
// the world point C_D o. The pair and the cluster drift at unit speed, so the far runs re-centre
// (recentre(), every ~2 time units); the orbit's frame stays at its centre. Errors are measured on invariants (pair distances, the
// distance to the centre, the energy) against a run of the same system at the origin with a
// quarter of the step; the far errors must be within 10x of the origin's. A run without the
// cluster frame (each body's frame moved by C_D instead) shows the loss the frame removes.
#include <doctest/doctest.h>

#include <string>

#include "common.hpp"

namespace {

using stab::Mat;
using stab::report;
using Chart = sesi::Hyperbolic<2, double>;
using Amb = Chart::Ambient;
using Frame = sesi::State<Chart>::Frame;
template <class C>
using Method = sesi::Yoshida4<C>;
using Stepper = stab::Rech<Method, Chart>;

/// The point at geodesic distance s from the origin in the direction of angle a.
Amb point(double s, double a) {
  return Amb(std::sinh(s) * std::cos(a), std::sinh(s) * std::sin(a), std::cosh(s));
}
/// A tangent vector at x = point(s, a): radial speed vr, angular speed vt (unit-speed basis).
Amb velocity(double s, double a, double vr, double vt) {
  const Amb radial(std::cosh(s) * std::cos(a), std::cosh(s) * std::sin(a), std::sinh(s));
  const Amb angular(-std::sin(a), std::cos(a), 0.0);
  return vr * radial + vt * angular;
}
/// A unit-speed drift along axis 1 at x: the generator of the boost along axis 1 at x.
Amb drift(const Amb& x, double speed) { return speed * Amb(0.0, x[2], x[1]); }

/// The boost C_D along axis 0.
Frame far_frame(double D) {
  Frame c = Frame::Identity();
  c(0, 0) = c(2, 2) = std::cosh(D);
  c(0, 2) = c(2, 0) = std::sinh(D);
  return c;
}

/// Cluster-local points F_b embed(q_b).
template <class Sys>
Mat<double> local_points(const Sys& sys, sesi::State<Chart> s) {
  s.clustered = false;
  return sesi::embedding_points(sys, s);
}
/// The invariants compared: every pair distance and, with a centre (its local point), each
/// body's distance to it.
template <class Sys>
std::vector<double> invariants(const Sys& sys, const sesi::State<Chart>& s, const Amb* centre) {
  const Mat<double> X = local_points(sys, s);
  std::vector<double> out;
  Amb x, y;
  for (int i = 0; i < s.bodies(); ++i) {
    x = X.col(i);
    for (int j = i + 1; j < s.bodies(); ++j) {
      y = X.col(j);
      out.push_back(sys.chart().distance(x, y));
    }
    if (centre) out.push_back(sys.chart().distance(x, *centre));
  }
  return out;
}

struct Errors {
  double invariant = 0, energy = 0;
  int recentred = 0;
};

/// Run s for `steps` steps of dt with re-charting (and re-centring); returns the largest
/// invariant error against the reference `ref` (same length) at the end and the largest energy
/// error along the way.
template <class Sys>
Errors run(const Sys& sys, sesi::State<Chart> s, double dt, long steps, const Amb* centre,
           const std::vector<double>* ref, std::vector<double>* end = nullptr) {
  Stepper st;
  auto w = sys.make_workspace();
  const double e0 = sys.energy(s, w);
  Errors r;
  const Frame c0 = s.cluster;
  for (long k = 0; k < steps; ++k) {
    st.do_step(sys, s, double(k) * dt, dt);
    r.energy = std::max(r.energy, std::abs(sys.energy(s, w) - e0));
  }
  r.recentred = s.clustered && s.cluster != c0;
  // The centre in the cluster's (final) frame, as the system sees it.
  Amb c;
  if (centre) {
    if (s.clustered) {
      sys.chart().to_frame(s.cluster, *centre, c);
    } else {
      c = *centre;
    }
  }
  const std::vector<double> inv = invariants(sys, s, centre ? &c : nullptr);
  if (end) *end = inv;
  if (ref) {
    for (std::size_t i = 0; i < inv.size(); ++i) {
      const double e = std::abs(inv[i] - (*ref)[i]);
      r.invariant = std::max(r.invariant, e != e ? 1e300 : e);
    }
  }
  return r;
}

/// The near system's state: bodies at world points X with velocities V (identity frames).
template <class Sys>
sesi::State<Chart> near_state(const Sys& sys, const Mat<double>& X, const Mat<double>& V) {
  return stab::from_world(sys, X, V);
}
/// The same state moved to distance D: cluster frame C_D (nothing else changes).
sesi::State<Chart> moved(sesi::State<Chart> s, double D) {
  if (D > 0) s.set_cluster(far_frame(D));
  return s;
}

/// Runs the system at D = 0 (reference and plain), 10, 20, 30 and checks the 10x bound.
template <class SysFactory>
void far_range(const char* name, SysFactory make, const Mat<double>& X, const Mat<double>& V,
               bool with_centre, double dt, long steps) {
  std::vector<double> ref;
  {
    const auto sys = make(Amb(0, 0, 1));
    const Amb c(0, 0, 1);
    run(sys, moved(near_state(sys, X, V), 0), dt / 4, 4 * steps, with_centre ? &c : nullptr, nullptr, &ref);
  }
  Errors origin;
  for (double D : {0.0, 10.0, 20.0, 30.0}) {
    const Frame cd = D > 0 ? far_frame(D) : Frame::Identity();
    const Amb c = cd.col(2);  // the centre C_D o: the cluster frame's origin, exactly
    const auto sys = make(c);
    const Errors e = run(sys, moved(near_state(sys, X, V), D), dt, steps, with_centre ? &c : nullptr, &ref);
    const std::string tag = std::string("cluster ") + name + " D = " + std::to_string(int(D));
    report(tag + ": invariant error", e.invariant);
    report(tag + ": energy error", e.energy);
    if (D == 0) {
      origin = e;
      CHECK(e.invariant > 0);
      CHECK(e.invariant < 1e-5);
      continue;
    }
    CHECK((e.recentred != 0) == !with_centre);
    CHECK(e.invariant <= 10 * origin.invariant + 1e-14);
    CHECK(e.energy <= 10 * origin.energy + 1e-14);
  }
}

/// A harmonic pair (k = 1, rest length 1) at separation 1.2, spinning, drifting at unit speed.
void pair_scene(Mat<double>& X, Mat<double>& V) {
  X.resize(3, 2);
  V.resize(3, 2);
  X.col(0) = point(0.6, 0.0);
  X.col(1) = point(0.6, M_PI);
  V.col(0) = velocity(0.6, 0.0, 0.1, 0.3) + drift(X.col(0), 1.0);
  V.col(1) = velocity(0.6, M_PI, 0.1, 0.3) + drift(X.col(1), 1.0);
}
/// Three Lennard-Jones bodies near their equilateral minimum (side 1.12), jiggling, drifting.
void lj_scene(Mat<double>& X, Mat<double>& V) {
  X.resize(3, 3);
  V.resize(3, 3);
  for (int b = 0; b < 3; ++b) {
    const double a = 0.4 + 2.0 * M_PI * b / 3.0;
    X.col(b) = point(0.66, a);
    V.col(b) = velocity(0.66, a, 0.05 * (b - 1), 0.2) + drift(X.col(b), 1.0);
  }
}
/// One body on a near-circular orbit of radius 0.8 about a centre at the origin.
void orbit_scene(Mat<double>& X, Mat<double>& V) {
  X.resize(3, 1);
  V.resize(3, 1);
  X.col(0) = point(0.8, 0.3);
  V.col(0) = velocity(0.8, 0.3, 0.05, 1.1);
}

auto pair_system(const Amb&) {
  return sesi::System(Chart(1.0), std::vector<double>{1.0, 1.0}, sesi::HarmonicPair<double>{1.0, 1.0});
}
auto lj_system(const Amb&) {
  return sesi::System(Chart(1.0), std::vector<double>{1.0, 1.0, 1.0}, sesi::LennardJones<double>{});
}
auto orbit_system(const Amb& c) {
  sesi::CentralCotangent<Chart> term;
  term.k = 1.0;
  term.center = c;
  return sesi::System(Chart(1.0), std::vector<double>{1.0}, term);
}

}  // namespace

TEST_CASE("cluster frame: a harmonic pair at D = 10, 20, 30 as at the origin") {
  Mat<double> X, V;
  pair_scene(X, V);
  far_range("harmonic pair", pair_system, X, V, false, 0.01, 500);
}

TEST_CASE("cluster frame: a Lennard-Jones cluster at D = 10, 20, 30 as at the origin") {
  Mat<double> X, V;
  lj_scene(X, V);
  far_range("LJ cluster of 3", lj_system, X, V, false, 0.005, 1000);
}

TEST_CASE("cluster frame: a central-cotangent orbit at D = 10, 20, 30 as at the origin") {
  Mat<double> X, V;
  orbit_scene(X, V);
  far_range("central orbit", orbit_system, X, V, true, 0.01, 500);
}

TEST_CASE("without the cluster frame the far pair is integrated wrongly (the bound can fail)") {
  Mat<double> X, V;
  pair_scene(X, V);
  const auto sys = pair_system(Amb(0, 0, 1));
  std::vector<double> ref;
  run(sys, near_state(sys, X, V), 0.0025, 2000, nullptr, nullptr, &ref);
  const Errors origin = run(sys, near_state(sys, X, V), 0.01, 500, nullptr, &ref);
  for (double D : {10.0, 14.0}) {
    // Each body's own frame moved by C_D: world points of size e^D enter every chord.
    auto s = near_state(sys, X, V);
    s.enable_frames(3);
    for (auto& f : s.frames) f = far_frame(D);
    const Errors e = run(sys, s, 0.01, 500, nullptr, &ref);
    report("no cluster frame, harmonic pair D = " + std::to_string(int(D)) + ": invariant error / origin's",
           e.invariant / origin.invariant);
    CHECK_FALSE(e.invariant <= 10 * origin.invariant);
  }
}

TEST_CASE("cluster frame at the origin changes nothing, bit for bit") {
  // No drift (no re-centring): a cluster frame at the identity gives the run without one.
  Mat<double> X, V;
  pair_scene(X, V);
  for (int b = 0; b < 2; ++b) V.col(b) -= drift(X.col(b), 1.0);
  {
    const auto sys = pair_system(Amb(0, 0, 1));
    auto plain = near_state(sys, X, V);
    auto clustered = plain;
    clustered.set_cluster(Frame::Identity());
    Stepper a, b;
    stab::run(a, sys, plain, 0.01, 300);
    stab::run(b, sys, clustered, 0.01, 300);
    CHECK(plain.q == clustered.q);
    CHECK(plain.p == clustered.p);
    CHECK(clustered.cluster == Frame::Identity());
  }
  {
    orbit_scene(X, V);
    const auto sys = orbit_system(Amb(0, 0, 1));
    auto plain = near_state(sys, X, V);
    auto clustered = plain;
    clustered.set_cluster(Frame::Identity());
    Stepper a, b;
    stab::run(a, sys, plain, 0.01, 300);
    stab::run(b, sys, clustered, 0.01, 300);
    CHECK(plain.q == clustered.q);
    CHECK(plain.p == clustered.p);
  }
}

TEST_CASE("cluster frame: re-centring keeps reversibility and the world state") {
  // Forward 400 steps (4 time units at unit drift), momenta negated, 400 steps back.
  Mat<double> X, V;
  pair_scene(X, V);
  const auto sys = pair_system(Amb(0, 0, 1));
  for (double D : {0.0, 30.0}) {
    auto s = near_state(sys, X, V);
    s.set_cluster(D > 0 ? far_frame(D) : Frame::Identity());
    auto w = sys.make_workspace();
    const double e0 = sys.energy(s, w);
    const auto inv0 = invariants(sys, s, nullptr);
    const Mat<double> X0 = sesi::embedding_points(sys, s);
    // The plain symmetric method with re-centring between steps (no re-charting, whose
    // decisions on the way back differ: the cluster frame's own reversibility).
    Method<Chart> st;
    const sesi::RechartPolicy<double> policy;
    int recentred = 0;
    const auto go = [&] {
      for (int k = 0; k < 400; ++k) {
        st.do_step(sys, s, 0.01 * k, 0.01);
        recentred += sesi::recentre(sys, s, policy);
      }
    };
    go();
    CHECK(recentred >= 1);
    s.p = -s.p;
    go();
    s.p = -s.p;
    report("cluster reversibility D = " + std::to_string(int(D)) + ": re-centrings", recentred);
    const auto inv1 = invariants(sys, s, nullptr);
    const double de = std::abs(sys.energy(s, w) - e0);
    const double dd = std::abs(inv1[0] - inv0[0]);
    report("cluster reversibility D = " + std::to_string(int(D)) + ": separation", dd);
    report("cluster reversibility D = " + std::to_string(int(D)) + ": energy", de);
    CHECK(dd <= 1e-12);
    CHECK(de <= 1e-12);
    if (D == 0) {
      // World points back where they started (the cluster frame is O(1) here).
      const Mat<double> X1 = sesi::embedding_points(sys, s);
      const double dx = stab::max_distance(sys.chart(), X0, X1);
      report("cluster reversibility D = 0: world distance", dx);
      CHECK(dx <= 1e-12);
    }
  }
}

TEST_CASE("to_frame: a far centre read into a cluster frame without cancellation") {
  const Chart chart(1.0);
  for (double D : {10.0, 20.0, 30.0}) {
    const Frame c = far_frame(D);
    Amb local;
    const Amb origin = c.col(2);
    chart.to_frame(c, origin, local);
    CHECK(local == Amb(0, 0, 1));  // the frame's own origin: exact
    // A centre at distance 0.5 from the frame's origin, transversally: the naive C^{-1} c loses
    // eps e^{2D}; to_frame only what the world point resolves, eps sinh(D).
    const Amb near = point(0.5, 1.3);
    const Amb world = c * near;
    chart.to_frame(c, world, local);
    const double err = chart.distance(local, near);
    Frame inverse = c.transpose();
    inverse.row(2) = -inverse.row(2);
    inverse.col(2) = -inverse.col(2);
    const Amb naive = inverse * world;
    report("to_frame D = " + std::to_string(int(D)) + ": error / (eps sinh D)",
           err / (stab::eps<double>() * std::sinh(D)));
    report("naive C^-1 c D = " + std::to_string(int(D)) + ": error of the time part", std::abs(naive[2] - near[2]));
    CHECK(err <= 16 * stab::eps<double>() * std::sinh(D));
    // A general frame, rotation x boost x rotation (C's rotation part read from its columns).
    const Frame turn1 = stab::givens<double>(3, 0, 1, 0.7), turn2 = stab::givens<double>(3, 0, 1, -2.1);
    const Frame general = turn1 * c * turn2;
    const Amb world2 = general * near;
    chart.to_frame(general, world2, local);
    const double err2 = chart.distance(local, near);
    report("to_frame D = " + std::to_string(int(D)) + ", rotated frame: error / (eps sinh D)",
           err2 / (stab::eps<double>() * std::sinh(D)));
    CHECK(err2 <= 16 * stab::eps<double>() * std::sinh(D));
    chart.to_frame(general, Amb(general.col(2)), local);
    CHECK((local - Amb(0, 0, 1)).norm() <= 4 * stab::eps<double>());
  }
}

TEST_CASE("cluster frame: world points, velocities and the momentum map") {
  Mat<double> X, V;
  pair_scene(X, V);
  const auto sys = pair_system(Amb(0, 0, 1));
  auto s = moved(near_state(sys, X, V), 20.0);
  Stepper st;
  stab::run(st, sys, s, 0.01, 300);
  const Mat<double> W = sesi::embedding_points(sys, s);
  const Mat<double> U = sesi::embedding_velocities(sys, s);
  const Mat<double> L = local_points(sys, s);
  for (int b = 0; b < 2; ++b) {
    const Amb x = W.col(b);
    // On the hyperboloid to relative rounding of e^{2D}-sized terms.
    CHECK(std::abs(sys.chart().constraint(x)) <= 64 * stab::eps<double>() * x.squaredNorm());
    const Amb expected = s.cluster * L.col(b);
    CHECK((x - expected).norm() <= 4 * stab::eps<double>() * x.norm());
    CHECK(std::abs(sys.chart().tangency(x, Amb(U.col(b)))) <= 64 * stab::eps<double>() * x.norm() * Amb(U.col(b)).norm());
  }
  // The momentum map: the same run with the cluster frame at the identity (bit-identical locally,
  // with the same re-centrings B_1..B_r) has M_0, and the far state's map is Ad_{C_D} M_0 = C_D M_0 C_D^T.
  auto s0 = near_state(sys, X, V);
  s0.set_cluster(Frame::Identity());
  Stepper st0;
  int recentred = 0;
  Frame chain = Frame::Identity();  // |B_1| |B_2| ... |B_r| (entrywise absolute values)
  for (long k = 0; k < 300; ++k) {
    const Frame before = s0.cluster;
    st0.do_step(sys, s0, double(k) * 0.01, 0.01);
    if (s0.cluster != before) {
      Frame inverse = before.transpose();  // eta B^T eta
      inverse.row(2) = -inverse.row(2);
      inverse.col(2) = -inverse.col(2);
      chain = (chain * (inverse * s0.cluster).cwiseAbs()).eval();
      ++recentred;
    }
  }
  CHECK(recentred >= 1);
  CHECK(s0.q == s.q);
  const auto m0 = sesi::momentum_map(sys, s0);
  const auto m1 = sesi::momentum_map(sys, s);
  auto local = s0;
  local.clustered = false;
  const auto ml = sesi::momentum_map(sys, local);  // the local map M_l, the same on both sides
  Frame M0 = Frame::Zero(), Ml = Frame::Zero();
  int k = 0;
  for (int r = 0; r < 3; ++r) {
    for (int c = r + 1; c < 3; ++c, ++k) {
      M0(r, c) = m0[k];
      M0(c, r) = -m0[k];
      Ml(r, c) = Ml(c, r) = std::abs(ml[k]);
    }
  }
  const Frame cd = far_frame(20.0);
  const Frame expected = cd * M0 * cd.transpose();
  // Both sides are M_l moved by the frames in two groupings, fl(C M_l C^T) with C = fl(C_D B_1 .. B_r)
  // and fl(C_D fl(B M_l B^T) C_D^T) with B = fl(B_1 .. B_r). Each of the 2r + 2 products of 3x3
  // matrices on a side rounds to gamma_3 = 3 eps / 2 of the product of absolute values
  // (Higham, Accuracy and Stability, 3.5): |m1 - expected| <= (4r + 4) (3 eps / 2) P entrywise,
  // P = |C_D| |B_1|..|B_r| |M_l| (|C_D| |B_1|..|B_r|)^T. (The former bound, 64 eps |C_D|^2 |B|^4 |M_0|
  // in norms, was 1e5 times the difference measured.)
  const Frame outer = cd.cwiseAbs() * chain;
  const Frame P = outer * Ml * outer.transpose();
  const double c = (4.0 * recentred + 4.0) * 1.5 * stab::eps<double>();
  double worst = 0, worst_ratio = 0;
  k = 0;
  for (int r = 0; r < 3; ++r) {
    for (int col = r + 1; col < 3; ++col, ++k) {
      const double d = std::abs(m1[k] - expected(r, col));
      worst = std::max(worst, d);
      worst_ratio = std::max(worst_ratio, d / (c * P(r, col)));
      CHECK(d <= c * P(r, col));
    }
  }
  report("cluster D = 20: momentum map against Ad_{C_D} of the origin run's (relative)", worst / expected.norm());
  report("cluster D = 20: momentum map difference / its rounding bound (largest entry)", worst_ratio);
  report("cluster D = 20: re-centrings", recentred);
}

TEST_CASE("cluster frame on H^3 and on a dynamic-size H^3: pair and centre at D = 20") {
  // The same construction in three dimensions (a boost along axis 1, a rotated centre read by
  // to_frame), fixed-size and Eigen::Dynamic: the far pair's separation equals the origin's.
  const auto check_dim = [](auto chart) {
    using C = decltype(chart);
    using F = typename sesi::State<C>::Frame;
    using A = typename C::Ambient;
    const auto sys = sesi::System(chart, std::vector<double>{1.0, 1.0}, sesi::HarmonicPair<double>{1.0, 1.0});
    Mat<double> X(4, 2), V(4, 2);
    const double s = 0.6;
    X.col(0) << std::sinh(s) * 0.6, std::sinh(s) * 0.8, 0.0, std::cosh(s);
    X.col(1) << -std::sinh(s) * 0.6, -std::sinh(s) * 0.8, 0.0, std::cosh(s);
    for (int b = 0; b < 2; ++b) {
      // Drift along axis 2 (the boost generator there) plus a small spin about axis 2.
      const Eigen::Vector4d x = X.col(b);
      V.col(b) = Eigen::Vector4d(0, 0, x[3], x[2]) + 0.3 * Eigen::Vector4d(-x[1], x[0], 0, 0);
    }
    auto near = stab::from_world(sys, X, V);
    auto far = near;
    F cd = F::Identity(4, 4);
    cd(1, 1) = cd(3, 3) = std::cosh(20.0);
    cd(1, 3) = cd(3, 1) = std::sinh(20.0);
    far.set_cluster(cd);
    near.set_cluster(F::Identity(4, 4));
    stab::Rech<Method, C> a, b;
    stab::run(a, sys, near, 0.01, 400);
    stab::run(b, sys, far, 0.01, 400);
    CHECK(near.q == far.q);  // the same local run, bit for bit (the same re-centrings)
    CHECK(far.cluster != cd);
    A local(4);
    chart.to_frame(cd, A(cd.col(3)), local);
    CHECK((local - A(Eigen::Vector4d(0, 0, 0, 1))).norm() == 0.0);
    const Eigen::Vector4d p0(std::sinh(0.5) * 0.48, std::sinh(0.5) * 0.6, std::sinh(0.5) * 0.64, std::cosh(0.5));
    const A world = A(cd * p0);
    chart.to_frame(cd, world, local);
    CHECK(chart.distance(local, A(p0)) <= 16 * stab::eps<double>() * std::sinh(20.0));
  };
  check_dim(sesi::Hyperbolic<3, double>(1.0));
  check_dim(sesi::HyperbolicXd(1.0, 3));
}

TEST_CASE("to_frame with a velocity: a far body read into a cluster frame without cancellation") {
  // A body at distance 0.5 from the frame's origin with an O(1) velocity, moved out by a frame
  // rotation x boost(D) x rotation: its world x and v (entries ~e^D) are read back into the
  // frame. The matrix product C^{-1} v would lose eps e^{2D}; the closed form eps sinh D.
  const Chart chart(1.0);
  const Amb xl = point(0.5, 1.3), vl = velocity(0.5, 1.3, 0.3, -0.7);
  const Frame turn1 = stab::givens<double>(3, 0, 1, 0.7), turn2 = stab::givens<double>(3, 0, 1, -2.1);
  for (double D : {0.5, 1.5, 10.0, 20.0, 30.0}) {
    const Frame c = turn1 * far_frame(D) * turn2;
    const Amb x = c * xl, v = c * vl;
    Amb xo, vo;
    chart.to_frame(c, x, v, xo, vo);
    const double scale = stab::eps<double>() * std::sinh(std::max(D, 1.0));
    const double ex = chart.distance(xo, xl), ev = (vo - vl).norm();
    report("to_frame with v, D = " + std::to_string(D).substr(0, 4) + ": point error / (eps sinh D)", ex / scale);
    report("to_frame with v, D = " + std::to_string(D).substr(0, 4) + ": velocity error / (eps sinh D)", ev / scale);
    CHECK(ex <= 16 * scale);
    CHECK(ev <= 64 * scale);
    CHECK(std::abs(chart.tangency(xo, vo)) <= 16 * stab::eps<double>() * xo.norm() * vo.norm());
    if (D >= 10) {  // the product's loss, for contrast
      Frame inverse = c.transpose();
      inverse.row(2) = -inverse.row(2);
      inverse.col(2) = -inverse.col(2);
      const Amb naive = inverse * v;
      report("naive C^-1 v, D = " + std::to_string(int(D)) + ": velocity error", (naive - vl).norm());
    }
  }
}

TEST_CASE("enter_cluster_frame: a pair and an orbit given in world coordinates far out") {
  // The far systems of the tests above, but given as a user gives a scene: world points and
  // velocities (entries ~e^D), read into the space's own chart, then put into a cluster frame by
  // enter_cluster_frame. What world coordinates resolve far out bounds the result: the initial
  // state is known to ~eps sinh D (to_frame), and that error is carried along the run; within
  // that, the far runs match the origin's.
  const Frame turn = stab::givens<double>(3, 0, 1, 0.4);
  const sesi::RechartPolicy<double> policy;
  const auto go = [&](const char* name, auto make, const Mat<double>& X, const Mat<double>& V, bool with_centre,
                      double dt, long steps, double response) {
    std::vector<double> ref;
    {
      const Amb o(0, 0, 1);
      const auto sys = make(o);
      run(sys, near_state(sys, X, V), dt / 4, 4 * steps, with_centre ? &o : nullptr, nullptr, &ref);
    }
    const Amb o(0, 0, 1);
    const auto sys0 = make(o);
    auto s0 = near_state(sys0, X, V);
    CHECK_FALSE(sesi::enter_cluster_frame(sys0, s0, policy));  // at the origin: C = I
    CHECK(s0.clustered);
    const Errors origin = run(sys0, s0, dt, steps, with_centre ? &o : nullptr, &ref);
    for (double D : {10.0, 16.0, 20.0}) {
      const Frame c = turn * far_frame(D);
      const Mat<double> Xw = c * X, Vw = c * V;
      const Amb centre = c.col(2);
      const auto sys = make(centre);
      auto s = near_state(sys, Xw, Vw);  // the space's own chart, as the program reads a scene
      CHECK(sesi::enter_cluster_frame(sys, s, policy, with_centre ? &centre : nullptr));
      Amb local_centre(3);
      sys.chart().to_frame(s.cluster, centre, local_centre);
      const Errors e = run(sys, s, dt, steps, with_centre ? &centre : nullptr, &ref);
      // The input's rounding (c X, c V: 3-term products of e^D-sized entries, c itself rounded)
      // moves each point and velocity across the line of sight by <= 4 eps sinh D, to_frame by <= 4
      // more (its test above: 0.57 measured), and the invariants respond to an initial displacement
      // by at most `response` by t = 5 (measured at the origin by +-1e-6 along each tangent
      // direction with the program: pair 1.27, orbit 10.3).
      const double input = response * (4 + 4) * stab::eps<double>() * std::sinh(D);
      const std::string tag = std::string("entered ") + name + " D = " + std::to_string(int(D));
      report(tag + ": invariant error", e.invariant);
      report(tag + ": energy error", e.energy);
      CHECK(e.invariant <= 10 * origin.invariant + input);
      // No floor from lengths: the energy is formed from cluster-local O(1) quantities.
      CHECK(e.energy <= 10 * origin.energy);
    }
  };
  Mat<double> X, V;
  pair_scene(X, V);
  go("harmonic pair", pair_system, X, V, false, 0.01, 500, 1.27);
  orbit_scene(X, V);
  go("central orbit", orbit_system, X, V, true, 0.01, 500, 10.3);
}

TEST_CASE("closest_encounter in a cluster frame: the centre moved into the frame") {
  // A body 0.3 from a central-cotangent centre at D = 20, in the frame at the centre: with a
  // floor of 0.5 the encounter is found at the local distance 0.3; with 0.2 none is. (Measured
  // against the world centre, the local point would be ~20 away and never found.)
  const Frame c = far_frame(20.0);
  sesi::CentralCotangent<Chart> term;
  term.k = 1.0;
  term.center = c.col(2);
  term.min_distance = 0.5;
  const auto sys = sesi::System(Chart(1.0), std::vector<double>{1.0}, term);
  Mat<double> X(3, 1), V(3, 1);
  X.col(0) = point(0.3, 0.4);
  V.col(0) = velocity(0.3, 0.4, 0.0, 0.5);
  auto s = moved(near_state(sys, X, V), 20.0);
  const auto e = sesi::closest_encounter(sys, s);
  REQUIRE(e.found());
  CHECK(e.second == -1);
  CHECK(std::abs(e.gap - 0.3) <= 1e-12);
  term.min_distance = 0.2;
  const auto sys2 = sesi::System(Chart(1.0), std::vector<double>{1.0}, term);
  CHECK_FALSE(sesi::closest_encounter(sys2, s).found());
}
