// Integrates free motion on S^2 with SESI 4 through the installed package: the error against the
// exact great circle must fall as dt^4 (measured order within 0.3 of 4). Exits non-zero otherwise.
#include <cmath>
#include <cstdio>
#include <vector>

#include <sesi/sesi.hpp>

namespace {
using Chart = sesi::Sphere2d;

double error_at(double dt, double t_end) {
  sesi::System sys(Chart(1.0), std::vector<double>{1.0});
  sesi::State<Chart> x(2, 1);
  x.q << 1.0, 0.5;
  x.p << 0.3, 0.2;
  const Eigen::Vector3d x0 = sesi::embedding_points(sys, x).col(0);
  const Eigen::Vector3d v0 = sesi::embedding_velocities(sys, x).col(0);
  sesi::Yoshida4<Chart> stepper;
  const long steps = std::lround(t_end / dt);
  for (long k = 0; k < steps; ++k) stepper.do_step(sys, x, k * dt, dt);
  const double w = v0.norm();  // angular speed on the unit sphere
  const Eigen::Vector3d exact = std::cos(w * t_end) * x0 + std::sin(w * t_end) / w * v0;
  return (sesi::embedding_points(sys, x).col(0) - exact).norm();
}
}  // namespace

int main() {
  const double coarse = error_at(0.1, 10.0), fine = error_at(0.05, 10.0);
  const double order = std::log2(coarse / fine);
  std::printf("consumer: SESI 4 errors %.3g, %.3g; measured order %.2f\n", coarse, fine, order);
  return std::abs(order - 4.0) <= 0.3 ? 0 : 1;
}
