#pragma once
/// @file embedded_integrator.hpp
/// The Integrator of the geodesic methods (methods.hpp, EmbeddedMethods) on S^n and H^n: the state
/// is held in the embedding, each body's point x on the quadric <x,x> = s R^2 and its tangent
/// velocity v (sesi::reference::EmbeddedState), and stepped by the geodesic splitting of
/// include/sesi/reference/embedding.hpp (exact geodesic drifts, tangential kicks by the ambient
/// gradients of the scene's System, System::ambient_gradient) composed with the method's table.
/// No chart, no frames, no re-charting and no cluster frame: world points are the local points.
/// The outputs are those of the chart methods: q and p are read in the scene's chart from x and
/// v (reference::to_chart), the energy and momentum map are formed from x and v.
///
/// Far out on H^n the ambient coordinates grow like e^{r/R} (r the distance from the origin), and
/// every quantity formed from them by Minkowski products (the retraction, the tangential
/// projection, pair distances, the kinetic energy) loses digits like eps e^{2r/R}, where the
/// chart methods' cluster frame keeps a compact group's O(1) (docs/scheme.md, "The geodesic
/// methods").

#include <cmath>
#include <limits>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>

#include <sesi/reference/embedding.hpp>

#include "chart_integrator.hpp"
#include "errors.hpp"
#include "integrator.hpp"
#include "methods.hpp"
#include "terms.hpp"

namespace sesi::program {

/// The largest eps e^{2r/R} (r a body's distance from the origin of H^n) with which a geodesic
/// method starts: farther out its ambient coordinates (of size e^{r/R}) keep fewer than two digits
/// of the pair distances and the speeds (docs/scheme.md, "The geodesic methods").
inline constexpr double geodesic_reach_limit = 1e-2;

/// H^n: refuse a geodesic method whose scene has a body where geodesic_reach_limit is passed,
/// with one line naming the method, the body and its distance (the chart methods hold such
/// bodies in a cluster frame). Throws InputError.
inline void check_geodesic_reach(const Scene& scene) {
  for (int b = 0; b < scene.body_count(); ++b) {
    const double r = scene.bodies[static_cast<std::size_t>(b)].q[0];  // q_1 = r / R
    const double resolution = std::numeric_limits<double>::epsilon() * std::exp(2.0 * r);
    if (!(resolution > geodesic_reach_limit)) continue;
    throw InputError(Origin{scene.source}, "bodies[" + std::to_string(b + 1) + "]",
                     "at distance " + format_short(r * scene.space.radius) + " from the origin of H^" +
                         std::to_string(scene.dim()) + " (" + format_short(r) +
                         " radii) the embedding coordinates of method '" + scene.integrator.method +
                         "' resolve distances only to eps e^(2r/R) = " + format_short(resolution) +
                         " (they lose digits like that beyond ~10 radii); use a sesi method, which holds far "
                         "bodies in a cluster frame");
  }
}

/// The engine of every geodesic method on Chart: one type, the table's weights as data.
template <class Chart>
using GeodesicEngine =
    sesi::reference::GeodesicComposition<coefficients::Runtime, Chart, sesi::Splitting::drift_kick_drift>;

/// The engine of the processed geodesic methods (GeodesicProcessedMethod): one type, the
/// kernel's and the processor's weights as data.
template <class Chart>
using GeodesicProcessedEngine = sesi::reference::GeodesicProcessed<coefficients::Runtime, Chart>;

/// The engine of the geodesic method called name (a name of EmbeddedMethods): `plain` or, for a
/// processed method, `processed` is set.
template <class Chart, class... Method>
void geodesic_engine(MethodList<Method...>, std::string_view name, std::optional<GeodesicEngine<Chart>>& plain,
                     std::optional<GeodesicProcessedEngine<Chart>>& processed) {
  const auto try_method = [&]<class M>() {
    if (name != M::name) return false;
    if constexpr (M::processed) {
      processed.emplace(GeodesicProcessedEngine<Chart>::template of<typename M::table>());
    } else {
      plain.emplace(GeodesicEngine<Chart>::template of<typename M::table>());
    }
    return true;
  };
  if (!(try_method.template operator()<Method>() || ...)) {
    throw std::logic_error("not a geodesic method: '" + std::string(name) + "'");
  }
}

template <class Chart>
class EmbeddedIntegrator final : public Integrator {
  using Q = sesi::reference::Quadric<Chart>;
  using EState = sesi::reference::EmbeddedState<Chart>;

 public:
  explicit EmbeddedIntegrator(const Scene& scene)
      : sys_(make_system(scene, make_chart<Chart>(scene.space))),
        e_(sesi::reference::to_embedded(sys_, initial_state<Chart>(scene))) {
    // The thermostats are stages of the chart engine: the scene checks refuse them here.
    if (scene.thermostat) throw std::logic_error("a thermostat with geodesic method '" + scene.integrator.method + "'");
    geodesic_engine<Chart>(EmbeddedMethods{}, scene.integrator.method, stepper_, processed_);
    if (processed_) {
      dt_ = scene.integrator.dt.value_or(0.0);
      initial_ = e_;
    }
  }
  EmbeddedIntegrator(const EmbeddedIntegrator&) = delete;
  EmbeddedIntegrator& operator=(const EmbeddedIntegrator&) = delete;

  void step(double t, double h) override {
    if (processed_) {
      processed_->do_step(sys_, e_, t, h);  // pre-processes first, or re-enters for another h
      shown_valid_ = false;
      if (dt_ == 0.0) dt_ = h;  // the step, when the scene has none (Python)
    } else {
      stepper_->do_step(sys_, e_, t, h);
    }
#if defined(SESI_ENABLE_CHECKS) && SESI_ENABLE_CHECKS
    check_on_quadric();
#endif
  }

  /// In the scene's chart: q = chart(x) (angles in their principal ranges), p = m J^T eta v.
  void read(Eigen::MatrixXd& q, Eigen::MatrixXd& p) const override {
    const auto s = sesi::reference::to_chart(sys_, shown());
    q = s.q;
    p = s.p;
  }
  int first_non_finite_body() const override {
    const EState& e = shown();
    for (int b = 0; b < e.bodies(); ++b) {
      if (!e.x.col(b).allFinite() || !e.v.col(b).allFinite()) return b + 1;
    }
    return 0;
  }
  /// sum m/2 <v,v> plus the potential at the points x (System::ambient_potential_energy).
  double energy() override { return kinetic_energy() + potential_energy(); }
  /// M = sum_b m_b (x_b v_b^T - v_b x_b^T), its entries a < b row by row (diagnostics.hpp).
  Eigen::VectorXd momentum_map() override {
    const int a = sys_.ambient_dim();
    Eigen::VectorXd out = Eigen::VectorXd::Zero(a * (a - 1) / 2);
    const EState& e = shown();
    int k = 0;
    for (int r = 0; r < a; ++r) {
      for (int c = r + 1; c < a; ++c, ++k) {
        for (int b = 0; b < sys_.bodies(); ++b) {
          out[k] += sys_.mass(b) * (e.x(r, b) * e.v(c, b) - e.v(r, b) * e.x(c, b));
        }
      }
    }
    return out;
  }
  Eigen::MatrixXd points() override { return shown().x; }
  Eigen::MatrixXd velocities() override { return shown().v; }
  bool clustered() const override { return false; }
  Eigen::MatrixXd local_points() override { return shown().x; }
  Eigen::VectorXd to_local(const Eigen::VectorXd& world) const override { return world; }
  int body_with_non_finite_energy() override {
    const EState& e = shown();
    for (int b = 0; b < sys_.bodies(); ++b) {
      if (!std::isfinite(sys_.mass(b) * Q::dot(e.v.col(b), e.v.col(b)))) return b + 1;
    }
    w_.X = e.x;
    sys_.ambient_gradient(w_);
    for (int b = 0; b < sys_.bodies(); ++b) {
      if (!w_.G.col(b).allFinite()) return b + 1;
    }
    return 0;
  }
  /// A processed method's state is the kernel's variables for the scene's step, before the first
  /// step the state itself (as ChartIntegrator's; one entered with another step, after a
  /// shortened last step, is moved to the scene's step on a copy): restore takes them up again.
  FramedState framed_state() const override {
    FramedState out;
    out.embedded = true;
    out.x = e_.x;
    out.v = e_.v;
    if (processed_ && processed_->entered() && processed_->entered_step() != dt_) {
      EState moved = e_;
      processed_->apply_inverse_processor(sys_, moved, processed_->entered_step());
      processed_->apply_processor(sys_, moved, dt_);
      out.x = moved.x;
      out.v = moved.v;
    }
    return out;
  }
  FramedState shown_state() const override {
    FramedState out;
    out.embedded = true;
    out.x = shown().x;
    out.v = shown().v;
    return out;
  }
  void start_from(const FramedState& state) override {
    restore(state);
    if (processed_) {
      initial_ = e_;  // the state itself until the first step (restore and framed_state)
      processed_->restart();
    }
  }
  void restore(const FramedState& state) override {
    if (!state.embedded) {
      throw std::logic_error("a geodesic method's integrator was given a chart state (q, p) to restore");
    }
    if (state.x.rows() != e_.x.rows() || state.x.cols() != e_.x.cols() || state.v.rows() != e_.v.rows() ||
        state.v.cols() != e_.v.cols()) {
      throw std::logic_error("the embedded state to restore has the wrong size");
    }
    e_.x = state.x;
    e_.v = state.v;
    if (processed_) {
      shown_valid_ = false;
      // (The initial state, e.g. another method's before its first step, is the state itself.)
      const bool initial = e_.x == initial_.x && e_.v == initial_.v;
      if (dt_ == 0.0 || initial) {
        processed_->restart();
      } else {
        processed_->resume(dt_);
      }
    }
  }

 private:
  /// The state the outputs and diagnostics see: e_, or for a processed method the state its
  /// kernel's variables stand for (post-processed on a copy once per state).
  const EState& shown() const {
    if (!processed_) return e_;
    if (!shown_valid_) {
      processed_->post_process(sys_, e_, shown_);
      shown_valid_ = true;
    }
    return shown_;
  }
  double kinetic_energy() const {
    const EState& e = shown();
    double k = 0.0;
    for (int b = 0; b < sys_.bodies(); ++b) k += sys_.mass(b) * Q::dot(e.v.col(b), e.v.col(b)) / 2.0;
    return k;
  }
  double potential_energy() {
    w_.X = shown().x;
    return sys_.ambient_potential_energy(w_);
  }

#if defined(SESI_ENABLE_CHECKS) && SESI_ENABLE_CHECKS
  /// After each step (debug builds): every finite body on the quadric and its velocity tangent,
  /// to the round-off of the step's last operation, the library's retraction (the products'
  /// rounding, a few eps times the Euclidean sizes |x| |x| and |x| |v|; far out on H^n these are
  /// e^{r/R} times the Minkowski sizes). Non-finite bodies are the run loop's to report.
  void check_on_quadric() const {
    const double r2 = sys_.chart().radius() * sys_.chart().radius();
    const double tolerance = 8.0 * (sys_.ambient_dim() + 2) * std::numeric_limits<double>::epsilon();
    for (int b = 0; b < e_.bodies(); ++b) {
      const auto x = e_.x.col(b);
      const auto v = e_.v.col(b);
      if (!x.allFinite() || !v.allFinite()) continue;
      SESI_CHECK(std::abs(Q::dot(x, x) - Q::sign * r2) <= tolerance * x.squaredNorm(),
                 "geodesic method: a body left the quadric <x,x> = s R^2");
      SESI_CHECK(std::abs(Q::dot(x, v)) <= tolerance * x.norm() * v.norm(),
                 "geodesic method: a velocity is not tangent, <x,v> != 0");
    }
  }
#endif

  SystemOf<Chart> sys_;
  EState e_;  ///< the state, or a processed method's kernel's variables
  std::optional<GeodesicEngine<Chart>> stepper_;
  // A processed method: its engine (mutable: post-processing moves its processor's caches, not
  // the state), the scene's step, the initial state, and the post-processed state.
  mutable std::optional<GeodesicProcessedEngine<Chart>> processed_;
  double dt_ = 0.0;
  EState initial_;
  mutable EState shown_;
  mutable bool shown_valid_ = false;
  typename SystemOf<Chart>::Workspace w_ = sys_.make_workspace();  // the diagnostics' own
};

/// The geodesic integrator on Space<N> for the N in Dims (dispatch.hpp's FixedDims) equal to
/// scene.dim(), or nullptr.
template <template <int, class> class Space, int... Dims>
std::unique_ptr<Integrator> embedded_integrator_for(const Scene& scene, std::integer_sequence<int, Dims...>) {
  std::unique_ptr<Integrator> out;
  const auto try_dim = [&]<int N>() {
    if (scene.dim() != N) return false;
    out = std::make_unique<EmbeddedIntegrator<Space<N, double>>>(scene);
    return true;
  };
  static_cast<void>((try_dim.template operator()<Dims>() || ...));
  return out;
}

}  // namespace sesi::program
