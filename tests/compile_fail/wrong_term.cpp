// A potential term whose gradient returns the gradient instead of writing it: sesi::System's first
// error says what a term must provide (tests/compile_fail/check.cmake expects "sesi: a potential
// term must model ExternalTerm").
#include <vector>

#include <sesi/sesi.hpp>

struct Height {
  double value(const sesi::Sphere<2>&, const Eigen::Vector3d& x, double m) const { return m * x[2]; }
  Eigen::Vector3d gradient(const sesi::Sphere<2>&, const Eigen::Vector3d&, double m) const {
    return {0.0, 0.0, m};
  }
};

int main() {
  sesi::System<sesi::Sphere<2>, Height> sys(sesi::Sphere<2>(1.0), std::vector<double>{1.0}, Height{});
  return sys.bodies() == 1 ? 0 : 1;
}
