#pragma once
/// @file system.hpp
/// A Hamiltonian system: bodies (masses) on one chart, plus potential terms.
/// H = sum_b sum_i K_i(q_b, p_b; m_b) + sum of the terms on the embedding points x_b = embed(q_b).
/// Only what the system has is compiled into its step: without terms there is no kick at all,
/// and a pair loop exists only for pair terms.

#include <cmath>
#include <concepts>
#include <tuple>
#include <type_traits>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "sesi/chart.hpp"
#include "sesi/config.hpp"
#include "sesi/potentials.hpp"
#include "sesi/state.hpp"

namespace sesi {

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

template <HierarchicalChart Chart_, class... Terms>
class System {
 public:
  using Chart = Chart_;
  using Scalar = typename Chart::Scalar;
  using Point = typename Chart::Point;
  using StateType = State<Chart>;
  static constexpr int ambient_dimension = detail::ambient_dimension_of<Chart>();

  static constexpr bool has_potential = sizeof...(Terms) > 0;
  static_assert(!has_potential || EmbeddedChart<Chart>,
                "potential terms act on embedding points: the chart must model EmbeddedChart");

  using Workspace = sesi::Workspace<Chart>;

  System(Chart chart, std::vector<Scalar> masses, Terms... terms)
      : chart_(std::move(chart)), masses_(std::move(masses)), terms_(std::move(terms)...) {
    for ([[maybe_unused]] Scalar m : masses_) SESI_CHECK(m > Scalar(0), "masses must be positive");
  }

  const Chart& chart() const { return chart_; }
  const std::vector<Scalar>& masses() const { return masses_; }
  Scalar mass(int b) const { return masses_[static_cast<std::size_t>(b)]; }
  int bodies() const { return static_cast<int>(masses_.size()); }
  int dim() const { return chart_.dim(); }
  const std::tuple<Terms...>& terms() const { return terms_; }

  Workspace make_workspace() const {
    Workspace w;
    w.resize(dim(), ambient_dim(), bodies());
    return w;
  }
  int ambient_dim() const {
    if constexpr (EmbeddedChart<Chart>) {
      return chart_.ambient_dim();
    } else {
      return chart_.dim();
    }
  }

  Scalar kinetic_energy(const StateType& s) const {
    Scalar k(0);
    Point q(dim()), p(dim());
    for (int b = 0; b < bodies(); ++b) {
      q = s.q.col(b);
      p = s.p.col(b);
      k += sesi::kinetic_energy(chart_, q, p, mass(b));
    }
    return k;
  }

  /// Refresh the per-body trig caches of w from s (charts with HasTrigCache; else nothing).
  void refresh(const StateType& s, Workspace& w) const {
    w.resize(dim(), ambient_dim(), bodies());
    if constexpr (HasTrigCache<Chart>) {
      for (int b = 0; b < bodies(); ++b) {
        w.q = s.q.col(b);
        chart_.refresh(w.q, w.trig[static_cast<std::size_t>(b)]);
      }
    }
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
      embed_all(s, w);
      Scalar v(0);
      std::apply([&](const auto&... term) { ((v += term_energy(term, w)), ...); }, terms_);
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

  /// Ambient gradients of the potential for all bodies into w.G (w.X must hold the points).
  void ambient_gradient(Workspace& w) const {
    w.G.setZero();
    std::apply([&](const auto&... term) { (add_term_gradient(term, w), ...); }, terms_);
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
      embed_cached(s, w);
      ambient_gradient(w);
      for (int b = 0; b < bodies(); ++b) {
        pull_back(s, w, b);
        s.p.col(b) -= h * w.p;
      }
    }
  }
  /// The same kick, also keeping the chart gradient dV/dq of every body in grad (dim x bodies),
  /// for a stepper that reuses it while q and the frames stay as they are.
  void kick_cached(StateType& s, Scalar h, Workspace& w, typename StateType::Matrix& grad) const {
    if constexpr (has_potential) {
      embed_cached(s, w);
      ambient_gradient(w);
      grad.resize(dim(), bodies());
      for (int b = 0; b < bodies(); ++b) {
        pull_back(s, w, b);
        grad.col(b) = w.p;
        s.p.col(b) -= h * w.p;
      }
    }
  }

  /// Chart gradient dV/dq of all bodies (dim x bodies), for reference methods and tests.
  void potential_gradient(const StateType& s, Workspace& w,
                          typename StateType::Matrix& out) const {
    out.setZero(dim(), bodies());
    if constexpr (has_potential) {
      embed_all(s, w);
      ambient_gradient(w);
      for (int b = 0; b < bodies(); ++b) {
        pull_back(s, w, b);
        out.col(b) = w.p;
      }
    }
  }

 private:
  /// w.X from the caches (or from q for charts without them).
  void embed_cached(const StateType& s, Workspace& w) const {
    for (int b = 0; b < bodies(); ++b) {
      if constexpr (HasTrigCache<Chart>) {
        chart_.embed(w.trig[static_cast<std::size_t>(b)], w.x);
      } else {
        w.q = s.q.col(b);
        chart_.embed(w.q, w.x);
      }
      if (s.framed()) {
        w.X.col(b).noalias() = s.frames[static_cast<std::size_t>(b)] * w.x;  // world = F local
      } else {
        w.X.col(b) = w.x;
      }
    }
  }
  /// w.p = J(q_b)^T F_b^T w.G.col(b) (the chain rule through the body's frame, if any).
  void pull_back(const StateType& s, Workspace& w, int b) const {
    if (s.framed()) {
      w.g.noalias() = s.frames[static_cast<std::size_t>(b)].transpose() * w.G.col(b);
    } else {
      w.g = w.G.col(b);
    }
    if constexpr (HasTrigCache<Chart>) {
      chart_.pullback(w.trig[static_cast<std::size_t>(b)], w.g, w.p);
    } else {
      w.q = s.q.col(b);
      chart_.pullback(w.q, w.g, w.p);
    }
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
  Scalar term_energy(const Term& term, Workspace& w) const {
    Scalar v(0);
    if (inactive(term)) return v;
    if constexpr (PairTerm<Term, Chart>) {
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
      for (int b = 0; b < bodies(); ++b) {
        w.x = w.X.col(b);
        v += term.value(chart_, w.x, mass(b));
      }
    }
    return v;
  }

  template <class Term>
  void add_term_gradient(const Term& term, Workspace& w) const {
    if (inactive(term)) return;
    if constexpr (PairTerm<Term, Chart>) {
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
      for (int b = 0; b < bodies(); ++b) {
        w.x = w.X.col(b);
        term.gradient(chart_, w.x, mass(b), w.g);
        w.G.col(b) += w.g;
      }
    }
  }

  Chart chart_;
  std::vector<Scalar> masses_;
  std::tuple<Terms...> terms_;
};

/// Deduction guide: System(chart, masses, terms...).
template <class Chart, class... Terms>
System(Chart, std::vector<typename Chart::Scalar>, Terms...) -> System<Chart, Terms...>;

}  // namespace sesi
