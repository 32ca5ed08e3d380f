#pragma once
/// @file terms.hpp
/// The potential terms of a scene at run time, as three term types of the library's System: a
/// chord pair aggregate, a geodesic pair aggregate and an external aggregate, each a list of the
/// built-in terms. So a (space, dimension) has one System type whatever the scene's combination
/// of potentials, and the program instantiates no space x dimension x potential combinations.
/// An empty aggregate costs nothing: the System skips a term whose empty() is true.
///
/// The chord aggregate (the seed's chord well) gets the chord in the ambient metric from the
/// System (|x_i - x_j| on S^n and E^n, the Minkowski chord 2R sinh(d/2R) on H^n): no arc
/// function per pair. The geodesic aggregate gets the geodesic distance d.

#include <algorithm>
#include <limits>
#include <memory>
#include <optional>
#include <type_traits>
#include <variant>
#include <vector>

#include <sesi/potentials.hpp>
#include <sesi/system.hpp>

#include "scene.hpp"

namespace sesi::program {

/// A sum of pair terms of one distance kind, each one of Alternatives: W = sum of the terms' W.
/// On a space with pair_geometry the sum is an AlgebraicPairTerm: a term with an algebraic form
/// (cotangent gravity) gets the pair's geometry, the others its distance, computed once.
template <class Kind, class... Alternatives>
class PairSum {
 public:
  using distance_kind = Kind;
  using Term = std::variant<Alternatives...>;

  void add(Term term) { terms_.push_back(std::move(term)); }
  bool empty() const { return terms_.empty(); }

  const std::vector<Term>& terms() const { return terms_; }

  template <class Space>
  double value(const Space& space, double d, double mi, double mj) const {
    return sum(d, [&](const auto& t, auto arg) { return t.value(space, arg, mi, mj); });
  }
  template <class Space>
  double derivative(const Space& space, double d, double mi, double mj) const {
    return sum(d, [&](const auto& t, auto arg) { return t.derivative(space, arg, mi, mj); });
  }
  /// d^2W/dd^2, for the configurational temperature (sesi::System::laplacian_sum).
  template <class Space>
  double second_derivative(const Space& space, double d, double mi, double mj) const {
    return sum(d, [&](const auto& t, auto arg) { return t.second_derivative(space, arg, mi, mj); });
  }
  template <class Space>
    requires sesi::HasPairGeometry<Space>
  double value(const Space& space, const sesi::PairGeometry<double>& g, double mi, double mj) const {
    return sum_on(space, g, [&](const auto& t, auto arg) { return t.value(space, arg, mi, mj); });
  }
  template <class Space>
    requires sesi::HasPairGeometry<Space>
  double derivative(const Space& space, const sesi::PairGeometry<double>& g, double mi, double mj) const {
    return sum_on(space, g, [&](const auto& t, auto arg) { return t.derivative(space, arg, mi, mj); });
  }
  template <class Space>
    requires sesi::HasPairGeometry<Space>
  double second_derivative(const Space& space, const sesi::PairGeometry<double>& g, double mi, double mj) const {
    return sum_on(space, g, [&](const auto& t, auto arg) { return t.second_derivative(space, arg, mi, mj); });
  }
  template <class Space>
    requires sesi::HasPairGeometry<Space>
  double derivative_over_sn(const Space& space, const sesi::PairGeometry<double>& g, double mi, double mj) const {
    return sum_on(space, g, [&](const auto& t, auto arg) {
      if constexpr (requires { t.derivative_over_sn(space, arg, mi, mj); }) {
        return t.derivative_over_sn(space, arg, mi, mj);
      } else {
        return t.derivative(space, arg, mi, mj) / g.sn;
      }
    });
  }

 private:
  template <class F>
  double sum(double d, F&& f) const {
    double w = 0.0;
    for (const Term& term : terms_) w += std::visit([&](const auto& t) { return f(t, d); }, term);
    return w;
  }
  template <class Space, class F>
  double sum_on(const Space& space, const sesi::PairGeometry<double>& g, F&& f) const {
    double d = -1.0;  // the distance, once a term needs it
    const auto one = [&](const auto& t) {
      using T = std::remove_cvref_t<decltype(t)>;
      if constexpr (requires { t.value(space, g, 1.0, 1.0); }) {
        return f(t, g);
      } else if constexpr (sesi::is_chord_term<T>) {
        return f(t, g.chord());
      } else {
        if (d < 0.0) d = space.distance_of(g);
        return f(t, d);
      }
    };
    // One term, the common case, without the loop (this is the inner loop of all-pairs sums).
    if (terms_.size() == 1) return 0.0 + std::visit(one, terms_.front());
    double w = 0.0;
    for (const Term& term : terms_) w += std::visit(one, term);
    return w;
  }

  std::vector<Term> terms_;
};

/// The pair terms of a scene that are functions of the chord c (the seed's chord well).
template <class Chart>
using ChordPairTerms = PairSum<sesi::chord_distance, sesi::ChordWell<double>>;

/// The long-range pair terms of a scene, functions of the geodesic distance d: all pairs.
template <class Chart>
using PairTerms = PairSum<sesi::geodesic_distance, sesi::CotangentGravity<double>, sesi::HarmonicPair<double>>;

/// The short-range pair terms (Lennard-Jones): through a neighbour index, out to the largest
/// cutoff (sesi::ShortRangeTerm).
template <class Chart>
class ShortPairTerms : public PairSum<sesi::geodesic_distance, sesi::LennardJones<double>> {
  using Base = PairSum<sesi::geodesic_distance, sesi::LennardJones<double>>;

 public:
  void add(sesi::LennardJones<double> term) {
    Base::add(term);
    lj_.push_back(term);
  }
  template <class Space>
  double range(const Space&) const {
    double r = 0.0;
    for (const auto& term : lj_) r = std::max(r, term.cutoff);
    return r;
  }
  /// The many-body kernel's call (sesi::System::add_gradient_by_pairs), once per pair in a Verlet
  /// list: the sum of the terms' dW/dd / sn (LennardJones::derivative_over, one division fewer
  /// than PairSum's dW/dd / sn), without the variant, inlined.
  template <class Space>
    requires sesi::HasPairGeometry<Space>
  SESI_INLINE double derivative_over_sn(const Space& space, const sesi::PairGeometry<double>& g, double mi,
                                        double mj) const {
    static_cast<void>(mi);
    static_cast<void>(mj);
    const double d = space.distance_of(g);
    if (lj_.size() == 1) return 0.0 + lj_.front().derivative_over(space, d, g.sn);
    double w = 0.0;
    for (const auto& term : lj_) w += term.derivative_over(space, d, g.sn);
    return w;
  }
  /// One Lennard-Jones term with the call above's bits, by value: the kernel's vector loop
  /// (sesi::System::pair_block) inlines it with no branch on the number of terms.
  struct OneTerm {
    sesi::LennardJones<double> lj;
    template <class Space>
    SESI_INLINE double derivative_over_sn(const Space& space, const sesi::PairGeometry<double>& g, double,
                                          double) const {
      return 0.0 + lj.derivative_over(space, space.distance_of(g), g.sn);
    }
  };
  /// The term the kernel's vector loop evaluates instead of this one (sesi::System::
  /// add_gradient_by_pairs): OneTerm where there is one term, else none (this).
  std::optional<OneTerm> vector_kernel() const {
    return lj_.size() == 1 ? std::optional<OneTerm>(OneTerm{lj_.front()}) : std::nullopt;
  }

 private:
  std::vector<sesi::LennardJones<double>> lj_;  // the terms, as the base holds them
};

/// An external potential given as code (FunctionExternalSpec), on world points: in a cluster
/// frame C (H^n) it sees the world point C x of a local x, and its gradient goes back as C^T g
/// (the chain rule of V(C x)).
template <class Chart>
struct FunctionExternal {
  using Ambient = typename Chart::Ambient;
  std::shared_ptr<const FunctionExternalSpec::Functions> functions;
  Eigen::MatrixXd frame;  ///< world = frame * local; empty: the identity

  double value(const Chart&, const Ambient& x, double m) const {
    return functions->value(world(x), m);
  }
  void gradient(const Chart&, const Ambient& x, double m, Ambient& g) const {
    Eigen::VectorXd dv = Eigen::VectorXd::Zero(x.size());
    functions->gradient(world(x), m, dv);
    if (frame.size() == 0) {
      g = dv;
    } else {
      g = frame.transpose() * dv;
    }
  }

 private:
  Eigen::VectorXd world(const Ambient& x) const {
    if (frame.size() == 0) return x;
    return frame * x;
  }
};

/// All external terms of a scene: V(x) = sum of the terms' V.
template <class Chart>
class ExternalTerms {
 public:
  using Ambient = typename Chart::Ambient;
  using Term = std::variant<sesi::CentralCotangent<Chart>, FunctionExternal<Chart>>;

  void add(Term term) { terms_.push_back(std::move(term)); }
  bool empty() const { return terms_.empty(); }

  /// Every term depends on where the world is: in a cluster frame (H^n) the system evaluates
  /// the terms as seen from it (sesi::System::has_movable_center): force centres moved into
  /// the frame, function terms given the frame.
  bool has_centres() const { return !terms_.empty(); }
  template <class Frame>
    requires requires(const Chart& c, const Frame& f, Ambient& a) { c.to_frame(f, a, a); }
  ExternalTerms in_frame(const Chart& space, const Frame& frame) const {
    ExternalTerms out = *this;
    for (Term& term : out.terms_) {
      std::visit(
          [&](auto& t) {
            if constexpr (std::is_same_v<std::remove_cvref_t<decltype(t)>, FunctionExternal<Chart>>) {
              t.frame = frame;
            } else {
              const Ambient world = t.center;
              space.to_frame(frame, world, t.center);
            }
          },
          term);
    }
    return out;
  }

  double value(const Chart& space, const Ambient& x, double m) const {
    double v = 0.0;
    for (const Term& term : terms_) {
      v += std::visit([&](const auto& t) { return t.value(space, x, m); }, term);
    }
    return v;
  }

  /// The Laplacian of the sum (sesi::System::laplacian_sum): NaN when a term is given as code
  /// (FunctionExternal has no Laplacian).
  double laplacian(const Chart& space, const Ambient& x, double m) const {
    double v = 0.0;
    for (const Term& term : terms_) {
      v += std::visit(
          [&](const auto& t) {
            if constexpr (requires { t.laplacian(space, x, m); }) {
              return static_cast<double>(t.laplacian(space, x, m));
            } else {
              return std::numeric_limits<double>::quiet_NaN();
            }
          },
          term);
    }
    return v;
  }

  /// Called for many bodies at once on threads, so it keeps no scratch of its own; one term,
  /// the common case, writes g directly.
  void gradient(const Chart& space, const Ambient& x, double m, Ambient& g) const {
    if (terms_.size() == 1) {
      std::visit([&](const auto& t) { t.gradient(space, x, m, g); }, terms_.front());
      return;
    }
    g = Ambient::Zero(x.size());
    Ambient one(x.size());
    for (const Term& term : terms_) {
      std::visit([&](const auto& t) { t.gradient(space, x, m, one); }, term);
      g += one;
    }
  }

 private:
  std::vector<Term> terms_;
};

/// The scene's potentials, sorted into the two aggregates.
template <class Chart>
void add_terms(const Scene& scene, ChordPairTerms<Chart>& chords, PairTerms<Chart>& pairs,
               ShortPairTerms<Chart>& short_pairs, ExternalTerms<Chart>& externals) {
  for (const PotentialSpec& spec : scene.potentials) {
    if (const auto* s = std::get_if<ChordWellSpec>(&spec)) {
      chords.add(sesi::ChordWell<double>(s->theta0, s->strength));
    } else if (const auto* s = std::get_if<CotangentGravitySpec>(&spec)) {
      pairs.add(sesi::CotangentGravity<double>{s->G});
    } else if (const auto* s = std::get_if<HarmonicPairSpec>(&spec)) {
      pairs.add(sesi::HarmonicPair<double>{s->k, s->d0});
    } else if (const auto* s = std::get_if<LennardJonesSpec>(&spec)) {
      short_pairs.add(sesi::LennardJones<double>{s->epsilon, s->sigma, s->cutoff});
    } else if (const auto* s = std::get_if<CentralCotangentSpec>(&spec)) {
      sesi::CentralCotangent<Chart> term;
      term.k = s->k;
      term.center = s->center;
      externals.add(std::move(term));
    } else if (const auto* s = std::get_if<FunctionExternalSpec>(&spec)) {
      externals.add(FunctionExternal<Chart>{s->functions, {}});
    }
  }
}

/// The one system type of a chart: masses, three pair sums and the external terms.
template <class Chart>
using SystemOf = sesi::System<Chart, ChordPairTerms<Chart>, PairTerms<Chart>, ShortPairTerms<Chart>,
                              ExternalTerms<Chart>>;

/// The scene's system on chart.
template <class Chart>
SystemOf<Chart> make_system(const Scene& scene, const Chart& chart) {
  ChordPairTerms<Chart> chords;
  PairTerms<Chart> pairs;
  ShortPairTerms<Chart> short_pairs;
  ExternalTerms<Chart> externals;
  add_terms(scene, chords, pairs, short_pairs, externals);
  std::vector<double> masses;
  for (const Body& b : scene.bodies) masses.push_back(b.mass);
  SystemOf<Chart> system(chart, std::move(masses), std::move(chords), std::move(pairs), std::move(short_pairs),
                         std::move(externals));
  system.set_neighbour_skin(scene.integrator.neighbour_skin);
  return system;
}

}  // namespace sesi::program
