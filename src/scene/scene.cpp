#include "scene.hpp"

namespace sesi::program {

std::string_view space_name(SpaceKind kind) {
  switch (kind) {
    case SpaceKind::sphere: return "sphere";
    case SpaceKind::hyperbolic: return "hyperbolic";
    case SpaceKind::euclidean: break;
  }
  return "euclidean";
}

std::string_view potential_kind(const PotentialSpec& spec) {
  struct Kind {
    std::string_view operator()(const ChordWellSpec&) const { return "chord-well"; }
    std::string_view operator()(const CotangentGravitySpec&) const { return "cotangent-gravity"; }
    std::string_view operator()(const CentralCotangentSpec&) const { return "central-cotangent"; }
    std::string_view operator()(const HarmonicPairSpec&) const { return "harmonic-pair"; }
    std::string_view operator()(const LennardJonesSpec&) const { return "lennard-jones"; }
    std::string_view operator()(const FunctionExternalSpec&) const { return "function"; }
  };
  return std::visit(Kind{}, spec);
}

std::string_view trajectory_format_name(TrajectoryFormat format) {
  return format == TrajectoryFormat::h5md ? "h5md" : "csv";
}

}  // namespace sesi::program
