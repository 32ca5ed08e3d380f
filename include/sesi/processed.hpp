#pragma once
/// @file processed.hpp
/// Processed composition methods (issue #15): Psi_h = P^{-1} o K_h o P, with a kernel K_h and a
/// processor P that are both compositions of the seed's base step S (coefficients.hpp, "processed
/// methods"; S. Blanes, F. Casas, A. Murua, SIAM J. Sci. Comput. 27 (2006) 1817; HLW V.3.3).
///
/// n steps of Psi_h are P^{-1} K_h^n P: the processor cancels between steps, so only the kernel is
/// stepped (z_{n+1} = K_h(z_n), its `stages` force evaluations per step) and the processor is
/// applied where a state is entered (z_0 = P(y_0)) or read (y_n = P^{-1}(z_n), on a copy). The
/// kernel's variables z are not the state: they differ from it by O(h^2), so energy, positions
/// and every other output are read from post_process().
///
/// One engine: the kernel is a sesi::Composition over the kernel's weights, and P and P^{-1} are
/// Compositions over the processor's weights (g_1..g_m and -g_m..-g_1: S is symmetric, so
/// S(a)^{-1} = S(-a)); nothing in that engine assumes palindromic weights or weights summing to 1.
/// Each has its own instance, so that the kernel's trig caches and, in the kick-drift-kick form,
/// its last gradient (first same as last) survive a post-processing: reading the state between
/// two kernel steps costs the kernel nothing.
///
/// The processor depends on the step size h: z holds "the state entered with h". A step of
/// another size re-enters first (z <- P_{h'}(P_h^{-1}(z)), 2m stages: the cost of a change of
/// step, e.g. a shortened last step), and post_process uses the h the state was entered with.

#include <array>
#include <concepts>
#include <cstddef>
#include <string_view>
#include <type_traits>
#include <utility>
#include <variant>
#include <vector>

#include "sesi/coefficients.hpp"
#include "sesi/config.hpp"
#include "sesi/recharting.hpp"
#include "sesi/stepper.hpp"

namespace sesi {

/// A processed table (coefficients.hpp): an effective order, a kernel table and processor
/// weights g_1..g_m.
template <class T>
concept ProcessedTable = requires {
  { T::name } -> std::convertible_to<std::string_view>;
  { T::order } -> std::convertible_to<unsigned short>;
  { T::processor_stages } -> std::convertible_to<std::size_t>;
  { T::template processor<double>() } -> std::same_as<std::array<double, T::processor_stages>>;
  typename T::kernel;
  { T::kernel::template weights<double>() } -> std::same_as<std::array<double, T::kernel::stages>>;
};

namespace detail {
template <class Table>
struct kernel_table {
  using type = typename Table::kernel;
};
template <>
struct kernel_table<coefficients::Runtime> {
  using type = coefficients::Runtime;
};
/// P^{-1}'s weights from P's: -g_m, ..., -g_1.
template <class Scalar, class Weights>
std::vector<Scalar> inverse_processor(const Weights& g) {
  std::vector<Scalar> out(g.size());
  for (std::size_t k = 0; k < g.size(); ++k) out[k] = -g[g.size() - 1 - k];
  return out;
}
}  // namespace detail

/// A processed method over the processed table Table (or, with Table = coefficients::Runtime, over
/// weights given at run time: Processed<coefficients::Runtime, Chart>::of<Table>()).
///
/// Use (y the state, z = x the kernel's variables):
///
///     sesi::Processed<sesi::coefficients::BlanesCasasMurua8Processed, Chart> stepper;
///     stepper.pre_process(sys, x, dt);             // x: y -> z = P(y)
///     for (...) stepper.do_step(sys, x, t, dt);    // z -> K_dt(z)
///     stepper.post_process(sys, x, y);             // y = P^{-1}(z); x untouched
///     stepper.leave(sys, x);                       // or in place, x: z -> y
///
/// The stepper holds whether its state has been entered and with which step: one stepper per
/// state. do_step on a state not entered pre-processes it first, and post_process of a state not
/// entered is a copy, so x is always read through post_process. A state saved in the kernel's
/// variables (a checkpoint) is taken up again with resume(dt).
///
/// Engine is the composition engine of the kernel and the processor: sesi::Composition (the
/// seed's base step in chart coordinates), or any engine with its template signature, its
/// (weights, order) constructor and do_step, e.g. the embedding's geodesic splitting
/// (sesi::reference::GeodesicProcessed, reference/embedding.hpp).
template <class Table, HierarchicalChart Chart, Splitting Form = Splitting::drift_kick_drift,
          template <class, class, Splitting, class...> class Engine = Composition>
class Processed {
  static constexpr bool runtime_table = std::is_same_v<Table, coefficients::Runtime>;
  static_assert(runtime_table || ProcessedTable<Table>,
                "sesi::Processed needs a processed table (coefficients.hpp: kernel, processor_stages, "
                "processor<Scalar>()); a composition table goes with sesi::Composition");

 public:
  using Scalar = typename Chart::Scalar;
  /// The kernel's engine: a Composition over the kernel table (or runtime weights).
  using kernel_type = Engine<typename detail::kernel_table<Table>::type, Chart, Form>;
  /// The processor's engine (P and P^{-1}).
  using processor_type = Engine<coefficients::Runtime, Chart, Form>;
  using state_type = typename kernel_type::state_type;
  using deriv_type = state_type;
  using value_type = Scalar;
  using time_type = Scalar;
  using order_type = unsigned short;
  using table = Table;

  /// The effective order (0 for a runtime table: ask order()).
  static constexpr order_type order_value = Table::order;

  Processed() requires(!runtime_table && ProcessedTable<Table>)
      : kernel_(), pre_(table_processor<Table>(), 0),
        post_(detail::inverse_processor<Scalar>(Table::template processor<Scalar>()), 0) {}
  /// A runtime table: the kernel's weights (palindromic, sum 1), the processor's g_1..g_m (g_1
  /// applied first) and the effective order.
  Processed(std::vector<Scalar> kernel, std::vector<Scalar> processor, order_type order)
    requires runtime_table
      : kernel_(std::move(kernel), 0), pre_(processor, 0),
        post_(detail::inverse_processor<Scalar>(processor), 0), order_(order) {
    SESI_CHECK(!processor.empty(), "a processor needs at least one stage");
  }
  /// A runtime-table processed method with the weights and order of the processed table T.
  template <ProcessedTable T>
  static Processed of() requires runtime_table {
    const auto k = T::kernel::template weights<Scalar>();
    const auto g = T::template processor<Scalar>();
    return Processed(std::vector<Scalar>(k.begin(), k.end()), std::vector<Scalar>(g.begin(), g.end()),
                     T::order);
  }

  /// The effective order of P^{-1} K_h^n P.
  order_type order() const {
    if constexpr (runtime_table) {
      return order_;
    } else {
      return Table::order;
    }
  }
  /// Kernel stages: force evaluations per step.
  std::size_t stages() const { return kernel_.stages(); }
  /// Processor stages: force evaluations per pre- or post-processing.
  std::size_t processor_stages() const { return pre_.stages(); }
  const auto& kernel_weights() const { return kernel_.weights(); }
  /// g_1..g_m: P = S(g_m h) o ... o S(g_1 h).
  const std::vector<Scalar>& processor_weights() const { return pre_.weights(); }

  /// Whether the state is in the kernel's variables, and the step it was entered with.
  bool entered() const { return entered_; }
  time_type entered_step() const { return dt_; }

  /// Enter the kernel's variables: x <- P_dt(x). dt is the step the kernel will take.
  template <class Sys>
  void pre_process(Sys&& system, state_type& x, time_type dt) {
    SESI_CHECK(!entered_, "pre_process: the state is entered already (post-process or leave first)");
    SESI_CHECK(dt != time_type(0), "pre_process: the processor needs the (non-zero) step size");
    pre_.do_step(system, x, time_type(0), dt);
    dt_ = dt;
    entered_ = true;
  }

  /// One kernel step of dt: x <- K_dt(x), x in the kernel's variables. A state not entered is
  /// pre-processed first; one entered with another step is re-entered with dt (post- then
  /// pre-processing).
  template <class Sys>
  void do_step(Sys&& system, state_type& x, time_type t, time_type dt) {
    if (!entered_) {
      pre_process(system, x, dt);
    } else if (dt != dt_) {
      post_.do_step(system, x, t, dt_);
      pre_.do_step(system, x, t, dt);
      dt_ = dt;
    }
    kernel_.do_step(system, x, t, dt);
  }

  /// The state: out = P^{-1}(x) for the step x was entered with (a copy of x if not entered).
  /// x, and the kernel's caches, are untouched.
  template <class Sys>
  void post_process(Sys&& system, const state_type& x, state_type& out) {
    out = x;
    if (entered_) post_.do_step(system, out, time_type(0), dt_);
  }

  /// Leave the kernel's variables in place: x <- P^{-1}(x).
  template <class Sys>
  void leave(Sys&& system, state_type& x) {
    if (entered_) post_.do_step(system, x, time_type(0), dt_);
    entered_ = false;
  }

  /// x holds the kernel's variables for step dt already (saved from an entered state, e.g. a
  /// checkpoint): go on stepping it without pre-processing. Bit for bit the run that saved it.
  void resume(time_type dt) {
    SESI_CHECK(dt != time_type(0), "resume: the processor needs the (non-zero) step size");
    dt_ = dt;
    entered_ = true;
  }
  /// x holds the state itself again (e.g. one restored from before the first step): the next
  /// do_step pre-processes it.
  void restart() { entered_ = false; }

  /// The processor alone, in place and for any step: x <- P_dt(x), and x <- P_dt^{-1}(x). What
  /// the stepper holds (entered, and with which step) is not changed: for moving a state between
  /// the variables of two steps, P_{dt'}(P_dt^{-1}(z)), e.g. to save it for another step.
  template <class Sys>
  void apply_processor(Sys&& system, state_type& x, time_type dt) {
    pre_.do_step(system, x, time_type(0), dt);
  }
  template <class Sys>
  void apply_inverse_processor(Sys&& system, state_type& x, time_type dt) {
    post_.do_step(system, x, time_type(0), dt);
  }

  /// Forget the engines' caches (as Composition::reset); whether the state is entered is kept.
  void reset() {
    kernel_.reset();
    pre_.reset();
    post_.reset();
  }

 private:
  template <class T>
  static std::vector<Scalar> table_processor() {
    const auto g = T::template processor<Scalar>();
    return std::vector<Scalar>(g.begin(), g.end());
  }

  kernel_type kernel_;
  processor_type pre_, post_;
  time_type dt_ = time_type(0);
  bool entered_ = false;
  [[no_unique_address]] std::conditional_t<runtime_table, order_type, std::monostate> order_{};
};

/// A processed method that re-charts bodies between kernel steps (the counterpart of
/// RechartingComposition, kick-drift-kick form; docs/charts.md).
///
/// Re-charting changes a body's chart, and the base step, hence the kernel and the processor,
/// is chart-dependent: P_B^{-1} K_B^n P_B after P_A^{-1} K_A^k P_A is order p only if the state
/// crosses from chart A to chart B as y, not as z (z differs from y by P's O(h^2), which is
/// different in each chart). So when a body is to be re-charted after a kernel step, the state
/// leaves the kernel's variables in the old charts (P_A^{-1}), is re-charted, and enters again in
/// the new ones (P_B): 2m extra stages at each such step, none at the others (a cluster
/// re-centring alone moves no body's chart and is done on z directly). docs/scheme.md has the
/// measurements.
template <class Table, class Chart>
class RechartingProcessed : public Processed<Table, Chart, Splitting::kick_drift_kick> {
  using Base = Processed<Table, Chart, Splitting::kick_drift_kick>;

 public:
  using typename Base::state_type;
  using typename Base::time_type;
  using Scalar = typename Base::value_type;

  RechartingProcessed() = default;
  /// The policy, then Processed's own constructor arguments (or a Processed, e.g.
  /// Processed<coefficients::Runtime, Chart, Splitting::kick_drift_kick>::of<T>()).
  template <class... Args>
  explicit RechartingProcessed(RechartPolicy<Scalar> policy, Args&&... args)
      : Base(std::forward<Args>(args)...), policy_(policy) {}

  template <class Sys>
  void do_step(Sys&& system, state_type& x, time_type t, time_type dt) {
    Base::do_step(system, x, t, dt);
    using Raw = std::remove_cvref_t<Sys>;
    const auto& sys = detail::unwrap<Raw>::get(system);
    Recharted done;
    if (needs_rechart(sys, x)) {
      Base::leave(system, x);
      done = rechart(sys, x, policy_);
      Base::pre_process(system, x, dt);
      ++reentries_;
    } else {
      done = rechart(sys, x, policy_);  // a cluster re-centring (and frames given), no body
    }
    turns_ += done.turned;
    homes_ += done.homed;
  }

  const RechartPolicy<Scalar>& policy() const { return policy_; }
  /// Re-chartings done so far (turns and homings), and the homings alone.
  long recharts() const { return turns_ + homes_; }
  long homes() const { return homes_; }
  /// Steps after which the state left and re-entered the kernel's variables to be re-charted.
  long reentries() const { return reentries_; }

 private:
  /// Whether rechart() would turn or home a body of x.
  template <class Sys>
  bool needs_rechart(const Sys& sys, const state_type& x) const {
    if constexpr (Rechartable<Chart>) {
      const Chart& chart = sys.chart();
      typename Chart::Point q(dim_of(chart)), p(dim_of(chart));
      for (int b = 0; b < x.bodies(); ++b) {
        q = x.q.col(b);
        p = x.p.col(b);
        if (chart.rechart_action(q, p, policy_) != RechartAction::none) return true;
      }
    }
    static_cast<void>(sys);
    static_cast<void>(x);
    return false;
  }

  RechartPolicy<Scalar> policy_{};
  long turns_ = 0;
  long homes_ = 0;
  long reentries_ = 0;
};

/// The processed methods by their tables (coefficients.hpp) and by the program's names.
template <class Chart>
using Blanes6Processed = Processed<coefficients::Blanes6Processed, Chart>;
template <class Chart>
using BlanesCasasMurua8Processed = Processed<coefficients::BlanesCasasMurua8Processed, Chart>;
template <class Chart>
using BlanesCasasMurua10Processed = Processed<coefficients::BlanesCasasMurua10Processed, Chart>;
template <class Chart>
using Sesi6Processed = Blanes6Processed<Chart>;
template <class Chart>
using Sesi8Processed = BlanesCasasMurua8Processed<Chart>;
template <class Chart>
using Sesi10Processed = BlanesCasasMurua10Processed<Chart>;

}  // namespace sesi
