#pragma once
/// @file methods.hpp
/// The methods of `sesi run --method`, registered in ONE place: the `Methods` list below.
///
/// A method is a small descriptor: a name, an order, a one-line description and
/// `make<Sys>(sys)`, which returns a stepper for the system behind a virtual call (AnyStepper).
/// The composition methods all share one engine per system (sesi::Composition over
/// coefficients::Runtime, the table's weights as data), so adding a table costs no compile time.
/// The processed methods (ProcessedMethod) share a second one (sesi::Processed over runtime
/// weights, include/sesi/processed.hpp), whose stepped state is the kernel's variables.
/// On S^n and H^n the engine re-charts bodies near their chart's singular set between steps
/// (sesi::Recharting, docs/charts.md), so scenes may cross poles and go far out. A reference stepper (e.g.
/// dopri5, gauss4, rattle from include/sesi/reference/) is registered by adding a descriptor
/// to `Methods` whose `make` wraps it, e.g. in OdeintStyleStepper; that is compiled once per
/// (space, dimension).

#include <algorithm>
#include <cstddef>
#include <functional>
#include <memory>
#include <span>
#include <string_view>
#include <tuple>
#include <type_traits>
#include <vector>

#include <sesi/coefficients.hpp>
#include <sesi/processed.hpp>
#include <sesi/recharting.hpp>
#include <sesi/stepper.hpp>

namespace sesi::program {

/// A stepper for systems of type Sys, behind a virtual call.
template <class Sys>
class AnyStepper {
 public:
  using StateType = typename Sys::StateType;
  virtual ~AnyStepper() = default;
  /// Advance x from t to t + dt.
  virtual void step(StateType& x, double t, double dt) = 0;
  /// The composition engine's workspace, whose Verlet lists diagnostics may share
  /// (sesi::Workspace::share_lists), or null for a stepper without one.
  virtual typename Sys::Workspace* workspace() { return nullptr; }

  // Processed methods (ProcessedStepper, sesi::Processed): x is then the kernel's variables z
  // once the first step has entered them, and the state is output(x). The defaults are the other
  // methods', whose x is the state.

  /// Whether x is the kernel's variables of a processed method (false: x is the state).
  virtual bool processed() const { return false; }
  /// The state x stands for: P^{-1}(x) for the step x was entered with (x itself if not entered).
  virtual void output(const StateType& x, StateType& y) { y = x; }
  /// The step x was entered with (0: not entered; x is the state).
  virtual double entered_step() const { return 0.0; }
  /// x holds the kernel's variables for step dt (dt = 0: the state itself, not entered).
  virtual void assume_entered(double dt) { static_cast<void>(dt); }
  /// out = the kernel's variables of the same state for step dt: P_dt(P^{-1}(x)).
  virtual void reentered(const StateType& x, double dt, StateType& out) {
    static_cast<void>(dt);
    out = x;
  }
};

/// An odeint-style stepper (do_step(sys, x, t, dt)) held with its system.
template <class Sys, class Stepper>
class OdeintStyleStepper final : public AnyStepper<Sys> {
 public:
  explicit OdeintStyleStepper(const Sys& sys) : sys_(sys) {}
  void step(typename Sys::StateType& x, double t, double dt) override {
    stepper_.do_step(std::cref(sys_), x, t, dt);
  }

 private:
  const Sys& sys_;
  Stepper stepper_;
};

/// The composition engine of the program for a chart: one type for every coefficient table,
/// re-charting where the chart allows it.
/// Re-charted runs use the kick-drift-kick form (sesi::RechartingComposition, docs/charts.md).
template <class Chart>
using ProgramComposition =
    std::conditional_t<sesi::Rechartable<Chart>,
                       sesi::RechartingComposition<coefficients::Runtime, Chart>,
                       sesi::Composition<coefficients::Runtime, Chart>>;

/// A composition with the weights of Table, as ProgramComposition.
template <class Table, class Chart>
ProgramComposition<Chart> make_composition() {
  if constexpr (sesi::Rechartable<Chart>) {
    using Engine = sesi::Composition<coefficients::Runtime, Chart, sesi::Splitting::kick_drift_kick>;
    auto engine = Engine::template of<Table>();
    return ProgramComposition<Chart>(sesi::RechartPolicy<typename Chart::Scalar>{}, std::move(engine));
  } else {
    return sesi::Composition<coefficients::Runtime, Chart>::template of<Table>();
  }
}

/// A composition for Sys: one type for every coefficient table.
template <class Sys>
class CompositionStepper final : public AnyStepper<Sys> {
 public:
  CompositionStepper(const Sys& sys, ProgramComposition<typename Sys::Chart> engine)
      : sys_(sys), engine_(std::move(engine)) {}
  void step(typename Sys::StateType& x, double t, double dt) override {
    engine_.do_step(std::cref(sys_), x, t, dt);
  }
  typename Sys::Workspace* workspace() override { return &engine_.workspace(); }

 private:
  const Sys& sys_;
  ProgramComposition<typename Sys::Chart> engine_;
};

/// The processed engine of the program for a chart (sesi::Processed over runtime weights, one type
/// for every processed table): on S^n and H^n in kick-drift-kick form with re-charting between
/// kernel steps, leaving and re-entering the kernel's variables around each re-charting
/// (sesi::RechartingProcessed), like ProgramComposition.
template <class Chart>
using ProgramProcessed =
    std::conditional_t<sesi::Rechartable<Chart>, sesi::RechartingProcessed<coefficients::Runtime, Chart>,
                       sesi::Processed<coefficients::Runtime, Chart>>;

/// A processed method for Sys over the processed table Table (include/sesi/processed.hpp).
template <class Sys>
class ProcessedStepper final : public AnyStepper<Sys> {
  using Chart = typename Sys::Chart;

 public:
  using StateType = typename Sys::StateType;
  template <class Table>
  static std::unique_ptr<AnyStepper<Sys>> make(const Sys& sys) {
    if constexpr (sesi::Rechartable<Chart>) {
      using Base = sesi::Processed<coefficients::Runtime, Chart, sesi::Splitting::kick_drift_kick>;
      return std::make_unique<ProcessedStepper>(
          sys, ProgramProcessed<Chart>(sesi::RechartPolicy<typename Chart::Scalar>{},
                                       Base::template of<Table>()));
    } else {
      return std::make_unique<ProcessedStepper>(sys, ProgramProcessed<Chart>::template of<Table>());
    }
  }
  ProcessedStepper(const Sys& sys, ProgramProcessed<Chart> engine) : sys_(sys), engine_(std::move(engine)) {}

  void step(StateType& x, double t, double dt) override { engine_.do_step(std::cref(sys_), x, t, dt); }
  bool processed() const override { return true; }
  void output(const StateType& x, StateType& y) override { engine_.post_process(std::cref(sys_), x, y); }
  double entered_step() const override { return engine_.entered() ? engine_.entered_step() : 0.0; }
  void assume_entered(double dt) override {
    if (dt == 0.0) {
      engine_.restart();
    } else {
      engine_.resume(dt);
    }
  }
  void reentered(const StateType& x, double dt, StateType& out) override {
    out = x;
    if (engine_.entered() && engine_.entered_step() == dt) return;
    if (engine_.entered()) engine_.apply_inverse_processor(std::cref(sys_), out, engine_.entered_step());
    engine_.apply_processor(std::cref(sys_), out, dt);
  }

 private:
  const Sys& sys_;
  ProgramProcessed<Chart> engine_;
};

/// A string usable as a template argument (for descriptions in the registry).
template <std::size_t N>
struct Text {
  char value[N];
  constexpr Text(const char (&text)[N]) { std::copy_n(text, N, value); }  // NOLINT: implicit
  constexpr std::string_view view() const { return {value, N - 1}; }
};

/// A symmetric composition of the seed's hierarchical Strang step (as sesi::Composition) with a
/// coefficient table of include/sesi/coefficients.hpp.
template <class Table, Text About>
struct CompositionMethod {
  static constexpr std::string_view name = Table::name;
  static constexpr int order = Table::order;
  static constexpr int stages = Table::stages;  // force evaluations per step (kick-drift-kick, FSAL)
  static constexpr int output_stages = 0;  // force evaluations per state read (none)
  static constexpr std::string_view about = About.view();
  template <class Sys>
  static std::unique_ptr<AnyStepper<Sys>> make(const Sys& sys) {
    return std::make_unique<CompositionStepper<Sys>>(
        sys, make_composition<Table, typename Sys::Chart>());
  }
};

/// A processed method (include/sesi/processed.hpp): the kernel of the processed table Table is
/// stepped, its processor applied where the state is read (ChartIntegrator::shown).
template <class Table, Text About>
struct ProcessedMethod {
  static constexpr std::string_view name = Table::name;
  static constexpr int order = Table::order;  // the effective order
  static constexpr int stages = Table::kernel::stages;  // force evaluations per step (the kernel's)
  static constexpr int output_stages = Table::processor_stages;  // per state read: P^{-1} on a copy
  static constexpr std::string_view about = About.view();
  template <class Sys>
  static std::unique_ptr<AnyStepper<Sys>> make(const Sys& sys) {
    return ProcessedStepper<Sys>::template make<Table>(sys);
  }
};

template <class... Method>
struct MethodList {};

// clang-format off
/// Every method of the program. To add one, add its descriptor here (nothing else changes).
using Methods = MethodList<
  CompositionMethod<coefficients::Strang,     "Strang splitting, the seed's SESI 2 (1 stage)">,
  CompositionMethod<coefficients::Yoshida4,   "Yoshida's triple jump, the seed's SESI 4 (3 stages)">,
  CompositionMethod<coefficients::Suzuki4,    "Suzuki's fractal composition (5 stages)">,
  CompositionMethod<coefficients::McLachlan4, "McLachlan's SS5, small error constant (5 stages)">,
  CompositionMethod<coefficients::Yoshida6,   "Yoshida's solution A (7 stages)">,
  CompositionMethod<coefficients::KahanLi6,   "Kahan and Li's s9odr6a (9 stages)">,
  CompositionMethod<coefficients::McLachlan8, "McLachlan's SS15 (15 stages)">,
  CompositionMethod<coefficients::KahanLi8,   "Kahan and Li's s17odr8a (17 stages)">,
  ProcessedMethod<coefficients::Blanes6Processed,
                  "processed, Blanes 2001 (7 stages; 10 more per output)">,
  ProcessedMethod<coefficients::BlanesCasasMurua8Processed,
                  "processed, Blanes-Casas-Murua 2006 (13 stages; 20 more per output)">,
  ProcessedMethod<coefficients::BlanesCasasMurua10Processed,
                  "processed, Blanes-Casas-Murua 2006 (23 stages; 24 more per output)">>;
// clang-format on

/// A geodesic method (S^n and H^n): the embedding splitting of include/sesi/reference/embedding.hpp
/// (exact geodesic drifts and tangential kicks on ambient points x and velocities v, no chart and
/// no re-charting) composed with a coefficient table. Stepped by EmbeddedIntegrator
/// (src/integrators/embedded_integrator.hpp), not by a chart stepper: make_integrator picks it by
/// is_embedded_method.
template <class Table, Text Name, Text About>
struct GeodesicMethod {
  using table = Table;
  static constexpr bool processed = false;
  static constexpr std::string_view name = Name.view();
  static constexpr int order = Table::order;
  static constexpr int stages = Table::stages;  // force evaluations per step
  static constexpr int output_stages = 0;  // force evaluations per state read (none)
  static constexpr std::string_view about = About.view();
};

/// A processed geodesic method: the processed table Table (as ProcessedMethod) over the geodesic
/// splitting (sesi::reference::GeodesicProcessed); the kernel is stepped, the processor applied
/// where the state is read (EmbeddedIntegrator::shown).
template <class Table, Text Name, Text About>
struct GeodesicProcessedMethod {
  using table = Table;
  static constexpr bool processed = true;
  static constexpr std::string_view name = Name.view();
  static constexpr int order = Table::order;            // the effective order
  static constexpr int stages = Table::kernel::stages;  // force evaluations per step (the kernel's)
  static constexpr int output_stages = Table::processor_stages;  // per state read: P^{-1} on a copy
  static constexpr std::string_view about = About.view();
};

// clang-format off
/// The geodesic methods, each on the table of the sesi method of the same suffix.
using EmbeddedMethods = MethodList<
  GeodesicMethod<coefficients::Strang,     "geodesic2",          "geodesic splitting in the embedding, Strang (S^n, H^n; 1 stage)">,
  GeodesicMethod<coefficients::Yoshida4,   "geodesic4",          "geodesic splitting, Yoshida's triple jump (3 stages)">,
  GeodesicMethod<coefficients::Yoshida6,   "geodesic6",          "geodesic splitting, Yoshida's solution A (7 stages)">,
  GeodesicMethod<coefficients::KahanLi6,   "geodesic6-kahan-li", "geodesic splitting, Kahan and Li's s9odr6a (9 stages)">,
  GeodesicMethod<coefficients::McLachlan8, "geodesic8",          "geodesic splitting, McLachlan's SS15 (15 stages)">,
  GeodesicMethod<coefficients::KahanLi8,   "geodesic8-kahan-li", "geodesic splitting, Kahan and Li's s17odr8a (17 stages)">,
  GeodesicProcessedMethod<coefficients::Blanes6Processed,            "geodesic6-processed",
                          "geodesic splitting, processed, Blanes 2001 (7 stages; 10 more per output)">,
  GeodesicProcessedMethod<coefficients::BlanesCasasMurua8Processed,  "geodesic8-processed",
                          "geodesic splitting, processed, Blanes-Casas-Murua 2006 (13 stages; 20 more per output)">,
  GeodesicProcessedMethod<coefficients::BlanesCasasMurua10Processed, "geodesic10-processed",
                          "geodesic splitting, processed, Blanes-Casas-Murua 2006 (23 stages; 24 more per output)">>;
// clang-format on

/// Is name a geodesic method (EmbeddedMethods)?
bool is_embedded_method(std::string_view name);

/// The chart compositions that are not processed (sesi2 .. sesi8-kahan-li), in registration order:
/// the methods that run on a space with a topology (check_topology_method, validate.hpp).
std::span<const std::string_view> composition_method_names();
bool is_composition_method(std::string_view name);

/// What --help and the scene checks need to know of a method.
struct MethodInfo {
  std::string_view name;
  int order;
  std::string_view about;
  int stages;  ///< force evaluations per step
  /// Force evaluations per state read between steps (an output row, a check): a processed
  /// method's post-processing and, after a step of another size, re-entry; 0 for the others.
  int output_stages;
};

/// All registered methods, in registration order.
std::span<const MethodInfo> method_catalogue();
/// Method names alone (for "did you mean").
std::span<const std::string_view> method_names();
/// Is name a registered method?
bool is_method(std::string_view name);
/// The method called name, or null.
const MethodInfo* find_method_info(std::string_view name);

namespace detail {
template <class Sys, class... Method>
std::unique_ptr<AnyStepper<Sys>> make_stepper(MethodList<Method...>, std::string_view name,
                                              const Sys& sys) {
  std::unique_ptr<AnyStepper<Sys>> out;
  const auto try_method = [&]<class M>() {
    if (name != M::name) return false;
    out = M::template make<Sys>(sys);
    return true;
  };
  static_cast<void>((try_method.template operator()<Method>() || ...));
  return out;
}
}  // namespace detail

/// The stepper called name for sys (nullptr for an unknown name; scenes are checked before).
template <class Sys>
std::unique_ptr<AnyStepper<Sys>> make_stepper(std::string_view name, const Sys& sys) {
  return detail::make_stepper<Sys>(Methods{}, name, sys);
}

}  // namespace sesi::program
