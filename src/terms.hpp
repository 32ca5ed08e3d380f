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

#include <variant>
#include <vector>

#include <sesi/potentials.hpp>
#include <sesi/system.hpp>

#include "scene.hpp"

namespace sesi::program {

/// The pair terms of a scene that are functions of the chord c: W(c) = sum of the terms' W.
template <class Chart>
class ChordPairTerms {
 public:
  using distance_kind = sesi::chord_distance;
  using Term = sesi::ChordWell<double>;

  void add(Term term) { terms_.push_back(std::move(term)); }
  bool empty() const { return terms_.empty(); }

  double value(const Chart& space, double c, double mi, double mj) const {
    double w = 0.0;
    for (const Term& t : terms_) w += t.value(space, c, mi, mj);
    return w;
  }
  double derivative(const Chart& space, double c, double mi, double mj) const {
    double dw = 0.0;
    for (const Term& t : terms_) dw += t.derivative(space, c, mi, mj);
    return dw;
  }

 private:
  std::vector<Term> terms_;
};

/// The pair terms of a scene that are functions of the geodesic distance d: W(d) = sum of W.
template <class Chart>
class PairTerms {
 public:
  using distance_kind = sesi::geodesic_distance;
  using Term = std::variant<sesi::CotangentGravity<double>, sesi::HarmonicPair<double>,
                            sesi::LennardJones<double>>;

  void add(Term term) { terms_.push_back(std::move(term)); }
  bool empty() const { return terms_.empty(); }

  double value(const Chart& space, double d, double mi, double mj) const {
    double w = 0.0;
    for (const Term& term : terms_)
      w += std::visit([&](const auto& t) { return t.value(space, d, mi, mj); }, term);
    return w;
  }
  double derivative(const Chart& space, double d, double mi, double mj) const {
    double dw = 0.0;
    for (const Term& term : terms_)
      dw += std::visit([&](const auto& t) { return t.derivative(space, d, mi, mj); }, term);
    return dw;
  }

 private:
  std::vector<Term> terms_;
};

/// All external terms of a scene: V(x) = sum of the terms' V.
template <class Chart>
class ExternalTerms {
 public:
  using Ambient = typename Chart::Ambient;
  using Term = std::variant<sesi::CentralCotangent<Chart>>;

  void add(Term term) { terms_.push_back(std::move(term)); }
  bool empty() const { return terms_.empty(); }

  double value(const Chart& space, const Ambient& x, double m) const {
    double v = 0.0;
    for (const Term& term : terms_) {
      v += std::visit([&](const auto& t) { return t.value(space, x, m); }, term);
    }
    return v;
  }

  void gradient(const Chart& space, const Ambient& x, double m, Ambient& g) const {
    g = Ambient::Zero(x.size());
    for (const Term& term : terms_) {
      std::visit([&](const auto& t) { t.gradient(space, x, m, scratch_); }, term);
      g += scratch_;
    }
  }

 private:
  std::vector<Term> terms_;
  mutable Ambient scratch_;  // one term's gradient (no allocation per call)
};

/// The scene's potentials, sorted into the two aggregates.
template <class Chart>
void add_terms(const Scene& scene, ChordPairTerms<Chart>& chords, PairTerms<Chart>& pairs,
               ExternalTerms<Chart>& externals) {
  for (const PotentialSpec& spec : scene.potentials) {
    if (const auto* s = std::get_if<ChordWellSpec>(&spec)) {
      chords.add(sesi::ChordWell<double>(s->theta0, s->strength));
    } else if (const auto* s = std::get_if<CotangentGravitySpec>(&spec)) {
      pairs.add(sesi::CotangentGravity<double>{s->G});
    } else if (const auto* s = std::get_if<HarmonicPairSpec>(&spec)) {
      pairs.add(sesi::HarmonicPair<double>{s->k, s->d0});
    } else if (const auto* s = std::get_if<LennardJonesSpec>(&spec)) {
      pairs.add(sesi::LennardJones<double>{s->epsilon, s->sigma, s->cutoff});
    } else if (const auto* s = std::get_if<CentralCotangentSpec>(&spec)) {
      sesi::CentralCotangent<Chart> term;
      term.k = s->k;
      term.center = s->center;
      externals.add(std::move(term));
    }
  }
}

/// The one system type of a chart: masses, two pair aggregates and an external aggregate.
template <class Chart>
using SystemOf = sesi::System<Chart, ChordPairTerms<Chart>, PairTerms<Chart>, ExternalTerms<Chart>>;

/// The scene's system on chart.
template <class Chart>
SystemOf<Chart> make_system(const Scene& scene, const Chart& chart) {
  ChordPairTerms<Chart> chords;
  PairTerms<Chart> pairs;
  ExternalTerms<Chart> externals;
  add_terms(scene, chords, pairs, externals);
  std::vector<double> masses;
  for (const Body& b : scene.bodies) masses.push_back(b.mass);
  return SystemOf<Chart>(chart, std::move(masses), std::move(chords), std::move(pairs),
                         std::move(externals));
}

}  // namespace sesi::program
