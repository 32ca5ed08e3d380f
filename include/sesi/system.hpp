#pragma once
/// @file system.hpp
/// A Hamiltonian system: bodies (masses) on one chart, plus potential terms.
/// H = sum_b sum_i K_i(q_b, p_b; m_b) + sum of the terms on the embedding points x_b = embed(q_b).
/// Only what the system has is compiled into its step: without terms there is no kick at all,
/// and a pair loop exists only for pair terms.
///
/// On a quotient (a chart with a topology: Quotient, topology.hpp) every pair term is evaluated
/// on the minimum image (Allen & Tildesley, 2nd ed., sec. 1.6.2; on a compact hyperbolic surface,
/// Sausset & Tarjus, J. Phys. A 40, 12873 (2007)): the pair (i, j) is W(d(x_i, y)) with y the
/// image of x_j nearest to x_i, and dW/dx_i is taken there. Pair sums always go by rows, each
/// body summing its own partners in ascending (j, image) order, so the result does not depend
/// on the thread count. The minimum image is unique for a cutoff up to the topology's
/// max_cutoff(), which the program enforces; a pair term without a range is summed over the
/// minimum images of all pairs (a truncation, not a lattice sum: the program refuses such a
/// term on a quotient, as it refuses external terms there, which the system applies unchanged).

#include <cmath>
#include <algorithm>
#include <array>
#include <atomic>
#include <concepts>
#include <cstdint>
#include <cstdlib>
#include <functional>
#include <limits>
#include <tuple>
#include <type_traits>
#include <utility>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "sesi/chart.hpp"
#include "sesi/config.hpp"
#include "sesi/neighbours.hpp"
#include "sesi/parallel.hpp"
#include "sesi/potentials.hpp"
#include "sesi/profile.hpp"
#include "sesi/state.hpp"

namespace sesi {

namespace detail {
/// A stamp unique to each System object: a copy, a move or an assignment takes a new one. The
/// kick-drift-kick stepper keeps the last gradient for the same system, which an address does
/// not tell (a System rebuilt in a loop with new parameters takes its predecessor's place).
struct InstanceStamp {
  std::uint64_t value = next();
  InstanceStamp() = default;
  InstanceStamp(const InstanceStamp&) : value(next()) {}
  InstanceStamp& operator=(const InstanceStamp&) {
    value = next();
    return *this;
  }
  static std::uint64_t next() {
    static std::atomic<std::uint64_t> counter{0};
    return ++counter;
  }
};
}  // namespace detail

/// Per-body trig caches for charts that have them; nothing otherwise.
template <class Chart>
struct TrigStore {
  void resize(int, int) {}
};
template <HasTrigCache Chart>
struct TrigStore<Chart> {
  std::vector<typename Chart::TrigType> trig;
  void resize(int dim, int bodies) {
    if (static_cast<int>(trig.size()) != bodies) trig.resize(static_cast<std::size_t>(bodies));
    for (auto& t : trig) t.resize(dim);
  }
};

/// Scratch space of a step for one chart type, sized once (steppers own one, so a step
/// allocates nothing).
template <HierarchicalChart Chart>
struct Workspace : TrigStore<Chart> {
  using Scalar = typename Chart::Scalar;
  static constexpr int ambient_dimension = detail::ambient_dimension_of<Chart>();
  using Point = typename Chart::Point;
  using AmbientVector = Eigen::Matrix<Scalar, ambient_dimension, 1>;
  using AmbientMatrix = Eigen::Matrix<Scalar, ambient_dimension, Eigen::Dynamic>;

  Point q, p;            // one body's coordinates and momenta
  AmbientVector x, y, g, gy;  // one body's (or pair's) ambient points and gradients
  AmbientMatrix X, G;    // all bodies' embedding points and potential gradients

  /// One chunk's scratch in the loops over bodies that run on threads (parallel.hpp).
  struct Scratch {
    Point q, p, gq;  // gq: one chart-coordinate term's dV/dq
    AmbientVector x, y, g, h, acc;
  };
  std::vector<Scratch> scratch;
  /// Per body: a row's share of a sum (energies), summed in body order afterwards.
  std::vector<Scalar> rows;
  /// Per term of the system (by position): the Verlet list of a short-range term.
  std::vector<VerletList<Chart>> verlet;
  /// Another workspace's Verlet lists used instead of verlet (share_lists), or none.
  struct Borrowed {
    std::vector<VerletList<Chart>>* lists = nullptr;
    Borrowed() = default;
    Borrowed(const Borrowed&) {}  // a copy owns its lists: a borrow is its owner's arrangement
    Borrowed& operator=(const Borrowed&) { return *this; }
  } borrowed;
  /// Use other's Verlet lists from now on (nullptr: its own again), e.g. diagnostics at the
  /// points a stepper just evaluated, so that one neighbour structure serves both. The caller
  /// keeps other alive and never uses the two workspaces at once. Results do not change: lists
  /// are rebuilt whenever they do not fit the points (VerletList::update).
  void share_lists(Workspace* other) { borrowed.lists = other ? &other->verlet : nullptr; }
  std::vector<VerletList<Chart>>& lists() { return borrowed.lists ? *borrowed.lists : verlet; }
  /// The tiles' partial gradients (System's symmetric pair sums on threads).
  std::vector<Scalar> tile_gradients;
  /// A domain's points of every body of the whole simulation (System::set_whole_run: pair terms
  /// without a cutoff).
  AmbientMatrix whole;
  /// System::patch_gradient's marks (one per body) and the bodies whose rows it recomputes.
  std::vector<char> marks;
  std::vector<int> affected;
  /// The pair sums through Verlet lists (System::add_gradient_by_pairs) of the lists pair_lists
  /// at build pair_builds, laid out in the lists' visit order (the bodies sorted by cell), so
  /// that a row's partners and their pairs lie in nearby memory whatever the bodies' order:
  /// visit (position s -> body) and visit_pos (body -> s); the points and masses in that order
  /// (visit_X, visit_mass: copied at every evaluation); the pairs i < j row by row in that order
  /// (pair_first, pair_second: positions; pair_base: each position's first pair); each row's
  /// entries in that order (visit_row: each position's first entry; entry_pos: the partner's
  /// position, entry_pair: the entry's pair), and per pair k its dW/dd / sn: in a copy in visit
  /// order alone (pair_value[k]; the row's sum forms 1 - cs again from the two points it reads
  /// anyway, 8 bytes a pair and an entry less to move: S^3's 10^5 bodies 248 MB to 231 MB), in the
  /// bodies' own order with 1 - cs beside it (pair_value[2k], pair_value[2k + 1]: one cache line;
  /// recomputing it there made S^2's two-thread force phase 8 % longer).
  std::vector<Scalar> pair_value, visit_mass;
  AmbientMatrix visit_X;
  /// Whether the visit order is the bodies' own (index_pairs' choice): then X and the masses are
  /// read where they are, with no copy. points_in_order, masses_in_order: what the passes read.
  bool visit_own = false;
  const AmbientMatrix* points_in_order = nullptr;
  const Scalar* masses_in_order = nullptr;
  std::vector<long> order_counts;  // index_pairs' per chunk counts (System::own_order_is_local)
  std::vector<int> visit, visit_pos, visit_row, entry_pos, entry_pair;
  std::vector<int> pair_first, pair_second, pair_base;
  std::vector<int> pair_scan;  // parallel::prefix_sums' per chunk (pair_base, visit_row)
  const NeighbourLists* pair_lists = nullptr;
  long pair_builds = -1;
  /// The state's cluster frame C (State::cluster) while the terms are evaluated: external terms
  /// see their centres in the cluster's frame (or, without a centre, world points C x).
  Eigen::Matrix<Scalar, ambient_dimension, ambient_dimension> cluster;
  bool clustered = false;

  /// Scratch for `chunks` chunks of the given sizes (allocates only when they grow).
  void ensure_scratch(int chunks, int dim, int ambient) {
    if (static_cast<int>(scratch.size()) < chunks) scratch.resize(static_cast<std::size_t>(chunks));
    for (Scratch& s : scratch) {
      if (s.q.size() != dim) {
        s.q.resize(dim);
        s.p.resize(dim);
        s.gq.resize(dim);
      }
      if (s.x.size() != ambient) {
        s.x.resize(ambient);
        s.y.resize(ambient);
        s.g.resize(ambient);
        s.h.resize(ambient);
        s.acc.resize(ambient);
      }
    }
  }

  Workspace() {
    // Fixed-size members start defined, so that copying a fresh stepper copies no garbage.
    if constexpr (Chart::dimension != Eigen::Dynamic) {
      q.setZero();
      p.setZero();
    }
    if constexpr (ambient_dimension != Eigen::Dynamic) {
      x.setZero();
      y.setZero();
      g.setZero();
      gy.setZero();
    }
  }

  void resize(int dim, int ambient, int bodies) {
    if (X.cols() != bodies || X.rows() != ambient) {
      TrigStore<Chart>::resize(dim, bodies);
      X.resize(ambient, bodies);
      G.resize(ambient, bodies);
    }
    if (q.size() != dim) {
      q.resize(dim);
      p.resize(dim);
    }
    if (x.size() != ambient) {
      x.resize(ambient);
      y.resize(ambient);
      g.resize(ambient);
      gy.resize(ambient);
    }
  }
};

namespace detail {
/// A potential term's requirements, with a message that names both concepts (System's check).
template <class Term, class Chart>
constexpr bool report_term() {
  static_assert(ChartTerm<Term, Chart> || ExternalTerm<Term, Chart> || PairTerm<Term, Chart>,
                "sesi: a potential term must model ExternalTerm (value(chart, x, m) and gradient(chart, x, m, g) "
                "on an embedding point x), PairTerm (distance_kind, value(chart, d, m_i, m_j) and "
                "derivative(chart, d, m_i, m_j)) or ChartTerm (coordinates, value(chart, q, m) and "
                "gradient(chart, q, m, g) on chart coordinates q); docs/concepts.md");
  return true;
}
/// The chart's and the terms' requirements, each failure with its own message. Only terms on
/// embedding points need an embedded chart.
template <class Chart, class... Terms>
constexpr bool report_system() {
  static_cast<void>(report_hierarchical_chart<Chart>());
  if constexpr (HierarchicalChart<Chart> && sizeof...(Terms) > 0) {
    if constexpr (((!ChartTerm<Terms, Chart>) || ...)) static_cast<void>(report_embedded_chart<Chart>());
    static_cast<void>((report_term<Terms, Chart>() && ...));
  }
  return true;
}
}  // namespace detail

template <class Chart_, class... Terms>
class System {
  // First, so that a mistake in the chart or a term is the first error (docs/concepts.md).
  static_assert(detail::report_system<Chart_, Terms...>());

 public:
  using Chart = Chart_;
  using Scalar = typename Chart::Scalar;
  using Point = typename Chart::Point;
  using StateType = State<Chart>;
  static constexpr int ambient_dimension = detail::ambient_dimension_of<Chart>();

  static constexpr bool has_potential = sizeof...(Terms) > 0;
  /// Terms on embedding points (they need an EmbeddedChart), and terms on chart coordinates.
  static constexpr bool has_embedded_terms = ((!ChartTerm<Terms, Chart>) || ... || false);
  static constexpr bool has_chart_terms = (ChartTerm<Terms, Chart> || ... || false);

  /// External terms with force centres that a cluster frame can move: a public world centre
  /// `center` on which the value depends through the distance only (CentralCotangent), or an
  /// aggregate that moves its own (`in_frame(chart, C)`, the term as seen from the frame C, and
  /// `has_centres()`, e.g. the program's list of a scene's external terms). In a cluster frame
  /// they are evaluated with the centres moved into the cluster's frame, C^{-1} c, computed by
  /// the chart without cancellation (Hyperbolic::to_frame), so a centre near the cluster is O(1)
  /// like the bodies.
  using Frame = Eigen::Matrix<Scalar, ambient_dimension, ambient_dimension>;
  template <class Term>
  static constexpr bool has_movable_center =
      requires(Term t, const Chart& c, const Frame& frame) { c.to_frame(frame, t.center, t.center); } ||
      requires(const Term& t, const Chart& c, const Frame& frame) {
        { t.in_frame(c, frame) } -> std::same_as<Term>;
        { t.has_centres() } -> std::convertible_to<bool>;
      };
  /// Whether some term has such a centre: then a cluster frame stays where it was put (at the
  /// centre; sesi::recentre), since a far centre off the frame's origin is known only to
  /// eps sinh D (docs/charts.md).
  bool has_movable_centres() const {
    bool any = false;
    std::apply([&](const auto&... term) { ((any = any || has_centres_of(term)), ...); }, terms_);
    return any;
  }
  /// The term as the system evaluates it on w's cluster-local points: with the centre moved
  /// into the cluster frame when w.clustered (for a check on w.X, e.g. a close-encounter floor).
  template <class Term>
    requires has_movable_center<Term>
  Term in_cluster_frame(const Term& term, const sesi::Workspace<Chart>& w) const {
    return w.clustered ? localized(term, w) : term;
  }

  using Workspace = sesi::Workspace<Chart>;
  using AmbientVectorOf = typename Workspace::AmbientVector;

  System(Chart chart, std::vector<Scalar> masses, Terms... terms)
      : chart_(std::move(chart)), masses_(std::move(masses)), terms_(std::move(terms)...) {
    for ([[maybe_unused]] Scalar m : masses_) SESI_CHECK(m > Scalar(0), "masses must be positive");
    if constexpr (on_quotient) {
      // Beyond max_cutoff a pair would meet two images, or one the search does not see.
      std::apply([&](const auto&... term) { (check_cutoff(term), ...); }, terms_);
    }
  }

  const Chart& chart() const { return chart_; }
  const std::vector<Scalar>& masses() const { return masses_; }
  Scalar mass(int b) const { return masses_[static_cast<std::size_t>(b)]; }
  int bodies() const { return static_cast<int>(masses_.size()); }
  int dim() const { return dim_of(chart_); }
  /// This object's stamp (detail::InstanceStamp): equal for one object only, whatever its address.
  std::uint64_t instance() const { return instance_.value; }
  const std::tuple<Terms...>& terms() const { return terms_; }

  /// How pair sums are formed. automatic: below rows_from bodies the symmetric loop over pairs
  /// i < j on one thread; from rows_from on, rows (each body sums its own pairs, on threads, so
  /// the result does not depend on the thread count), short-range terms through a Verlet list
  /// (neighbours.hpp). all_pairs: rows over all pairs even for short-range terms (the reference
  /// the lists are tested against: both give the same forces to the bit).
  enum class PairSearch { automatic, all_pairs };
  void set_pair_search(PairSearch search) { pair_search_ = search; }
  PairSearch pair_search() const { return pair_search_; }
  /// The skin of the short-range terms' Verlet lists, as a fraction of each term's range
  /// (VerletList::skin_fraction, default default_skin_fraction); 0 rebuilds the lists at every evaluation. The
  /// forces do not depend on it, only the time they take (docs/benchmarks.md, "Skin").
  void set_neighbour_skin(Scalar fraction) { neighbour_skin_ = fraction; }
  Scalar neighbour_skin() const { return neighbour_skin_; }
  static constexpr int rows_from = parallel::min_parallel_bodies;
  /// Whether the chart has a topology: pair terms on the minimum image, always by rows.
  static constexpr bool on_quotient = detail::QuotientChart<Chart>;
  bool by_rows() const { return on_quotient || domain_ || bodies() >= rows_from; }

  /// A domain of one simulation across processes (the program's src/domain; Plimpton, J. Comput.
  /// Phys. 117, 1 (1995)): the system holds the bodies one process steps and copies of the bodies
  /// within reach of them (its halo, stepped elsewhere). `drifted` refreshes the copies after
  /// every drift (drifted(), which the composition engine calls before each kick); `sum` takes a
  /// sum over bodies (the rows of an energy, say) over the bodies this process owns, in the whole
  /// system's body order, so that every process gets one process's bits. A domain sums pairs by
  /// rows at any size (as the whole system does from rows_from bodies on). Empty functions: one
  /// process.
  using RowSum = std::function<Scalar(const std::vector<Scalar>&)>;
  using Drifted = std::function<void(StateType&, Workspace&)>;
  void set_domain(RowSum sum, Drifted drifted) {
    row_sum_ = std::move(sum);
    drifted_ = std::move(drifted);
    domain_ = static_cast<bool>(row_sum_);
  }
  /// Whether this system is a domain of a simulation across processes (set_domain).
  bool domain() const { return domain_; }
  /// A domain's view of the whole simulation, for pair terms without a cutoff (whole_run_terms):
  /// each body this process owns pairs with every body of the whole simulation, not only with
  /// its halo. ids: each body's index in the whole simulation; own: the bodies this process owns
  /// (indices here, ascending); masses: the whole simulation's; gather(local, rows, whole): the
  /// own bodies' columns of local (rows x bodies(), column-major) from every process into whole
  /// (rows x masses.size(), in the whole simulation's body order), on every process (a collective
  /// call, made at every evaluation of such a term). An own body's sums are then one process's
  /// to the bit (add_whole_run_gradient).
  using Gather = std::function<void(const Scalar* local, int rows, Scalar* whole)>;
  void set_whole_run(std::vector<int> ids, std::vector<int> own, std::vector<Scalar> masses, Gather gather) {
    whole_ids_ = std::move(ids);
    whole_own_ = std::move(own);
    whole_masses_ = std::move(masses);
    gather_ = std::move(gather);
  }
  /// Whether an active pair term has no cutoff: every body's force depends on every body.
  bool whole_run_terms() const {
    bool any = false;
    std::apply([&](const auto&... term) {
      ((any = any || (long_range<std::remove_cvref_t<decltype(term)>> && !inactive(term))), ...);
    }, terms_);
    return any;
  }
  /// A new stamp (instance()): a stepper's gradient kept for this system is dropped, as for
  /// another system, and the next kick evaluates afresh (the same bits as the kept one where
  /// nothing changed).
  void renew_instance() { instance_ = detail::InstanceStamp(); }
  /// The sum of rows over bodies: in body order, or the domain's.
  Scalar sum_rows(const std::vector<Scalar>& rows) const {
    return row_sum_ ? row_sum_(rows) : parallel::sum_in_order(rows);
  }
  /// After a drift: a domain's halo is brought up to date (nothing for one process).
  void drifted(StateType& s, Workspace& w) const {
    if (drifted_) drifted_(s, w);
  }
  /// Refresh the trig caches of w for the given bodies only (their q changed from outside the
  /// level flows: a domain's halo).
  void refresh_bodies(const StateType& s, Workspace& w, const std::vector<int>& changed) const {
    if constexpr (HasTrigCache<Chart>) {
      Point q(dim());
      for (const int b : changed) {
        q = s.q.col(b);
        chart_.refresh(q, w.trig[static_cast<std::size_t>(b)]);
      }
    } else {
      static_cast<void>(s);
      static_cast<void>(w);
      static_cast<void>(changed);
    }
  }

  Workspace make_workspace() const {
    Workspace w;
    w.resize(dim(), ambient_dim(), bodies());
    return w;
  }
  int ambient_dim() const {
    return ambient_dim_of(chart_);
  }

  /// The bodies' kinetic energies on threads, summed in body order (the bits of a plain loop).
  Scalar kinetic_energy(const StateType& s) const {
    std::vector<Scalar> rows(static_cast<std::size_t>(bodies()));
    parallel::for_chunks(bodies(), parallel::chunks_for(bodies()), [&](int begin, int end, int) {
      Point q(dim()), p(dim());
      for (int b = begin; b < end; ++b) {
        q = s.q.col(b);
        p = s.p.col(b);
        rows[static_cast<std::size_t>(b)] = sesi::kinetic_energy(chart_, q, p, mass(b));
      }
    });
    return sum_rows(rows);
  }

  /// Refresh the per-body trig caches of w from s (charts with HasTrigCache; else nothing).
  void refresh(const StateType& s, Workspace& w) const {
    w.resize(dim(), ambient_dim(), bodies());
    if constexpr (HasTrigCache<Chart>) {
      for_bodies(w, [&](int b, typename Workspace::Scratch& sc) {
        sc.q = s.q.col(b);
        chart_.refresh(sc.q, w.trig[static_cast<std::size_t>(b)]);
      });
    }
  }

  /// f(b, scratch) for every body b, on threads from parallel::min_parallel_bodies bodies on
  /// (f must write only to body b's entries).
  template <class F>
  void for_bodies(Workspace& w, F&& f) const {
    const int n = bodies();
    const int chunks = parallel::chunks_for(n);
    w.ensure_scratch(chunks, dim(), ambient_dim());
    if (chunks == 1) {  // few bodies or one thread: a plain loop the compiler can inline
      const profile::Loop region(parallel::shared_loop(n));  // a parallel region in a profile
      region.chunk([&] {
        for (int b = 0; b < n; ++b) f(b, w.scratch.front());
      });
      return;
    }
    parallel::for_chunks(n, chunks, [&](int begin, int end, int c) {
      typename Workspace::Scratch& sc = w.scratch[static_cast<std::size_t>(c)];
      for (int b = begin; b < end; ++b) f(b, sc);
    });
  }

  /// Embedding points of all bodies into w.X.
  void embed_all(const StateType& s, Workspace& w) const {
    refresh(s, w);
    embed_cached(s, w);
  }

  Scalar potential_energy(const StateType& s, Workspace& w) const {
    if constexpr (!has_potential) {
      return Scalar(0);
    } else {
      if constexpr (has_embedded_terms) embed_all(s, w);
      Scalar v(0);
      int index = 0;
      std::apply([&](const auto&... term) { ((v += any_term_energy(term, s, w, index++)), ...); }, terms_);
      return v;
    }
  }
  Scalar potential_energy(const StateType& s) const {
    Workspace w = make_workspace();
    return potential_energy(s, w);
  }
  Scalar energy(const StateType& s, Workspace& w) const {
    return kinetic_energy(s) + potential_energy(s, w);
  }
  Scalar energy(const StateType& s) const {
    Workspace w = make_workspace();
    return energy(s, w);
  }

  /// The potential energy of the points in w.X (cluster-local when w.clustered), for states
  /// held in the embedding (reference::EmbeddedState): the terms summed as potential_energy
  /// does, so a state with the same points has the same energy to the bit. Terms on embedding
  /// points only (no ChartTerm: those need chart coordinates).
  Scalar ambient_potential_energy(Workspace& w) const requires(!has_chart_terms) {
    Scalar v(0);
    int index = 0;
    std::apply([&](const auto&... term) { ((v += term_energy(term, w, index++)), ...); }, terms_);
    return v;
  }

  /// Ambient gradients of the potential for all bodies into w.G (w.X must hold the points).
  void ambient_gradient(Workspace& w) const {
    // Zeroed on threads (at 10^5 bodies a serial setZero was a third of a step's serial time).
    parallel::for_chunks(static_cast<int>(w.G.cols()), parallel::chunks_for(static_cast<int>(w.G.cols())),
                         [&](int begin, int end, int) { w.G.middleCols(begin, end - begin).setZero(); });
    int index = 0;
    std::apply([&](const auto&... term) { (add_embedded_gradient(term, w, index++), ...); }, terms_);
  }

  /// The potential kick: p -= h dV/dq, with dV/dq = J(q)^T dV/dx per body.
  void kick(StateType& s, Scalar h, Workspace& w) const {
    if constexpr (has_potential) {
      refresh(s, w);
      kick_cached(s, h, w);
    }
  }

  /// The kick when w's trig caches already hold the trig of s.q (the composition engine keeps
  /// them in sync through the level flows, so a kick computes no sine).
  void kick_cached(StateType& s, Scalar h, Workspace& w) const {
    if constexpr (has_potential) {
      const profile::Scope scope(profile::Phase::force);
      prepare_gradients(s, w);
      for_bodies(w, [&](int b, typename Workspace::Scratch& sc) {
        body_gradient(s, w, b, sc);
        s.p.col(b) -= h * sc.p;
      });
    }
  }
  /// The same kick, also keeping the chart gradient dV/dq of every body in grad (dim x bodies),
  /// for a stepper that reuses it while q and the frames stay as they are.
  void kick_cached(StateType& s, Scalar h, Workspace& w, typename StateType::Matrix& grad) const {
    if constexpr (has_potential) {
      const profile::Scope scope(profile::Phase::force);
      prepare_gradients(s, w);
      grad.resize(dim(), bodies());
      for_bodies(w, [&](int b, typename Workspace::Scratch& sc) {
        body_gradient(s, w, b, sc);
        // A plain loop: GCC 12 leaves Eigen's `grad.col(b) = sc.p` out of line here, 5 % of
        // the seed scene's step (perf, `sesi bench --scene paper`).
        for (Eigen::Index i = 0; i < sc.p.size(); ++i) {
          grad(i, b) = sc.p(i);
          s.p(i, b) -= h * sc.p(i);
        }
      });
    }
  }

  /// After kick_cached(s, h, w, grad), bodies `changed` (ascending) took other chart coordinates
  /// or frames (a re-charting or a reduction into a topology's domain, which keep the world
  /// point; or any other change): grad and w's caches are brought to what kick_cached at the new
  /// s would leave, bit for bit, recomputing only the rows that depend on a changed body -- the
  /// changed bodies and their partners in the short-range terms' lists at the old points and at
  /// the new (every other row sees the same points, so a fresh evaluation repeats its bits). s.clustered and s.cluster must be as at the kick. Returns
  /// false, changing nothing the next kick_cached would not recompute anyway, where every body
  /// depends on every other (a long-range or chord pair term, or the few-body symmetric pair
  /// loop) or more than a sixteenth of the bodies changed: the caller then evaluates afresh.
  bool patch_gradient(const StateType& s, Workspace& w, const std::vector<int>& changed,
                      typename StateType::Matrix& grad) const {
    if constexpr (!has_potential || !has_embedded_terms) {
      static_cast<void>(s);
      static_cast<void>(w);
      static_cast<void>(changed);
      static_cast<void>(grad);
      return false;
    } else {
      const int n = bodies();
      if (grad.cols() != n || w.X.cols() != n || static_cast<int>(changed.size()) * 16 > n || !rows_only(w)) {
        return false;
      }
      const profile::Scope scope(profile::Phase::force);
      w.ensure_scratch(1, dim(), ambient_dim());
      typename Workspace::Scratch& sc = w.scratch.front();
      // The rows to recompute: the changed bodies and every partner of one, at the old points
      // (the lists the kick used fit them) and at the new ones (a body may have moved: a user's
      // change of the state between steps), so that no row keeps a changed body's old share.
      std::array<const NeighbourLists*, sizeof...(Terms)> lists{};  // each short-range term's
      // Marks are set for the bodies collected in w.affected and cleared again at the end: no
      // pass over all the bodies (a serial one was most of a step's serial time at 10^5 bodies).
      w.marks.resize(static_cast<std::size_t>(n), 0);
      w.affected.clear();
      for (const int b : changed) mark(w, b);
      int index = 0;
      // (w.X holds the kick's points here, where the kick brought the lists up to date: no body
      // has moved since, so no list check.)
      std::apply([&](const auto&... term) { (mark_partners(term, w, changed, {}, index++, lists), ...); }, terms_);
      // The changed bodies' trig and world points, as refresh and embed_cached compute them.
      for (const int b : changed) {
        sc.q = s.q.col(b);
        if constexpr (HasTrigCache<Chart>) {
          chart_.refresh(sc.q, w.trig[static_cast<std::size_t>(b)]);
          chart_.embed(w.trig[static_cast<std::size_t>(b)], sc.x);
        } else {
          chart_.embed(sc.q, sc.x);
        }
        if (s.framed()) {
          w.X.col(b).noalias() = s.frames[static_cast<std::size_t>(b)] * sc.x;
        } else {
          w.X.col(b) = sc.x;
        }
      }
      index = 0;  // (lists are symmetric: a row that sees b is a row b sees; the changed bodies moved)
      std::apply([&](const auto&... term) { (mark_partners(term, w, changed, changed, index++, lists), ...); }, terms_);
      std::sort(w.affected.begin(), w.affected.end());
      for (const int b : w.affected) w.marks[static_cast<std::size_t>(b)] = 0;
      const int count = static_cast<int>(w.affected.size());
      w.ensure_scratch(parallel::chunks_for(count), dim(), ambient_dim());
      const auto rows = [&](int begin, int end, int c) {
        typename Workspace::Scratch& scr = w.scratch[static_cast<std::size_t>(c)];
        for (int a = begin; a < end; ++a) {
          const int i = w.affected[static_cast<std::size_t>(a)];
          w.G.col(i).setZero();
          int t = 0;
          std::apply([&](const auto&... term) { (add_row_of(term, w, i, lists[static_cast<std::size_t>(t++)], scr), ...); },
                     terms_);
          body_gradient(s, w, i, scr);
          for (Eigen::Index k = 0; k < scr.p.size(); ++k) grad(k, i) = scr.p(k);
        }
      };
      parallel::for_chunks(count, parallel::chunks_for(count), rows);
      return true;
    }
  }

  /// The Verlet lists of an active short-range pair term whose range is at least reach, brought
  /// up to date at w.X (the points of w's last evaluation), or null when there is none: every
  /// pair closer than reach is in them (a close-encounter check needs no index of its own).
  const NeighbourLists* neighbour_lists(Workspace& w, Scalar reach) const {
    const NeighbourLists* found = nullptr;
    if (!by_rows() || w.X.cols() != bodies()) return found;
    int index = 0;
    std::apply(
        [&](const auto&... term) {
          (([&] {
             const int k = index++;
             if constexpr (PairTerm<std::remove_cvref_t<decltype(term)>, Chart> &&
                           ShortRangeTerm<std::remove_cvref_t<decltype(term)>, Chart>) {
               if (!found && !inactive(term) && term.range(chart_) >= reach) found = lists_of(term, w, k);
             }
           }()),
           ...);
        },
        terms_);
    return found;
  }

  /// Chart gradient dV/dq of all bodies (dim x bodies), for reference methods and tests.
  void potential_gradient(const StateType& s, Workspace& w,
                          typename StateType::Matrix& out) const {
    out.setZero(dim(), bodies());
    if constexpr (has_potential) {
      refresh(s, w);
      prepare_gradients(s, w);
      for_bodies(w, [&](int b, typename Workspace::Scratch& sc) {
        body_gradient(s, w, b, sc);
        out.col(b) = sc.p;
      });
    }
  }

  /// sum_b Delta_b V at s: the Laplace-Beltrami operator of the potential in each body's
  /// position, in the space's metric, summed over the bodies (a pair term counts at both of its
  /// bodies); the denominator of the configurational temperature (diagnostics.hpp). Pair terms
  /// by rows (each body sums its partners in ascending order, through the Verlet list of a
  /// short-range term), the rows in body order: the same bits for any thread count. NaN when a
  /// term has no Laplacian (potentials.hpp: laplacian, second_derivative) or, for pair terms,
  /// the chart has no curvature().
  Scalar laplacian_sum(const StateType& s, Workspace& w) const {
    if constexpr (!has_potential) {
      static_cast<void>(s);
      static_cast<void>(w);
      return Scalar(0);
    } else {
      if constexpr (has_embedded_terms) embed_all(s, w);
      Scalar v(0);
      int index = 0;
      std::apply([&](const auto&... term) { ((v += term_laplacian(term, s, w, index++)), ...); }, terms_);
      return v;
    }
  }
  Scalar laplacian_sum(const StateType& s) const {
    Workspace w = make_workspace();
    return laplacian_sum(s, w);
  }

 private:
  // ---- the Laplacian of the potential (laplacian_sum) -----------------------------------------
  template <class Term>
  static constexpr bool pair_has_second_derivative =
      requires(const Term& t, const Chart& c, Scalar d) {
        { t.second_derivative(c, d, d, d) } -> std::convertible_to<Scalar>;
      };
  template <class Term>
  Scalar term_laplacian(const Term& term, const StateType& s, Workspace& w, int index) const {
    if (inactive(term)) return Scalar(0);
    if constexpr (ChartTerm<Term, Chart>) {
      static_cast<void>(index);
      if constexpr (requires(const Point& q) {
                      { term.laplacian(chart_, q, Scalar(1)) } -> std::convertible_to<Scalar>;
                    }) {
        SESI_CHECK(!s.framed() && !s.clustered, "chart-coordinate terms need the bodies in the chart itself");
        w.rows.assign(static_cast<std::size_t>(bodies()), Scalar(0));
        for_bodies(w, [&](int b, typename Workspace::Scratch& sc) {
          sc.q = s.q.col(b);
          w.rows[static_cast<std::size_t>(b)] = term.laplacian(chart_, sc.q, mass(b));
        });
        return sum_rows(w.rows);
      } else {
        return std::numeric_limits<Scalar>::quiet_NaN();
      }
    } else if constexpr (PairTerm<Term, Chart>) {
      static_cast<void>(s);
      if constexpr (!pair_has_second_derivative<Term> ||
                    !(HasPairGeometry<Chart> || requires { chart_.curvature(); })) {
        static_cast<void>(index);
        return std::numeric_limits<Scalar>::quiet_NaN();
      } else {
        if constexpr (long_range<Term>) {
          if (whole_run()) return whole_run_laplacian(term, w);
        }
        // Each body sums Delta_i W(d_ij) over all its partners j (both ends of a pair count).
        const NeighbourLists* lists = by_rows() ? lists_of(term, w, index) : nullptr;
        const Scalar reach2 = reach2_of(term);
        w.rows.assign(static_cast<std::size_t>(bodies()), Scalar(0));
        for_bodies(w, [&](int i, typename Workspace::Scratch& sc) {
          sc.x = w.X.col(i);
          Scalar row(0);
          for_partners(lists, i, /*upper=*/false,
                       [&](int j, int k) { row += pair_laplacian(term, sc, w, i, j, k, reach2); });
          w.rows[static_cast<std::size_t>(i)] = row;
        });
        return sum_rows(w.rows);
      }
    } else {
      static_cast<void>(s);
      static_cast<void>(index);
      if constexpr (requires(const typename Chart::Ambient& x) {
                      { term.laplacian(chart_, x, Scalar(1)) } -> std::convertible_to<Scalar>;
                    }) {
        // As term_energy: in a cluster frame the term's centre moves into it, or a term without
        // one sees world points C x (the Laplacian is invariant under the isometry C).
        w.rows.assign(static_cast<std::size_t>(bodies()), Scalar(0));
        if (w.clustered) {
          if constexpr (has_movable_center<Term>) {
            const Term local = localized(term, w);
            for_bodies(w, [&](int b, typename Workspace::Scratch& sc) {
              sc.x = w.X.col(b);
              w.rows[static_cast<std::size_t>(b)] = local.laplacian(chart_, sc.x, mass(b));
            });
          } else {
            for_bodies(w, [&](int b, typename Workspace::Scratch& sc) {
              sc.x.noalias() = w.cluster * w.X.col(b);
              w.rows[static_cast<std::size_t>(b)] = term.laplacian(chart_, sc.x, mass(b));
            });
          }
        } else {
          for_bodies(w, [&](int b, typename Workspace::Scratch& sc) {
            sc.x = w.X.col(b);
            w.rows[static_cast<std::size_t>(b)] = term.laplacian(chart_, sc.x, mass(b));
          });
        }
        return sum_rows(w.rows);
      } else {
        return std::numeric_limits<Scalar>::quiet_NaN();
      }
    }
  }
  /// Delta_i W(d_ij), sc.x holding point i: W'' + (n - 1) ctn W' of the geodesic distance
  /// (special::radial_laplacian), or its chord form (special::chord_laplacian).
  template <class Term>
  Scalar pair_laplacian(const Term& term, typename Workspace::Scratch& sc, const Workspace& w, int i, int j,
                        int k, Scalar reach2) const {
    sc.y = w.X.col(j);
    to_image(sc, k);
    return pair_laplacian_of(term, sc, mass(i), mass(j), reach2);
  }
  /// The same of the points sc.x, sc.y (of masses mi, mj).
  template <class Term>
  Scalar pair_laplacian_of(const Term& term, typename Workspace::Scratch& sc, Scalar mi, Scalar mj,
                           Scalar reach2) const {
    const int n = dim();
    if constexpr (HasPairGeometry<Chart>) {
      const PairGeometry<Scalar> g = chart_.pair_geometry(sc.x, sc.y);
      if (g.chord2 >= reach2) return Scalar(0);  // (a NaN chord goes on, and stays NaN)
      if constexpr (is_chord_term<Term>) {
        const Scalar c = g.chord();
        return special::chord_laplacian(chart_.curvature(), n, c, term.derivative(chart_, c, mi, mj),
                                        term.second_derivative(chart_, c, mi, mj));
      } else if constexpr (AlgebraicPairTerm<Term, Chart> &&
                           requires { term.second_derivative(chart_, g, mi, mj); }) {
        return special::radial_laplacian(n, g.sn, g.cs(), term.derivative(chart_, g, mi, mj),
                                         term.second_derivative(chart_, g, mi, mj));
      } else {
        const Scalar d = chart_.distance_of(g);
        return special::radial_laplacian(n, g.sn, g.cs(), term.derivative(chart_, d, mi, mj),
                                         term.second_derivative(chart_, d, mi, mj));
      }
    } else {
      static_cast<void>(reach2);
      const Scalar kappa = chart_.curvature();
      if constexpr (is_chord_term<Term>) {
        const Scalar c = chord(sc);
        return special::chord_laplacian(kappa, n, c, term.derivative(chart_, c, mi, mj),
                                        term.second_derivative(chart_, c, mi, mj));
      } else {
        const Scalar d = chart_.distance(sc.x, sc.y);
        return special::radial_laplacian(n, special::sn(kappa, d), special::cs(kappa, d),
                                         term.derivative(chart_, d, mi, mj), term.second_derivative(chart_, d, mi, mj));
      }
    }
  }

  /// Before the per-body gradients: the embedding points and their ambient gradients (terms on
  /// embedding points), w's trig caches holding the trig of s.q.
  void prepare_gradients(const StateType& s, Workspace& w) const {
    if constexpr (has_chart_terms) {
      SESI_CHECK(!s.framed() && !s.clustered,
                 "chart-coordinate terms (ChartTerm) see the coordinates as stepped: bodies with frames have "
                 "other charts' coordinates");
    }
    if constexpr (has_embedded_terms) {
      embed_cached(s, w);
      ambient_gradient(w);
    } else {
      static_cast<void>(s);
      static_cast<void>(w);
    }
  }
  /// sc.p = dV/dq of body b: the embedding terms' pulled back, plus the chart terms'.
  void body_gradient(const StateType& s, Workspace& w, int b, typename Workspace::Scratch& sc) const {
    if constexpr (has_embedded_terms) {
      pull_back(s, w, b, sc);
    } else {
      sc.p.setZero();
    }
    if constexpr (has_chart_terms) {
      sc.q = s.q.col(b);
      std::apply([&](const auto&... term) { (add_chart_gradient(term, b, sc), ...); }, terms_);
    }
  }
  template <class Term>
  void add_chart_gradient(const Term& term, int b, typename Workspace::Scratch& sc) const {
    if constexpr (ChartTerm<Term, Chart>) {
      if (inactive(term)) return;
      sc.gq.setZero();
      term.gradient(chart_, sc.q, mass(b), sc.gq);
      sc.p += sc.gq;
    }
  }
  /// A term on embedding points adds its ambient gradient to w.G; a chart term adds nothing here
  /// (body_gradient adds its dV/dq).
  template <class Term>
  void add_embedded_gradient(const Term& term, Workspace& w, int index) const {
    if constexpr (!ChartTerm<Term, Chart>) add_term_gradient(term, w, index);
  }
  /// A term's energy: on chart coordinates from s.q, else from w's embedding points.
  template <class Term>
  Scalar any_term_energy(const Term& term, const StateType& s, Workspace& w, int index) const {
    if constexpr (ChartTerm<Term, Chart>) {
      static_cast<void>(index);
      if (inactive(term)) return Scalar(0);
      SESI_CHECK(!s.framed() && !s.clustered, "chart-coordinate terms need the bodies in the chart itself");
      w.rows.assign(static_cast<std::size_t>(bodies()), Scalar(0));
      for_bodies(w, [&](int b, typename Workspace::Scratch& sc) {
        sc.q = s.q.col(b);
        w.rows[static_cast<std::size_t>(b)] = term.value(chart_, sc.q, mass(b));
      });
      return sum_rows(w.rows);
    } else {
      return term_energy(term, w, index);
    }
  }

  /// w.X from the caches (or from q for charts without them): the cluster-local points
  /// F_b embed(q_b) (world = C F_b embed(q_b) with C = s.cluster when s.clustered).
  void embed_cached(const StateType& s, Workspace& w) const {
    w.clustered = s.clustered;
    if (s.clustered) w.cluster = s.cluster;
    for_bodies(w, [&](int b, typename Workspace::Scratch& sc) {
      if constexpr (HasTrigCache<Chart>) {
        chart_.embed(w.trig[static_cast<std::size_t>(b)], sc.x);
      } else {
        sc.q = s.q.col(b);
        chart_.embed(sc.q, sc.x);
      }
      if (s.framed()) {
        w.X.col(b).noalias() = s.frames[static_cast<std::size_t>(b)] * sc.x;  // world = F local
      } else {
        w.X.col(b) = sc.x;
      }
    });
  }
  /// sc.p = J(q_b)^T F_b^T w.G.col(b) (the chain rule through the body's frame, if any).
  void pull_back(const StateType& s, Workspace& w, int b, typename Workspace::Scratch& sc) const {
    if (s.framed()) {
      sc.g.noalias() = s.frames[static_cast<std::size_t>(b)].transpose() * w.G.col(b);
    } else {
      sc.g = w.G.col(b);
    }
    if constexpr (HasTrigCache<Chart>) {
      chart_.pullback(w.trig[static_cast<std::size_t>(b)], sc.g, sc.p);
    } else {
      sc.q = s.q.col(b);
      chart_.pullback(sc.q, sc.g, sc.p);
    }
  }

  // ---- patch_gradient's parts ----------------------------------------------------------------

  /// Whether every active term's gradient at a body depends only on that body and its partners
  /// in a short-range term's Verlet lists (patch_gradient's condition). An external term with a
  /// centre in a cluster frame is left to a fresh evaluation (it would be moved for every row).
  bool rows_only(const Workspace& w) const {
    bool ok = by_rows() && pair_search_ == PairSearch::automatic;
    std::apply([&](const auto&... term) { ((ok = ok && (inactive(term) || row_local(term, w))), ...); }, terms_);
    return ok;
  }
  template <class Term>
  bool row_local(const Term& term, const Workspace& w) const {
    if constexpr (PairTerm<Term, Chart>) {
      static_cast<void>(term);
      static_cast<void>(w);
      return ShortRangeTerm<Term, Chart> && HasChordMetric<Chart> && HasPairGeometry<Chart>;
    } else if constexpr (has_movable_center<Term>) {
      return !(w.clustered && has_centres_of(term));
    } else {
      static_cast<void>(term);
      static_cast<void>(w);
      return true;  // the body alone
    }
  }
  /// Marks body b (w.marks) and collects it in w.affected, once.
  static void mark(Workspace& w, int b) {
    char& m = w.marks[static_cast<std::size_t>(b)];
    if (m) return;
    m = 1;
    w.affected.push_back(b);
  }
  /// Marks (w.marks) every partner of a changed body in a short-range term's Verlet lists,
  /// brought up to date at w.X, and keeps them in lists[index].
  template <class Term>
  void mark_partners(const Term& term, Workspace& w, const std::vector<int>& changed, std::span<const int> moved,
                     int index, std::array<const NeighbourLists*, sizeof...(Terms)>& lists) const {
    if constexpr (PairTerm<Term, Chart> && ShortRangeTerm<Term, Chart> && HasChordMetric<Chart> &&
                  HasPairGeometry<Chart>) {
      if (inactive(term)) return;
      const NeighbourLists* list = lists_after_moves(term, w, index, moved);
      lists[static_cast<std::size_t>(index)] = list;
      for (const int b : changed) {
        for_partners(list, b, /*upper=*/false, [&](int j, int) { mark(w, j); });
      }
    } else {
      static_cast<void>(term);
      static_cast<void>(w);
      static_cast<void>(changed);
      static_cast<void>(moved);
      static_cast<void>(index);
      static_cast<void>(lists);
    }
  }
  /// Row i of one term's ambient gradient into w.G.col(i), as add_term_gradient adds it (lists:
  /// a short-range term's, from mark_partners).
  template <class Term>
  void add_row_of(const Term& term, Workspace& w, int i, const NeighbourLists* lists,
                  typename Workspace::Scratch& sc) const {
    if (inactive(term)) return;
    if constexpr (ChartTerm<Term, Chart>) {
      static_cast<void>(lists);  // (body_gradient adds it)
    } else if constexpr (PairTerm<Term, Chart>) {
      if constexpr (ShortRangeTerm<Term, Chart>) add_row_gradient(term, w, lists, reach2_of(term), i, sc);
    } else {
      static_cast<void>(lists);
      add_external_gradient(term, w, i, sc, w.clustered);  // (no centre here: rows_only)
    }
  }

  // ---- pair sums by rows (bodies >= rows_from) ----------------------------------------------

  template <class Term>
  void check_cutoff([[maybe_unused]] const Term& term) const {
    if constexpr (ShortRangeTerm<Term, Chart>) {
      SESI_CHECK(inactive(term) || term.range(chart_) <= chart_.topology().max_cutoff(),
                 "a pair term's range must not exceed the topology's max_cutoff()");
    }
  }

  /// The squared chord beyond which a term contributes nothing: a short-range term's range as a
  /// chord (monotone in the distance), else infinity.
  template <class Term>
  Scalar reach2_of(const Term& term) const {
    if constexpr (ShortRangeTerm<Term, Chart> && HasPairGeometry<Chart>) {
      const Scalar c = chart_.chord_of_distance(term.range(chart_));
      return c * c;
    } else {
      return std::numeric_limits<Scalar>::infinity();
    }
  }
  /// The Verlet list of a short-range term at w.X (term: its position in the system), or null
  /// for all pairs.
  template <class Term>
  const NeighbourLists* lists_of(const Term& term, Workspace& w, int index) const {
    if constexpr (ShortRangeTerm<Term, Chart> && HasChordMetric<Chart> && HasPairGeometry<Chart>) {
      if (pair_search_ == PairSearch::automatic) {
        std::vector<VerletList<Chart>>& store = w.lists();
        if (static_cast<int>(store.size()) <= index) store.resize(static_cast<std::size_t>(index) + 1);
        VerletList<Chart>& list = store[static_cast<std::size_t>(index)];
        list.skin_fraction = neighbour_skin_;
        return &list.update(chart_, w.X, term.range(chart_));
      }
    }
    static_cast<void>(term);
    static_cast<void>(index);
    return nullptr;
  }
  /// lists_of where w.X differs from the points of the term's last list update in the bodies
  /// `moved` only (VerletList::update_moved: only those are checked).
  template <class Term>
  const NeighbourLists* lists_after_moves(const Term& term, Workspace& w, int index, std::span<const int> moved) const {
    if constexpr (ShortRangeTerm<Term, Chart> && HasChordMetric<Chart> && HasPairGeometry<Chart>) {
      std::vector<VerletList<Chart>>& store = w.lists();
      if (pair_search_ == PairSearch::automatic && static_cast<int>(store.size()) > index) {
        VerletList<Chart>& list = store[static_cast<std::size_t>(index)];
        list.skin_fraction = neighbour_skin_;
        return &list.update_moved(chart_, w.X, term.range(chart_), moved);
      }
    }
    static_cast<void>(moved);
    return lists_of(term, w, index);
  }
  /// f(j, k) for the partners j of body i in ascending order: its list, or every other body;
  /// with upper, only j > i. k: the image of j the list holds (a compact surface's lists), else
  /// -1 (no image, or the minimum image to be found: to_image).
  template <class F>
  void for_partners(const NeighbourLists* lists, int i, bool upper, F&& f) const {
    if (lists) {
      const int* first = lists->index.data() + lists->begin(i);
      const int* last = lists->index.data() + lists->end(i);
      if (upper) first = std::upper_bound(first, last, i);
      if constexpr (on_quotient) {
        if (!lists->image.empty()) {
          const int* k = lists->image.data() + (first - lists->index.data());
          for (const int* j = first; j != last; ++j, ++k) f(*j, *k);
          return;
        }
      }
      for (const int* j = first; j != last; ++j) f(*j, -1);
    } else {
      for (int j = upper ? i + 1 : 0; j < bodies(); ++j) {
        if (j != i) f(j, -1);
      }
    }
  }
  /// On a quotient, sc.y (a point of body j) <- the image of it that pairs with sc.x: image k of
  /// a surface's list, or else the minimum image (the box's nearest image on the fly; the
  /// surface's nearest among its images()). Elsewhere nothing.
  void to_image(typename Workspace::Scratch& sc, int k) const {
    if constexpr (on_quotient) {
      if constexpr (detail::GhostImages<Chart>) {
        if (k >= 0) {
          chart_.topology().apply(k, sc.y);
          return;
        }
      }
      static_cast<void>(k);
      if constexpr (ambient_dimension != Eigen::Dynamic) {
        // In a local vector, kept in registers and stored whole: written in place component by
        // component, sc.y was then read back whole, a store-forwarding stall that made a box's
        // pair 2.2 times as slow (an E^2 box of 10^4 bodies, one gradient: 3.6 ms against 1.6 ms).
        AmbientVectorOf y = sc.y;
        chart_.topology().nearest_image(sc.x, y);
        sc.y = y;
      } else {
        chart_.topology().nearest_image(sc.x, sc.y);
      }
    } else {
      static_cast<void>(sc);
      static_cast<void>(k);
    }
  }
  /// W of the pair (i, j), sc.x holding point i (on a quotient, of j's image k, or nearest).
  template <class Term>
  Scalar pair_value(const Term& term, typename Workspace::Scratch& sc, const Workspace& w, int i, int j, int k,
                    Scalar reach2) const {
    sc.y = w.X.col(j);
    to_image(sc, k);
    return pair_value_of(term, sc, mass(i), mass(j), reach2);
  }
  /// W of the pair of points sc.x, sc.y (of masses mi, mj).
  template <class Term>
  Scalar pair_value_of(const Term& term, typename Workspace::Scratch& sc, Scalar mi, Scalar mj, Scalar reach2) const {
    if constexpr (HasPairGeometry<Chart>) {
      const PairGeometry<Scalar> g = chart_.pair_geometry(sc.x, sc.y);
      if (g.chord2 >= reach2) return Scalar(0);  // (a NaN chord goes on, and stays NaN)
      if constexpr (is_chord_term<Term>) {
        return term.value(chart_, g.chord(), mi, mj);
      } else if constexpr (AlgebraicPairTerm<Term, Chart>) {
        return term.value(chart_, g, mi, mj);
      } else {
        return term.value(chart_, chart_.distance_of(g), mi, mj);
      }
    } else {
      static_cast<void>(reach2);
      const Scalar d = is_chord_term<Term> ? chord(sc) : chart_.distance(sc.x, sc.y);
      return term.value(chart_, d, mi, mj);
    }
  }
  /// gi += dW(i, j)/dx_i and, with Both, gj += dW(i, j)/dx_j; sc.x, sc.y holding points i, j.
  template <bool Both, class Term, class GI, class GJ>
  void add_pair_gradient(const Term& term, typename Workspace::Scratch& sc, int i, int j, Scalar reach2,
                         GI&& gi, GJ&& gj) const {
    add_pair_gradient_of<Both>(term, sc, mass(i), mass(j), reach2, std::forward<GI>(gi), std::forward<GJ>(gj));
  }
  /// The same for points of masses mi, mj.
  template <bool Both, class Term, class GI, class GJ>
  void add_pair_gradient_of(const Term& term, typename Workspace::Scratch& sc, Scalar mi, Scalar mj, Scalar reach2,
                            GI&& gi, GJ&& gj) const {
    if constexpr (HasPairGeometry<Chart>) {
      const PairGeometry<Scalar> g = chart_.pair_geometry(sc.x, sc.y);
      if (g.chord2 >= reach2) return;
      Scalar dw;
      sc.g = sc.x - sc.y;
      if constexpr (is_chord_term<Term>) {
        const Scalar c = g.chord();
        dw = term.derivative(chart_, c, mi, mj);  // d chord / dx = G (x - y) / chord
        if (dw == Scalar(0)) return;
        dw /= c;
        if constexpr (Both) sc.h = -sc.g;
      } else {
        // d distance / dx = G (x - y - (1 - cs) x) / sn, and the same with x, y swapped: the
        // tangent gradients of Sphere's and Hyperbolic's distance_gradient, with no
        // transcendental function. dw is dW/dd / sn.
        dw = derivative_over_sn(term, g, mi, mj);
        if (dw == Scalar(0)) return;  // beyond a cutoff
        if constexpr (Both) sc.h = -sc.g - g.one_minus_cs * sc.y;
        sc.g -= g.one_minus_cs * sc.x;
      }
      if constexpr (requires { chart_.lower(sc.g); }) {
        chart_.lower(sc.g);
        if constexpr (Both) chart_.lower(sc.h);
      }
      gi += dw * sc.g;
      if constexpr (Both) gj += dw * sc.h;
    } else {
      static_cast<void>(reach2);
      if constexpr (is_chord_term<Term>) {
        const Scalar c = chord(sc);  // leaves G (x - y) in sc.g
        const Scalar dw = term.derivative(chart_, c, mi, mj) / c;
        gi += dw * sc.g;
        if constexpr (Both) gj -= dw * sc.g;
      } else {
        const Scalar d = chart_.distance(sc.x, sc.y);
        const Scalar dw = term.derivative(chart_, d, mi, mj);
        chart_.distance_gradient(sc.x, sc.y, sc.g);
        gi += dw * sc.g;
        if constexpr (Both) {
          chart_.distance_gradient(sc.y, sc.x, sc.h);
          gj += dw * sc.h;
        }
      }
    }
  }

  /// dW/dd / sn of a pair term of the geodesic distance on its pair geometry g.
  template <class Term>
  SESI_INLINE Scalar derivative_over_sn(const Term& term, const PairGeometry<Scalar>& g, Scalar mi, Scalar mj) const {
    return derivative_over_sn_on(chart_, term, g, mi, mj);
  }
  /// The same on a given chart (pair_block's local copy).
  template <class Term>
  SESI_INLINE static Scalar derivative_over_sn_on(const Chart& chart, const Term& term, const PairGeometry<Scalar>& g,
                                                  Scalar mi, Scalar mj) {
    if constexpr (requires { term.derivative_over_sn(chart, g, mi, mj); }) {
      return term.derivative_over_sn(chart, g, mi, mj);
    } else if constexpr (AlgebraicPairTerm<Term, Chart>) {
      return term.derivative(chart, g, mi, mj) / g.sn;
    } else {
      return term.derivative(chart, chart.distance_of(g), mi, mj) / g.sn;
    }
  }
  /// The rows of the many-body step: a term of the geodesic distance through a Verlet list, on
  /// a fixed-size space with pair_geometry off a quotient. The same arithmetic as
  /// add_pair_gradient<false>, in local vectors the compiler keeps in registers (through the
  /// scratch's members each partner was stored and read back).
  template <class Term>
  static constexpr bool fast_rows = !on_quotient && ambient_dimension != Eigen::Dynamic && HasPairGeometry<Chart> &&
                                    !is_chord_term<Term> && PairTerm<Term, Chart>;
  template <class Term>
  AmbientVectorOf fast_row(const Term& term, const Workspace& w, const NeighbourLists& lists, Scalar reach2,
                           int i) const {
    const AmbientVectorOf x = w.X.col(i);
    AmbientVectorOf acc = AmbientVectorOf::Zero();
    const Scalar mi = mass(i);
    const int* last = lists.index.data() + lists.end(i);
    for (const int* j = lists.index.data() + lists.begin(i); j != last; ++j) {
      const AmbientVectorOf y = w.X.col(*j);
      const PairGeometry<Scalar> g = chart_.pair_geometry(x, y);
      if (g.chord2 >= reach2) continue;  // (a NaN chord goes on, and stays NaN)
      const Scalar dw = derivative_over_sn(term, g, mi, mass(*j));
      if (dw == Scalar(0)) continue;  // beyond a cutoff
      AmbientVectorOf u = x - y;
      u -= g.one_minus_cs * x;
      if constexpr (requires { chart_.lower(u); }) chart_.lower(u);
      acc += dw * u;
    }
    return acc;
  }

  /// Room for m entries and a quarter more, so that a list rebuilt with a few more pairs does not
  /// make a step allocate.
  template <class V>
  static void reserve_with_slack(V& v, std::size_t m) {
    if (v.capacity() < m) v.reserve(m + m / 4);
  }
  /// The many-body gradient through Verlet lists, each pair's costly part once (Newton's third
  /// law, as LAMMPS' half lists) with the rows' sums as add_row_gradient forms them, bit for bit:
  /// first, on threads by blocks of pairs, every pair i < j of the lists gets dw = dW/dd / sn and
  /// 1 - cs (symmetric in i and j to the bit: |x - y| = |y - x|, |x + y| = |y + x|, and the term
  /// is a function of the pair), in the vector loops of pair_block; then each row i sums
  /// dw ((x_i - x_j) - (1 - cs) x_i) over its partners in ascending order, on threads by rows.
  /// Both passes run in the lists' visit order over a copy of the points in that order (as
  /// LAMMPS sorts its atoms by bin): a row's partners are then near it in memory, where in the
  /// bodies' own order (random, say) each partner and pair was a cache miss. The order changes
  /// where memory is read, not what is summed in which order: the same bits.
  template <class Term>
  void add_gradient_by_pairs(const Term& term, Workspace& w, const NeighbourLists& lists, long builds,
                             Scalar reach2) const {
    if constexpr (requires { term.vector_kernel(); }) {
      // A term of the same bits that the vector loop inlines whole (ShortPairTerms' one term).
      if (const auto kernel = term.vector_kernel()) return add_gradient_by_pairs(*kernel, w, lists, builds, reach2);
    }
    if (w.pair_lists != &lists || w.pair_builds != builds) index_pairs(w, lists);
    w.pair_lists = &lists;
    w.pair_builds = builds;
    const int n = lists.bodies();
    if (w.visit_own) {
      w.points_in_order = &w.X;
      w.masses_in_order = masses_.data();
    } else {
      if (w.visit_X.cols() != n || w.visit_X.rows() != w.X.rows()) w.visit_X.resize(w.X.rows(), n);
      w.visit_mass.resize(static_cast<std::size_t>(n));
      parallel::for_chunks(n, parallel::chunks_for(n), [&](int begin, int end, int) {
        for (int s = begin; s < end; ++s) {
          const int i = w.visit[static_cast<std::size_t>(s)];
          w.visit_X.col(s) = w.X.col(i);
          w.visit_mass[static_cast<std::size_t>(s)] = mass(i);
        }
      });
      w.points_in_order = &w.visit_X;
      w.masses_in_order = w.visit_mass.data();
    }
    const int pairs = static_cast<int>(w.pair_first.size());
    w.pair_value.resize((w.visit_own ? 2 : 1) * static_cast<std::size_t>(pairs));
    // Chunks of whole blocks: a pair's bits do not depend on its block, nor on the thread.
    const int blocks = (pairs + pair_block_size - 1) / pair_block_size;
    const simd::Level level = simd::level();
    parallel::for_chunks(blocks, std::max(1, std::min(blocks, parallel::chunks_for(bodies()))),
                         [&](int begin, int end, int) {
                           const int k0 = begin * pair_block_size, k1 = std::min(pairs, end * pair_block_size);
                           pair_blocks(level, term, w, reach2, k0, k1);
                         });
    parallel::for_chunks(n, parallel::chunks_for(n), [&](int begin, int end, int) {
      if (w.visit_own) {
        for (int s = begin; s < end; ++s) sum_of_row<true>(w, s, end);
      } else {
        for (int s = begin; s < end; ++s) sum_of_row<false>(w, s, end);
      }
    });
  }
  /// The lists' layout in visit order (Workspace::visit and the rest, add_gradient_by_pairs),
  /// after a rebuild: the pairs i < j row by row, and each entry's partner position and pair
  /// (entry (i, j) and its mirror (j, i) name the same pair).
  void index_pairs(Workspace& w, const NeighbourLists& lists) const {
    const int n = lists.bodies();
    const std::size_t un = static_cast<std::size_t>(n);
    w.visit.resize(un);
    w.visit_pos.resize(un);
    w.visit_own = lists.visit_order.size() != un || own_order_is_local(w, lists);
    if (w.visit_own) {  // (lists without an order, or bodies already in a local order: their own)
      parallel::for_each(n, [&](int s) { w.visit[static_cast<std::size_t>(s)] = s; });
    } else {
      std::copy(lists.visit_order.begin(), lists.visit_order.end(), w.visit.begin());
    }
    // Row i's pairs are its entries j > i, the last ones of its sorted row.
    w.pair_base.resize(un + 1);
    w.visit_row.resize(un + 1);
    parallel::for_chunks(n, parallel::chunks_for(n), [&](int begin, int end, int) {
      for (int s = begin; s < end; ++s) {
        const int i = w.visit[static_cast<std::size_t>(s)];
        w.visit_pos[static_cast<std::size_t>(i)] = s;
        const int* first = lists.index.data() + lists.begin(i);
        const int* last = lists.index.data() + lists.end(i);
        w.pair_base[static_cast<std::size_t>(s) + 1] = static_cast<int>(last - std::upper_bound(first, last, i));
        w.visit_row[static_cast<std::size_t>(s) + 1] = static_cast<int>(last - first);
      }
    });
    w.pair_base[0] = 0;
    w.visit_row[0] = 0;
    parallel::prefix_sums(w.pair_base.data() + 1, n, w.pair_scan);  // on threads: passes over every body
    parallel::prefix_sums(w.visit_row.data() + 1, n, w.pair_scan);
    const std::size_t pairs = static_cast<std::size_t>(w.pair_base[un]);
    const std::size_t entries = lists.index.size();
    reserve_with_slack(w.pair_first, pairs);
    reserve_with_slack(w.pair_second, pairs);
    reserve_with_slack(w.entry_pos, entries);
    reserve_with_slack(w.entry_pair, entries);
    reserve_with_slack(w.pair_value, (w.visit_own ? 2 : 1) * pairs);
    w.pair_first.resize(pairs);
    w.pair_second.resize(pairs);
    w.entry_pos.resize(entries);
    w.entry_pair.resize(entries);
    // Row i's upper entries start at its end less its pair count; entry (i, j), j < i, is row
    // j's entry for i, found by bisection in row j's upper entries.
    const auto upper_count = [&](int s) {
      return w.pair_base[static_cast<std::size_t>(s) + 1] - w.pair_base[static_cast<std::size_t>(s)];
    };
    parallel::for_chunks(n, parallel::chunks_for(n), [&](int begin, int end, int) {
      for (int s = begin; s < end; ++s) {
        const int i = w.visit[static_cast<std::size_t>(s)];
        const int up = lists.end(i) - upper_count(s);
        int out = w.visit_row[static_cast<std::size_t>(s)];
        for (int e = lists.begin(i); e < lists.end(i); ++e, ++out) {
          const int j = lists.index[static_cast<std::size_t>(e)];
          const int t = w.visit_pos[static_cast<std::size_t>(j)];
          int k;
          if (e >= up) {
            k = w.pair_base[static_cast<std::size_t>(s)] + (e - up);
            w.pair_first[static_cast<std::size_t>(k)] = s;
            w.pair_second[static_cast<std::size_t>(k)] = t;
          } else {
            const int* last = lists.index.data() + lists.end(j);
            const int* first = last - upper_count(t);
            const int* at = std::lower_bound(first, last, i);
            k = w.pair_base[static_cast<std::size_t>(t)] + static_cast<int>(at - first);
          }
          w.entry_pos[static_cast<std::size_t>(out)] = t;
          w.entry_pair[static_cast<std::size_t>(out)] = k;
        }
      }
    });
  }
  /// Whether the bodies' own order keeps partners as near in memory as the lists' visit order
  /// (bodies from a lattice or a spiral, say): then the pair sums read the points where they are
  /// and skip the copy in visit order, which costs more than it saves there (S^2's spiral of 10^5
  /// bodies: the force phase 30 % slower with it, `sesi run --profile`). Counted: list entries
  /// whose partner lies more than `far` bodies away, in either order (at a rebuild only; the
  /// choice changes where memory is read, never a result).
  bool own_order_is_local(Workspace& w, const NeighbourLists& lists) const {
    constexpr int far = 2048;
    const int n = lists.bodies();
    parallel::for_each(n, [&](int s) { w.visit_pos[static_cast<std::size_t>(lists.visit_order[static_cast<std::size_t>(s)])] = s; });
    const int chunks = parallel::chunks_for(n);
    const std::size_t uc = static_cast<std::size_t>(chunks);
    if (w.order_counts.size() < 2 * uc) w.order_counts.resize(2 * uc);
    long* own = w.order_counts.data();
    long* visit = own + chunks;
    parallel::for_chunks(n, chunks, [&](int begin, int end, int c) {
      long o = 0, v = 0;
      for (int i = begin; i < end; ++i) {
        const int si = w.visit_pos[static_cast<std::size_t>(i)];
        for (int e = lists.begin(i); e < lists.end(i); ++e) {
          const int j = lists.index[static_cast<std::size_t>(e)];
          o += std::abs(i - j) > far;
          v += std::abs(si - w.visit_pos[static_cast<std::size_t>(j)]) > far;
        }
      }
      own[c] = o;
      visit[c] = v;
    });
    long o = 0, v = 0;
    for (int c = 0; c < chunks; ++c) {
      o += own[c];
      v += visit[c];
    }
    return o <= v;
  }
  /// Pairs per block of pair_block: its arrays stay in L1 (5 x 64 doubles).
  static constexpr int pair_block_size = 64;
  /// pair_block on pairs [k0, k1) at the vector width of level (the same bits at every level).
  template <class Term>
  void pair_blocks(simd::Level level, const Term& term, Workspace& w, Scalar reach2, int k0, int k1) const {
#if SESI_SIMD_DISPATCH
    if (level == simd::Level::avx512) return pair_blocks_avx512(term, w, reach2, k0, k1);
    if (level == simd::Level::avx2) return pair_blocks_avx2(term, w, reach2, k0, k1);
#else
    static_cast<void>(level);
#endif
    pair_block<false>(term, w, reach2, k0, k1);
  }
#if SESI_SIMD_DISPATCH
  template <class Term>
  SESI_TARGET_AVX512 void pair_blocks_avx512(const Term& term, Workspace& w, Scalar reach2, int k0, int k1) const {
    pair_block<true>(term, w, reach2, k0, k1);
  }
  template <class Term>
  SESI_TARGET_AVX2 void pair_blocks_avx2(const Term& term, Workspace& w, Scalar reach2, int k0, int k1) const {
    pair_block<true>(term, w, reach2, k0, k1);
  }
#endif
  /// add_gradient_by_pairs' first pass on pairs [k0, k1), a block of pair_block_size at a time:
  /// each pair's geometry (a gather of two points, one square root), then dw over the block in
  /// a loop that vectorises (simd: the term's distance and derivative, two divisions, selects
  /// for its branches; measured in `sesi bench --scaling`, docs/benchmarks.md). At the base
  /// width (SSE2's two doubles) the vector loop was slower than the scalar one, so it stays
  /// scalar there.
  template <bool simd, class Term>
  SESI_INLINE void pair_block(const Term& term, Workspace& w, Scalar reach2, int k0, int k1) const {
    // Local copies: the chart's and the term's parameters read through `this` or a reference
    // are loads inside the term's branches (a cutoff), which keep GCC from if-converting the
    // loop, and so from vectorising it.
    const Chart chart = chart_;
    const auto& kernel = plain_copy(term);
    alignas(64) Scalar c2[pair_block_size], cc2[pair_block_size], sn[pair_block_size], omc[pair_block_size];
    alignas(64) Scalar mi[pair_block_size], mj[pair_block_size];
    for (int b = k0; b < k1; b += pair_block_size) {
      const int m = std::min(pair_block_size, k1 - b);
      for (int t = 0; t < m; ++t) {
        const int i = w.pair_first[static_cast<std::size_t>(b + t)], j = w.pair_second[static_cast<std::size_t>(b + t)];
        const AmbientVectorOf x = w.points_in_order->col(i), y = w.points_in_order->col(j);
        const PairGeometry<Scalar> g = chart_.pair_geometry(x, y);
        c2[t] = g.chord2;
        cc2[t] = g.cochord2;
        sn[t] = g.sn;
        omc[t] = g.one_minus_cs;
        mi[t] = w.masses_in_order[i];
        mj[t] = w.masses_in_order[j];
      }
      alignas(64) Scalar dw[pair_block_size];
      if constexpr (simd) {
        SESI_PRAGMA_SIMD
        for (int t = 0; t < m; ++t) dw[t] = block_dw(chart, kernel, c2[t], cc2[t], sn[t], omc[t], mi[t], mj[t], reach2);
      } else {
        for (int t = 0; t < m; ++t) dw[t] = block_dw(chart, kernel, c2[t], cc2[t], sn[t], omc[t], mi[t], mj[t], reach2);
      }
      if (w.visit_own) {
        Scalar* value = w.pair_value.data() + 2 * static_cast<std::size_t>(b);
        for (int t = 0; t < m; ++t) {
          value[2 * t] = dw[t];
          value[2 * t + 1] = omc[t];
        }
      } else {
        std::copy_n(dw, m, w.pair_value.data() + b);
      }
    }
  }
  /// A local copy of term where that is a copy of bytes, else term itself (pair_block).
  template <class Term>
  static decltype(auto) plain_copy(const Term& term) {
    if constexpr (std::is_trivially_copyable_v<Term>) {
      return Term(term);
    } else {
      return (term);
    }
  }
  /// One pair's dw in pair_block: 0 beyond the reach (a NaN chord goes on, and stays NaN).
  template <class Term>
  SESI_INLINE static Scalar block_dw(const Chart& chart, const Term& term, Scalar c2, Scalar cc2, Scalar sn, Scalar omc,
                                     Scalar mi, Scalar mj, Scalar reach2) {
    PairGeometry<Scalar> g;
    g.chord2 = c2;
    g.cochord2 = cc2;
    g.sn = sn;
    g.one_minus_cs = omc;
    const Scalar f = derivative_over_sn_on(chart, term, g, mi, mj);
    return c2 >= reach2 ? Scalar(0) : f;
  }
  /// add_gradient_by_pairs' second pass on the row at visit position s: the row's sum into
  /// w.G.col(i), i its body. A pair beyond the cutoff (dw = 0, its points finite) adds a zero: no
  /// branch to mispredict at the cutoff's edge, and the same bits (acc starts at +0 and a sum
  /// never turns it into -0, so adding +-0 changes nothing).
  ///
  /// The reads that miss the caches are prefetched (GCC's __builtin_prefetch, a hint that changes
  /// no value): the pair values a few entries ahead, whose pairs lie in other rows' blocks, and
  /// the gradient of the body a few rows ahead (in the bodies' own order).
  /// `kept`: 1 - cs read beside dw (the bodies' own order), else formed from x and y.
  template <bool kept>
  SESI_FLATTEN void sum_of_row(Workspace& w, int s, int rows_end) const {
    constexpr int entries_ahead = 16, rows_ahead = 4;
    if (s + rows_ahead < rows_end) {
      __builtin_prefetch(w.G.col(w.visit[static_cast<std::size_t>(s + rows_ahead)]).data(), 1);
    }
    const auto& points = *w.points_in_order;
    const AmbientVectorOf x = points.col(s);
    AmbientVectorOf acc = AmbientVectorOf::Zero();
    const int last = w.visit_row[static_cast<std::size_t>(s) + 1];
    const int ahead_end = static_cast<int>(w.entry_pair.size()) - entries_ahead;
    for (int e = w.visit_row[static_cast<std::size_t>(s)]; e < last; ++e) {
      constexpr std::size_t stride = kept ? 2 : 1;
      if (e < ahead_end) {
        __builtin_prefetch(w.pair_value.data() + stride * static_cast<std::size_t>(w.entry_pair[static_cast<std::size_t>(e + entries_ahead)]));
      }
      const std::size_t k = stride * static_cast<std::size_t>(w.entry_pair[static_cast<std::size_t>(e)]);
      const Scalar dw = w.pair_value[k];
      const AmbientVectorOf y = points.col(w.entry_pos[static_cast<std::size_t>(e)]);
      // (1 - cs of (x, y): the first pass's of (y, x) or (x, y), the same bits, as every chart's
      // pair_geometry forms it from the squares of x - y.)
      Scalar omc;
      if constexpr (kept) {
        omc = w.pair_value[k + 1];
      } else {
        omc = chart_.pair_geometry(x, y).one_minus_cs;
      }
      AmbientVectorOf u = x - y;
      u -= omc * x;
      if constexpr (requires { chart_.lower(u); }) chart_.lower(u);
      acc += dw * u;
    }
    w.G.col(w.visit[static_cast<std::size_t>(s)]) += acc;
  }

  // ---- long-range pair sums by tiles (bodies >= rows_from) ------------------------------------
  // The pair triangle i < j is cut into square tiles of a block size fixed by the body count
  // alone; each tile sums its pairs once (both ends, Newton's third law) into its own buffers,
  // and each body then adds its tiles' shares in tile order. Tiles may run on any thread in any
  // order: no result depends on the thread count.

  struct Tiling {
    int n, block, blocks;
    int tiles() const { return blocks * (blocks + 1) / 2; }
    /// The tile of blocks I <= J.
    int tile(int I, int J) const { return I * blocks - I * (I - 1) / 2 + (J - I); }
    int first(int I) const { return I * block; }
    int last(int I) const { return std::min(n, (I + 1) * block); }
  };
  Tiling tiling() const { return tiling_of(bodies()); }
  /// The tiles of n bodies (a domain's: of the whole simulation's).
  static Tiling tiling_of(int n) {
    // At most 48 blocks (1176 tiles: enough to balance any thread count this side of a node) of
    // at least 64 bodies (a tile's pairs outweigh its bookkeeping).
    const int block = std::max(64, (n + 47) / 48);
    return Tiling{n, block, (n + block - 1) / block};
  }
  /// For each tile (I, J), f(t, I, J) on threads.
  template <class F>
  void for_tiles(const Tiling& tl, F&& f) const {
    std::vector<std::pair<int, int>> blocks;  // tile t -> (I, J)
    blocks.reserve(static_cast<std::size_t>(tl.tiles()));
    for (int I = 0; I < tl.blocks; ++I) {
      for (int J = I; J < tl.blocks; ++J) blocks.emplace_back(I, J);
    }
    parallel::for_chunks(tl.tiles(), std::min(tl.tiles(), 4 * parallel::threads()), [&](int begin, int end, int c) {
      for (int t = begin; t < end; ++t) f(t, blocks[static_cast<std::size_t>(t)].first, blocks[static_cast<std::size_t>(t)].second, c);
    });
  }
  template <class Term>
  void add_tiled_gradient(const Term& term, Workspace& w) const {
    const Tiling tl = tiling();
    const int a = ambient_dim();
    const std::size_t per_tile = static_cast<std::size_t>(2 * tl.block * a);
    w.tile_gradients.assign(per_tile * static_cast<std::size_t>(tl.tiles()), Scalar(0));
    w.ensure_scratch(std::min(tl.tiles(), 4 * parallel::threads()), dim(), a);
    const Scalar reach2 = reach2_of(term);
    for_tiles(tl, [&](int t, int I, int J, int c) {
      typename Workspace::Scratch& sc = w.scratch[static_cast<std::size_t>(c)];
      Scalar* buf = w.tile_gradients.data() + per_tile * static_cast<std::size_t>(t);
      for (int i = tl.first(I); i < tl.last(I); ++i) {
        sc.x = w.X.col(i);
        Eigen::Map<AmbientVectorOf> gi(buf + static_cast<std::size_t>((i - tl.first(I)) * a), a);
        for (int j = I == J ? i + 1 : tl.first(J); j < tl.last(J); ++j) {
          sc.y = w.X.col(j);
          Eigen::Map<AmbientVectorOf> gj(buf + static_cast<std::size_t>((tl.block + j - tl.first(J)) * a), a);
          add_pair_gradient<true>(term, sc, i, j, reach2, gi, gj);
        }
      }
    });
    // Body i: its share of tiles (I, J) for J = 0, 1, ... in that order.
    for_bodies(w, [&](int i, typename Workspace::Scratch&) {
      const int I = i / tl.block;
      const auto share = [&](int t, int slot) {
        w.G.col(i) += Eigen::Map<const AmbientVectorOf>(
            w.tile_gradients.data() + per_tile * static_cast<std::size_t>(t) + static_cast<std::size_t>(slot * a), a);
      };
      for (int J = 0; J < tl.blocks; ++J) {
        // In tile (I, J) body i is a first index when I <= J, a second one when I >= J (both on
        // the diagonal).
        if (I <= J) share(tl.tile(I, J), i - tl.first(I));
        if (I >= J) share(tl.tile(J, I), tl.block + i - tl.first(I));
      }
    });
  }
  // ---- a domain's pair terms without a cutoff (set_whole_run) ---------------------------------
  // Each own body's row against every body of the whole simulation, whose points every process
  // gathers first (w.whole): no Newton's third law across processes, each pair's derivative is
  // computed by the owners of both its bodies. The rows are one process's to the bit.

  template <class Term>
  static constexpr bool long_range = PairTerm<Term, Chart> && !ShortRangeTerm<Term, Chart>;
  bool whole_run() const { return static_cast<bool>(gather_); }
  Scalar whole_mass(int b) const { return whole_masses_[static_cast<std::size_t>(b)]; }
  /// w.whole = the whole simulation's points (w.X's own columns from every process).
  void gather_whole(Workspace& w) const {
    const int n = static_cast<int>(whole_masses_.size()), a = ambient_dim();
    if (w.whole.rows() != a || w.whole.cols() != n) w.whole.resize(a, n);
    gather_(w.X.data(), a, w.whole.data());
  }
  /// f(l, b, scratch) for each own body (l: its index here, b: in the whole simulation), on
  /// threads: a row has every body as a partner, so a few own bodies fill the threads.
  template <class F>
  void for_own(Workspace& w, F&& f) const {
    const int n = static_cast<int>(whole_own_.size());
    const int chunks = std::max(1, std::min(n, 4 * parallel::threads()));
    w.ensure_scratch(chunks, dim(), ambient_dim());
    parallel::for_chunks(n, chunks, [&](int begin, int end, int c) {
      typename Workspace::Scratch& sc = w.scratch[static_cast<std::size_t>(c)];
      for (int k = begin; k < end; ++k) {
        const int l = whole_own_[static_cast<std::size_t>(k)];
        f(l, whole_ids_[static_cast<std::size_t>(l)], sc);
      }
    });
  }
  /// Each own body b's row of a term without a cutoff into w.G, as one process adds it: on a
  /// quotient over every other body ascending (add_row_gradient); else b's shares of the tiles
  /// of the whole simulation (add_tiled_gradient): for J ascending, where b's block I <= J the
  /// share of tile (I, J), its pairs with block J (j > b on the diagonal) ascending from zero,
  /// then where I >= J the share of tile (J, I), its pairs with block J (i < b) likewise. That
  /// second end's gradient is computed as the tile computes it, the points and masses in the
  /// tile's order (first index first): no symmetry of the term is assumed.
  template <class Term>
  void add_whole_run_gradient(const Term& term, Workspace& w) const {
    gather_whole(w);
    const int n = static_cast<int>(whole_masses_.size());
    const Scalar reach2 = reach2_of(term);
    for_own(w, [&](int l, int b, typename Workspace::Scratch& sc) {
      if constexpr (on_quotient) {
        sc.x = w.whole.col(b);
        sc.acc.setZero();
        for (int j = 0; j < n; ++j) {
          if (j == b) continue;
          sc.y = w.whole.col(j);
          to_image(sc, -1);
          add_pair_gradient_of<false>(term, sc, whole_mass(b), whole_mass(j), reach2, sc.acc, sc.acc);
        }
        w.G.col(l) += sc.acc;
      } else {
        const Tiling tl = tiling_of(n);
        const int I = b / tl.block;
        // The first end's gradient of a pair where b is the second: not b's (never read).
        AmbientVectorOf unused = AmbientVectorOf::Zero(ambient_dim());
        for (int J = 0; J < tl.blocks; ++J) {
          if (I <= J) {
            sc.x = w.whole.col(b);
            sc.acc.setZero();
            for (int j = I == J ? b + 1 : tl.first(J); j < tl.last(J); ++j) {
              sc.y = w.whole.col(j);
              add_pair_gradient_of<false>(term, sc, whole_mass(b), whole_mass(j), reach2, sc.acc, sc.acc);
            }
            w.G.col(l) += sc.acc;
          }
          if (I >= J) {
            sc.y = w.whole.col(b);
            sc.acc.setZero();
            for (int i = tl.first(J); i < (I == J ? b : tl.last(J)); ++i) {
              sc.x = w.whole.col(i);
              add_pair_gradient_of<true>(term, sc, whole_mass(i), whole_mass(b), reach2, unused, sc.acc);
            }
            w.G.col(l) += sc.acc;
          }
        }
      }
    });
  }
  /// The energy of a term without a cutoff as one process sums it (term_energy's rows): own
  /// body b's row is its pairs with j > b ascending, the rows summed in the whole simulation's
  /// body order (sum_rows).
  template <class Term>
  Scalar whole_run_energy(const Term& term, Workspace& w) const {
    gather_whole(w);
    const int n = static_cast<int>(whole_masses_.size());
    const Scalar reach2 = reach2_of(term);
    w.rows.assign(static_cast<std::size_t>(bodies()), Scalar(0));
    for_own(w, [&](int l, int b, typename Workspace::Scratch& sc) {
      sc.x = w.whole.col(b);
      Scalar row(0);
      for (int j = b + 1; j < n; ++j) {
        sc.y = w.whole.col(j);
        to_image(sc, -1);
        row += pair_value_of(term, sc, whole_mass(b), whole_mass(j), reach2);
      }
      w.rows[static_cast<std::size_t>(l)] = row;
    });
    return sum_rows(w.rows);
  }
  /// The Laplacian sum of a term without a cutoff as one process sums it (term_laplacian's
  /// rows): own body b's row over every other body ascending.
  template <class Term>
  Scalar whole_run_laplacian(const Term& term, Workspace& w) const {
    gather_whole(w);
    const int n = static_cast<int>(whole_masses_.size());
    const Scalar reach2 = reach2_of(term);
    w.rows.assign(static_cast<std::size_t>(bodies()), Scalar(0));
    for_own(w, [&](int l, int b, typename Workspace::Scratch& sc) {
      sc.x = w.whole.col(b);
      Scalar row(0);
      for (int j = 0; j < n; ++j) {
        if (j == b) continue;
        sc.y = w.whole.col(j);
        to_image(sc, -1);
        row += pair_laplacian_of(term, sc, whole_mass(b), whole_mass(j), reach2);
      }
      w.rows[static_cast<std::size_t>(l)] = row;
    });
    return sum_rows(w.rows);
  }

  /// The chord of sc.x, sc.y in the ambient metric, leaving G (x - y) in sc.g (as chord(w)).
  Scalar chord(typename Workspace::Scratch& sc) const {
    using std::sqrt;
    sc.g = sc.x - sc.y;
    if constexpr (requires { chart_.lower(sc.g); }) chart_.lower(sc.g);
    const Scalar c2 = (sc.x - sc.y).dot(sc.g);
    return sqrt(c2 < Scalar(0) ? Scalar(0) : c2);
  }

  /// The chord of the pair w.x, w.y in the ambient metric G, sqrt(<u, u>) with u = x - y, leaving
  /// G u in w.gy: |x - y| on S^n and E^n; on H^n (the chart's lower(v): v -> eta v) the Minkowski
  /// chord 2R sinh(d/2R), since a Euclidean norm would not be invariant under the boosts.
  /// Round-off negatives clamp to 0 (a NaN stays NaN).
  Scalar chord(Workspace& w) const {
    using std::sqrt;
    w.gy = w.x - w.y;
    if constexpr (requires { chart_.lower(w.gy); }) chart_.lower(w.gy);
    const Scalar c2 = (w.x - w.y).dot(w.gy);
    return sqrt(c2 < Scalar(0) ? Scalar(0) : c2);
  }

  /// A term with empty() (an aggregate of run-time terms, say) is skipped while it is empty.
  template <class Term>
  static bool inactive(const Term& term) {
    if constexpr (requires { { term.empty() } -> std::convertible_to<bool>; }) {
      return term.empty();
    } else {
      return false;
    }
  }

  template <class Term>
  Scalar term_energy(const Term& term, Workspace& w, int index) const {
    Scalar v(0);
    if (inactive(term)) return v;
    if constexpr (PairTerm<Term, Chart>) {
      if (by_rows()) {
        // A term without a cutoff as any other: row i sums its pairs i < j in ascending j (so a
        // domain's rows, against the whole simulation's bodies, are one process's).
        if constexpr (long_range<Term>) {
          if (whole_run()) return whole_run_energy(term, w);
        }
        const NeighbourLists* lists = lists_of(term, w, index);
        const Scalar reach2 = reach2_of(term);
        w.rows.assign(static_cast<std::size_t>(bodies()), Scalar(0));
        for_bodies(w, [&](int i, typename Workspace::Scratch& sc) {
          sc.x = w.X.col(i);
          Scalar row(0);
          for_partners(lists, i, /*upper=*/true,
                       [&](int j, int k) { row += pair_value(term, sc, w, i, j, k, reach2); });
          w.rows[static_cast<std::size_t>(i)] = row;
        });
        return sum_rows(w.rows);
      }
      for (int i = 0; i < bodies(); ++i) {
        w.x = w.X.col(i);
        for (int j = i + 1; j < bodies(); ++j) {
          w.y = w.X.col(j);
          const Scalar d = is_chord_term<Term> ? chord(w) : chart_.distance(w.x, w.y);
          v += term.value(chart_, d, mass(i), mass(j));
        }
      }
    } else {
      static_assert(ExternalTerm<Term, Chart>, "a term must model ExternalTerm or PairTerm");
      static_cast<void>(index);
      w.rows.assign(static_cast<std::size_t>(bodies()), Scalar(0));
      if (w.clustered) {
        if constexpr (has_movable_center<Term>) {
          const Term local = localized(term, w);
          for_bodies(w, [&](int b, typename Workspace::Scratch& sc) {
            sc.x = w.X.col(b);
            w.rows[static_cast<std::size_t>(b)] = local.value(chart_, sc.x, mass(b));
          });
        } else {
          // A term without a centre is a function of world points: V(C x).
          for_bodies(w, [&](int b, typename Workspace::Scratch& sc) {
            sc.x.noalias() = w.cluster * w.X.col(b);
            w.rows[static_cast<std::size_t>(b)] = term.value(chart_, sc.x, mass(b));
          });
        }
        return sum_rows(w.rows);
      }
      for_bodies(w, [&](int b, typename Workspace::Scratch& sc) {
        sc.x = w.X.col(b);
        w.rows[static_cast<std::size_t>(b)] = term.value(chart_, sc.x, mass(b));
      });
      v = sum_rows(w.rows);
    }
    return v;
  }

  template <class Term>
  void add_term_gradient(const Term& term, Workspace& w, int index) const {
    if (inactive(term)) return;
    if constexpr (PairTerm<Term, Chart>) {
      if (by_rows()) {
        if constexpr (long_range<Term>) {
          if (whole_run()) {
            add_whole_run_gradient(term, w);
            return;
          }
        }
        if constexpr (long_range<Term> && !on_quotient) {
          add_tiled_gradient(term, w);
          return;
        }
        const NeighbourLists* lists = lists_of(term, w, index);
        const Scalar reach2 = reach2_of(term);
        if constexpr (fast_rows<Term>) {
          if (lists) {
            add_gradient_by_pairs(term, w, *lists, w.lists()[static_cast<std::size_t>(index)].builds(), reach2);
            return;
          }
        }
        for_bodies(w, [&](int i, typename Workspace::Scratch& sc) { add_row_gradient(term, w, lists, reach2, i, sc); });
        return;
      }
      for (int i = 0; i < bodies(); ++i) {
        w.x = w.X.col(i);
        for (int j = i + 1; j < bodies(); ++j) {
          w.y = w.X.col(j);
          if constexpr (is_chord_term<Term>) {
            // d chord / dx = G (x - y) / chord, and the opposite in y.
            const Scalar d = chord(w);
            w.gy *= term.derivative(chart_, d, mass(i), mass(j)) / d;
            w.G.col(i) += w.gy;
            w.G.col(j) -= w.gy;
          } else if constexpr (requires { chart_.distance_gradients(w.x, w.y, w.g, w.g); }) {
            const Scalar d = chart_.distance_gradients(w.x, w.y, w.g, w.gy);
            const Scalar dw = term.derivative(chart_, d, mass(i), mass(j));
            w.G.col(i) += dw * w.g;
            w.G.col(j) += dw * w.gy;
          } else {
            const Scalar d = chart_.distance(w.x, w.y);
            const Scalar dw = term.derivative(chart_, d, mass(i), mass(j));
            chart_.distance_gradient(w.x, w.y, w.g);
            w.G.col(i) += dw * w.g;
            chart_.distance_gradient(w.y, w.x, w.g);
            w.G.col(j) += dw * w.g;
          }
        }
      }
    } else {
      static_cast<void>(index);
      if constexpr (has_movable_center<Term>) {
        if (w.clustered) {
          const Term local = localized(term, w);
          for_bodies(w, [&](int b, typename Workspace::Scratch& sc) { add_external_gradient(local, w, b, sc, false); });
          return;
        }
      }
      for_bodies(w, [&](int b, typename Workspace::Scratch& sc) { add_external_gradient(term, w, b, sc, w.clustered); });
    }
  }
  /// w.G.col(i) += row i of a pair term's gradient by rows: dW(i, j)/dx_i summed over the
  /// partners j in ascending order (its list, or all bodies), into one accumulator first.
  template <class Term>
  void add_row_gradient(const Term& term, Workspace& w, const NeighbourLists* lists, Scalar reach2, int i,
                        typename Workspace::Scratch& sc) const {
    if constexpr (fast_rows<Term>) {
      if (lists) {
        w.G.col(i) += fast_row(term, w, *lists, reach2, i);
        return;
      }
    }
    sc.x = w.X.col(i);
    sc.acc.setZero();
    for_partners(lists, i, /*upper=*/false, [&](int j, int k) {
      sc.y = w.X.col(j);
      to_image(sc, k);
      add_pair_gradient<false>(term, sc, i, j, reach2, sc.acc, sc.acc);
    });
    w.G.col(i) += sc.acc;
  }
  /// w.G.col(b) += an external term's gradient at body b: term as given (a term already moved
  /// into the cluster frame, or no cluster frame), or with world, a term without a centre seeing
  /// the world point C x: d V(C x) / dx = C^T (dV/dx)(C x), the chain rule through the frame.
  template <class Term>
  void add_external_gradient(const Term& term, Workspace& w, int b, typename Workspace::Scratch& sc,
                             bool world) const {
    if (world) {
      sc.y.noalias() = w.cluster * w.X.col(b);
      term.gradient(chart_, sc.y, mass(b), sc.g);
      w.G.col(b).noalias() += w.cluster.transpose() * sc.g;
    } else {
      sc.x = w.X.col(b);
      term.gradient(chart_, sc.x, mass(b), sc.g);
      w.G.col(b) += sc.g;
    }
  }

  /// The term with its centre in the cluster's frame (w.cluster).
  template <class Term>
  Term localized(const Term& term, const Workspace& w) const {
    if constexpr (requires { term.in_frame(chart_, w.cluster); }) {
      return term.in_frame(chart_, w.cluster);
    } else {
      Term local = term;
      chart_.to_frame(w.cluster, term.center, local.center);
      return local;
    }
  }
  template <class Term>
  static bool has_centres_of(const Term& term) {
    if constexpr (!has_movable_center<Term>) {
      return false;
    } else if constexpr (requires { term.has_centres(); }) {
      return term.has_centres();
    } else {
      return true;
    }
  }

  Chart chart_;
  std::vector<Scalar> masses_;
  std::tuple<Terms...> terms_;
  detail::InstanceStamp instance_;
  PairSearch pair_search_ = PairSearch::automatic;
  Scalar neighbour_skin_ = Scalar(default_skin_fraction);
  RowSum row_sum_;    // a domain's sums over its own bodies (set_domain)
  Drifted drifted_;   // a domain's halo refresh
  bool domain_ = false;
  // A domain's whole simulation (set_whole_run): each body's index in it, the own bodies, its
  // masses, the gather of its points.
  std::vector<int> whole_ids_, whole_own_;
  std::vector<Scalar> whole_masses_;
  Gather gather_;
};

/// Deduction guide: System(chart, masses, terms...).
template <class Chart, class... Terms>
System(Chart, std::vector<typename Chart::Scalar>, Terms...) -> System<Chart, Terms...>;

}  // namespace sesi
