// Sphere<Eigen::Dynamic>(R, n) steps like Sphere<n> (and the same for Hyperbolic and Euclidean),
// issue #2: the same operations on the same numbers, except that Eigen sums dot products and
// norms in a different order for fixed-size (unrolled, vectorised) and dynamic vectors. A sum
// of n+1 terms in another order differs by at most (n+1) eps |x||y|; each stage evaluates a few
// such sums per body (distance, its gradient, the embedding), so after `steps` steps of s stages
// the states may differ by about 8 (n+4) s steps eps |z| -- the bound below. Anything larger
// means the two paths compute different things.
#include <algorithm>
#include <cmath>
#include <tuple>
#include <type_traits>

#include <doctest/doctest.h>

#include "common.hpp"

namespace {

using namespace coretest;
namespace co = sesi::coefficients;

template <class Fixed, class Dyn, class Method, class DynMethod>
void check_same(long steps) {
  const int n = Fixed::dimension;
  const auto fixed = make_scene<Fixed>();
  const auto dyn = make_scene<Dyn>(n);
  REQUIRE(dyn.dim() == n);
  const auto x0 = initial_state(fixed);
  sesi::State<Dyn> y0(n, fixed.bodies());
  y0.q = x0.q;
  y0.p = x0.p;
  using Scalar = typename Fixed::Scalar;
  const Scalar e0 = fixed.energy(x0);
  CHECK(std::abs(e0 - dyn.energy(y0)) <= Scalar(8 * (n + 4)) * eps<Scalar>() * std::max(Scalar(1), std::abs(e0)));
  // Over the scene's time (common.hpp, scene_time: on H^n the trap pulls the bodies into the
  // chart's polar singularity later on).
  const auto x = run<Method>(fixed, x0, scene_time<Fixed>(), steps);
  const auto y = run<DynMethod>(dyn, y0, scene_time<Fixed>(), steps);
  INFO(Method::table::name, " n = ", n);
  const Scalar scale = std::max({Scalar(1), x.q.cwiseAbs().maxCoeff(), x.p.cwiseAbs().maxCoeff()});
  const Scalar bound = Scalar(8 * (n + 4)) * Scalar(Method::table::stages) * Scalar(steps) * eps<Scalar>() * scale;
  const Scalar diff = std::max((x.q - y.q).cwiseAbs().maxCoeff(), (x.p - y.p).cwiseAbs().maxCoeff());
  MESSAGE(Method::table::name, " n = ", n, ": max difference fixed - dynamic ", double(diff),
          " (bound ", double(bound), ")");
  CHECK(diff <= bound);
}

}  // namespace

template <int N>
using Dim = std::integral_constant<int, N>;

TEST_CASE_TEMPLATE_DEFINE("dynamic: Eigen::Dynamic charts step like fixed ones, to the round-off of reordered sums", D,
                          dynamic_dims) {
  constexpr int n = D::value;
  constexpr int X = Eigen::Dynamic;
  using KDK4 = co::Yoshida4;
  check_same<sesi::Sphere<n>, sesi::Sphere<X>, sesi::Yoshida4<sesi::Sphere<n>>,
             sesi::Yoshida4<sesi::Sphere<X>>>(20);
  check_same<sesi::Hyperbolic<n>, sesi::Hyperbolic<X>, sesi::Yoshida4<sesi::Hyperbolic<n>>,
             sesi::Yoshida4<sesi::Hyperbolic<X>>>(20);
  check_same<sesi::Euclidean<n>, sesi::Euclidean<X>,
             sesi::Composition<KDK4, sesi::Euclidean<n>, sesi::Splitting::kick_drift_kick>,
             sesi::Composition<KDK4, sesi::Euclidean<X>, sesi::Splitting::kick_drift_kick>>(20);
}
TEST_CASE_TEMPLATE_APPLY(dynamic_dims, std::tuple<Dim<1>, Dim<2>, Dim<3>, Dim<4>, Dim<5>, Dim<6>>);
