#include "observables.hpp"

#include <cmath>

#include <sesi/diagnostics.hpp>

#include "chart_integrator.hpp"
#include "terms.hpp"

namespace sesi::program {

struct Observables::Impl {
  virtual ~Impl() = default;
  virtual void set_state(const Eigen::MatrixXd& q, const Eigen::MatrixXd& p) = 0;
  virtual double energy() = 0;
  virtual Eigen::VectorXd momentum_map() = 0;
  virtual Eigen::MatrixXd points() = 0;
  virtual Eigen::MatrixXd velocities() = 0;
  virtual int body_with_non_finite_energy() = 0;
};

namespace {

template <class Chart>
struct ImplOn final : Observables::Impl {
  using Sys = SystemOf<Chart>;
  explicit ImplOn(const Scene& scene)
      : sys(make_system(scene, make_chart<Chart>(scene.space))), x(scene.dim(), scene.body_count()),
        w(sys.make_workspace()) {}

  void set_state(const Eigen::MatrixXd& q, const Eigen::MatrixXd& p) override {
    x.q = q;
    x.p = p;
  }
  double energy() override { return sys.energy(x, w); }
  Eigen::VectorXd momentum_map() override { return sesi::momentum_map(sys, x); }
  Eigen::MatrixXd points() override { return sesi::embedding_points(sys, x); }
  Eigen::MatrixXd velocities() override { return sesi::embedding_velocities(sys, x); }
  int body_with_non_finite_energy() override {
    typename Chart::Point q(sys.dim()), p(sys.dim());
    for (int b = 0; b < sys.bodies(); ++b) {
      q = x.q.col(b);
      p = x.p.col(b);
      if (!std::isfinite(sesi::kinetic_energy(sys.chart(), q, p, sys.mass(b)))) return b + 1;
    }
    typename Sys::StateType::Matrix gradient;
    sys.potential_gradient(x, w, gradient);
    for (int b = 0; b < sys.bodies(); ++b) {
      if (!gradient.col(b).allFinite()) return b + 1;
    }
    return 0;
  }

  Sys sys;
  typename Sys::StateType x;
  typename Sys::Workspace w;
};

std::unique_ptr<Observables::Impl> make_impl(const Scene& scene) {
  switch (scene.space.kind) {
    case SpaceKind::sphere:
      return std::make_unique<ImplOn<sesi::Sphere<Eigen::Dynamic, double>>>(scene);
    case SpaceKind::hyperbolic:
      return std::make_unique<ImplOn<sesi::Hyperbolic<Eigen::Dynamic, double>>>(scene);
    case SpaceKind::euclidean:
      break;
  }
  return std::make_unique<ImplOn<sesi::Euclidean<Eigen::Dynamic, double>>>(scene);
}

}  // namespace

Observables::Observables(const Scene& scene) : impl_(make_impl(scene)) {}
Observables::~Observables() = default;

void Observables::set_state(const Eigen::MatrixXd& q, const Eigen::MatrixXd& p) { impl_->set_state(q, p); }
double Observables::energy() { return impl_->energy(); }
Eigen::VectorXd Observables::momentum_map() { return impl_->momentum_map(); }
Eigen::MatrixXd Observables::points() { return impl_->points(); }
Eigen::MatrixXd Observables::velocities() { return impl_->velocities(); }
int Observables::body_with_non_finite_energy() { return impl_->body_with_non_finite_energy(); }

}  // namespace sesi::program
