// A chart without kinetic_dq: sesi::System's first error names the missing member
// (tests/compile_fail/check.cmake expects "sesi: the chart needs `Scalar kinetic_dq").
#include <vector>

#include <sesi/sesi.hpp>

struct Ring {
  using Scalar = double;
  using Point = Eigen::Matrix<double, 1, 1>;
  static constexpr int dimension = 1;
  int dim() const { return 1; }
  double kinetic(int, const Point&, double p, double m) const { return p * p / (2 * m); }
  double kinetic_dp(int, const Point&, double p, double m) const { return p / m; }
};

int main() {
  sesi::System<Ring> sys(Ring{}, std::vector<double>{1.0});
  return sys.bodies() == 1 ? 0 : 1;
}
