#pragma once
/// @file topology.hpp
/// Spaces with a topology (issue #26): the chart of the covering space (E^n, H^2) together with
/// a discrete group of isometries whose quotient is the space simulated, a periodic box
/// (topologies/periodic_box.hpp) or a compact hyperbolic surface (topologies/hyperbolic_surface.hpp).
///
/// "A space knows its topology" (docs/topology.md): the topology reduces a point into its
/// domain by an isometry of the group, recorded per body (image counts or a group word, so
/// that unwrapped positions are exact), gives the minimum-image separation of two points and
/// states the largest pair cutoff for which that image is unique. A Quotient is a Chart in every
/// respect (it derives from it): System, State, steppers and thermostats take it unchanged;
/// only the pair loops (minimum image), the neighbour structures and wrap() ask for topology().
/// Minimum image and cell lists: Allen & Tildesley, Computer Simulation of Liquids (2nd ed.,
/// 2017), 1.6 and 5.3; the hyperbolic surfaces: Sausset & Tarjus, J. Phys. A 40, 12873 (2007).

#include <utility>

#include "sesi/chart.hpp"
#include "sesi/state.hpp"

namespace sesi {

/// The chart of the covering space plus a topology (see the file comment).
template <class Chart, class Topo>
class Quotient : public Chart {
 public:
  using Topology = Topo;
  using Cover = Chart;  ///< the covering space's chart
  Quotient(Chart chart, Topo topology) : Chart(std::move(chart)), topology_(std::move(topology)) {}
  const Topo& topology() const { return topology_; }
  /// The covering space's chart (e.g. to build a System on the cover for a reference).
  const Chart& cover() const { return *this; }

 private:
  Topo topology_;
};

/// Charts that carry a topology (a Quotient or a user chart with topology()).
template <class C>
concept HasTopology = requires(const C& c) { c.topology(); };

/// Bring bodies back into the domain between steps. If some body's world point lies outside the
/// domain by more than `margin` (a length), EVERY body outside the domain (by any amount) is
/// reduced into it and its image record updated; else nothing changes, so that a
/// kick-drift-kick stepper's kept gradient and a Verlet list stay valid between such events
/// (the potential, a function of minimum-image separations, is the same for any images, so the
/// kept gradient stays valid across a wrap too). Returns the number of bodies moved.
///  - E^n box: q_b <- q_b - L floor(q_b / L) per component, counts_b += floor(q_b / L).
///  - H^2 surface: the body's frame F_b <- gamma F_b (q_b, p_b unchanged: an exact isometry of the
///    world point; frames are enabled first if the state has none), the word W_b updated so that
///    W_b x_b is unchanged (HyperbolicSurface::append_inverse).
/// A quotient never uses a cluster frame (recharting.hpp: ClusterChart is false for it).
template <class Sys>
  requires HasTopology<typename Sys::Chart>
int wrap(const Sys& sys, State<typename Sys::Chart>& s, typename Sys::Chart::Topology::Images& images,
         typename Sys::Scalar margin) {
  const auto& chart = sys.chart();
  return chart.topology().wrap(chart, s, images, margin);
}

}  // namespace sesi
