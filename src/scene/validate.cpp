#include "validate.hpp"

#include <algorithm>
#include <array>
#include <cstdint>
#include <cmath>
#include <limits>
#include <numbers>
#include <vector>

#include <sesi/potentials.hpp>
#include <sesi/topologies/hyperbolic_surface.hpp>
#include <sesi/topologies/periodic_box.hpp>

#include "methods.hpp"
#include "suggest.hpp"

namespace sesi::program {

void check_method(std::string_view method, const Origin& origin, std::string_view key) {
  if (is_method(method)) return;
  throw InputError(origin, key,
                   "unknown method '" + cut_input(method) + "'" +
                       did_you_mean(method, method_names()) + " (expected " +
                       one_of(method_names()) + ")");
}

void check_method_or_auto(std::string_view method, const Origin& origin, std::string_view key) {
  if (method == "auto") return;
  if (is_method(method)) return;
  throw InputError(origin, key,
                   "unknown method '" + cut_input(method) + "'" +
                       did_you_mean(method, method_names()) + " (expected \"auto\" or " +
                       one_of(method_names()) + ")");
}

void check_tolerance(double tolerance, const Origin& origin, std::string_view key) {
  if (!std::isfinite(tolerance) || tolerance < min_tolerance || tolerance > max_tolerance) {
    throw InputError(origin, key,
                     "expected a max relative energy error from " + format_number(min_tolerance) +
                         " to " + format_number(max_tolerance) + ", got " + format_number(tolerance));
  }
}

void check_dt(double dt, const Origin& origin, std::string_view key) {
  if (!std::isfinite(dt) || dt == 0.0) {
    throw InputError(origin, key, "expected a finite, non-zero step, got " + format_number(dt));
  }
}

void check_t_end(double t_end, const Origin& origin, std::string_view key) {
  if (!std::isfinite(t_end) || t_end < 0.0) {
    throw InputError(origin, key, "expected a finite end time >= 0, got " + format_number(t_end));
  }
}

void check_output_every(long output_every, const Origin& origin, std::string_view key) {
  if (output_every < 1) {
    throw InputError(origin, key,
                     "expected an integer >= 1 (steps between output rows), got " +
                         std::to_string(output_every));
  }
}

void check_threads(long threads, const Origin& origin, std::string_view key) {
  if (threads < 0 || threads > 4096) {
    throw InputError(origin, key,
                     "expected an integer from 0 (all cores) to 4096, got " + std::to_string(threads));
  }
}

void check_check_every(long check_every, const Origin& origin, std::string_view key) {
  if (check_every < 1) {
    throw InputError(origin, key,
                     "expected an integer >= 1 (steps between energy and encounter checks), got " +
                         std::to_string(check_every));
  }
}

void check_checkpoint_every(long checkpoint_every, const Origin& origin, std::string_view key) {
  if (checkpoint_every < 1) {
    throw InputError(origin, key,
                     "expected an integer >= 1 (steps between checkpoints), got " + std::to_string(checkpoint_every));
  }
}

void check_neighbour_skin(double skin, const Origin& origin, std::string_view key) {
  if (!(skin >= 0.0 && skin <= 1.0)) {
    throw InputError(origin, key,
                     "expected a number from 0 to 1 (the Verlet skin as a fraction of the cutoff), got " +
                         format_number(skin));
  }
}

TrajectoryFormat parse_trajectory_format(std::string_view name, const Origin& origin, std::string_view key) {
  if (name == "csv") return TrajectoryFormat::csv;
  if (name == "h5md") {
#ifdef SESI_HAVE_HDF5
    return TrajectoryFormat::h5md;
#else
    throw InputError(origin, key, "this sesi was built without HDF5, so 'h5md' is not available (expected \"csv\")");
#endif
  }
  const std::vector<std::string_view> names{"csv", "h5md"};
  throw InputError(origin, key,
                   "unknown trajectory format '" + cut_input(name) + "'" + did_you_mean(name, names) +
                       " (expected " + one_of(names) + ")");
}

void check_step_count(double t_end, double dt, const Origin& origin, std::string_view key) {
  if (t_end / std::abs(dt) > max_steps) {
    throw InputError(origin, key,
                     "t_end / |dt| = " + format_number(t_end / std::abs(dt)) +
                         " steps; at most " + format_number(max_steps) + " are allowed");
  }
}

void check_energy_guard(double threshold, const Origin& origin, std::string_view key) {
  if (!std::isfinite(threshold) || !(threshold > 0.0)) {
    throw InputError(origin, key,
                     "expected a finite threshold > 0 on the relative energy error (or false to turn "
                     "the guard off), got " + format_number(threshold));
  }
}

void check_min_distance(double distance, const Origin& origin, std::string_view key) {
  if (!std::isfinite(distance) || distance < 0.0) {
    throw InputError(origin, key,
                     "expected a finite distance >= 0 (0 turns the close-encounter check off), got " +
                         format_number(distance));
  }
}

double encounter_floor(const PotentialSpec& spec, double length) {
  const auto floor_of = [](double min_distance, double scale) {
    return min_distance < 0.0 ? sesi::default_min_distance(scale) : min_distance;
  };
  if (const auto* g = std::get_if<CotangentGravitySpec>(&spec)) return floor_of(g->min_distance, length);
  if (const auto* c = std::get_if<CentralCotangentSpec>(&spec)) return floor_of(c->min_distance, length);
  if (const auto* lj = std::get_if<LennardJonesSpec>(&spec)) return floor_of(lj->min_distance, lj->sigma);
  return 0.0;
}

double singular_gap(const PotentialSpec& spec, SpaceKind kind, double radius, double d) {
  const bool cotangent = std::holds_alternative<CotangentGravitySpec>(spec) ||
                         std::holds_alternative<CentralCotangentSpec>(spec);
  if (cotangent && kind == SpaceKind::sphere) return std::min(d, std::numbers::pi * radius - d);
  return d;
}

long step_count(double t_end, double dt) {
  const double ratio = t_end / std::abs(dt);
  // A ratio within round-off of an integer n is n steps, not n + 1 with a tiny last step.
  const double nearest_whole = std::round(ratio);
  if (std::abs(ratio - nearest_whole) <= 1e-9 * std::max(1.0, ratio)) {
    return static_cast<long>(nearest_whole);
  }
  return static_cast<long>(std::ceil(ratio));
}

void check_mass(double mass, const Origin& origin, std::string_view key) {
  if (!(mass > 0.0) || !std::isfinite(mass)) {
    throw InputError(origin, key, "expected a finite number > 0, got " + format_number(mass));
  }
}

void check_radius(double radius, const Origin& origin, std::string_view key) {
  if (!(radius > 0.0) || !std::isfinite(radius)) {
    throw InputError(origin, key, "expected a finite number > 0, got " + format_number(radius));
  }
}

void check_potential(const PotentialSpec& spec, const KeyPlace& place) {
  const auto fail = [&](std::string_view key, const std::string& message) {
    const auto [origin, path] = place(key);
    throw InputError(origin, path, message);
  };
  const auto finite = [&](std::string_view key, double value) {
    if (!std::isfinite(value)) fail(key, "expected a finite number, got " + format_number(value));
  };
  const auto floor = [&](double d) {
    if (!(d < 0.0)) {
      const auto [origin, path] = place("min_distance");
      check_min_distance(d, origin, path);
    }
  };
  if (const auto* s = std::get_if<ChordWellSpec>(&spec)) {
    if (!(s->theta0 >= 0.0 && s->theta0 <= std::numbers::pi)) {
      fail("theta0", "expected an angle in [0, pi], got " + format_number(s->theta0));
    }
    finite("strength", s->strength);
  } else if (const auto* s = std::get_if<CotangentGravitySpec>(&spec)) {
    finite("G", s->G);
    floor(s->min_distance);
  } else if (const auto* s = std::get_if<CentralCotangentSpec>(&spec)) {
    finite("k", s->k);
    for (Eigen::Index i = 0; i < s->center.size(); ++i) finite("center", s->center[i]);
    floor(s->min_distance);
  } else if (const auto* s = std::get_if<HarmonicPairSpec>(&spec)) {
    finite("k", s->k);
    if (!(s->d0 >= 0.0) || !std::isfinite(s->d0)) fail("d0", "expected a finite distance >= 0, got " + format_number(s->d0));
  } else if (const auto* s = std::get_if<LennardJonesSpec>(&spec)) {
    if (!(s->epsilon >= 0.0) || !std::isfinite(s->epsilon)) {
      fail("epsilon", "expected a finite number >= 0, got " + format_number(s->epsilon));
    }
    if (!(s->sigma > 0.0) || !std::isfinite(s->sigma)) fail("sigma", "expected a finite number > 0, got " + format_number(s->sigma));
    if (!(s->cutoff > 0.0) || !std::isfinite(s->cutoff)) {
      fail("cutoff", "expected a finite distance > 0, got " + format_number(s->cutoff));
    }
    floor(s->min_distance);
  }
}

double far_resolution(double radii) { return std::numeric_limits<double>::epsilon() * std::sinh(radii); }

void check_far_resolution(double radii, int dim, const Origin& origin, std::string_view key) {
  const double resolution = far_resolution(radii);
  if (!(resolution > far_resolution_limit)) return;
  const double reach = std::asinh(far_resolution_limit / std::numeric_limits<double>::epsilon());
  throw InputError(origin, key,
                   "at " + format_short(radii) + " radii from the origin of H^" + std::to_string(dim) +
                       ", coordinates resolve a point only to eps sinh(r/R) = " + format_short(resolution) +
                       " radii, too coarse to place bodies (at most " + format_number(far_resolution_limit) +
                       ", within " + format_short(reach) +
                       " radii); move the scene nearer the origin by an isometry, which changes nothing else");
}

namespace {

using namespace std::string_view_literals;

constexpr std::array thermostat_kind_names = {"langevin"sv, "nose-hoover"sv, "csvr"sv, "brownian"sv};
constexpr std::array langevin_keys = {"kind"sv, "temperature"sv, "gamma"sv, "seed"sv};
constexpr std::array nose_hoover_keys = {"kind"sv, "temperature"sv, "tau"sv, "chain"sv};
constexpr std::array csvr_keys = {"kind"sv, "temperature"sv, "tau"sv, "seed"sv};
constexpr std::array brownian_keys = {"kind"sv, "temperature"sv, "gamma"sv, "seed"sv};
constexpr std::array any_thermostat_keys = {"kind"sv, "temperature"sv, "gamma"sv, "tau"sv, "chain"sv, "seed"sv};

}  // namespace

std::span<const std::string_view> thermostat_kinds() { return thermostat_kind_names; }

std::span<const std::string_view> thermostat_keys(std::string_view kind) {
  if (kind == "langevin") return langevin_keys;
  if (kind == "nose-hoover") return nose_hoover_keys;
  if (kind == "csvr") return csvr_keys;
  if (kind == "brownian") return brownian_keys;
  return {};
}

std::span<const std::string_view> all_thermostat_keys() { return any_thermostat_keys; }

std::string kinds_taking(std::string_view key) {
  std::vector<std::string_view> kinds;
  for (std::string_view kind : thermostat_kind_names) {
    const auto keys = thermostat_keys(kind);
    if (std::find(keys.begin(), keys.end(), key) != keys.end()) kinds.push_back(kind);
  }
  return one_of(kinds);
}

void check_temperature(double kT, std::string_view kind, const Origin& origin, std::string_view key) {
  if (kind == "nose-hoover") {
    if (!(kT > 0.0) || !std::isfinite(kT)) {
      throw InputError(origin, key,
                       "expected a finite temperature kT > 0 for a nose-hoover thermostat (its chain masses "
                       "Q = N_f kT tau^2 vanish at 0), got " + format_number(kT));
    }
    return;
  }
  if (!(kT >= 0.0) || !std::isfinite(kT)) {
    throw InputError(origin, key, "expected a finite temperature kT >= 0 (energy units, k_B = 1), got " + format_number(kT));
  }
}

void check_friction(double gamma, const Origin& origin, std::string_view key) {
  if (!(gamma > 0.0) || !std::isfinite(gamma)) {
    throw InputError(origin, key, "expected a finite friction gamma > 0 (1/time), got " + format_number(gamma));
  }
}

void check_relaxation_time(double tau, const Origin& origin, std::string_view key) {
  if (!(tau > 0.0) || !std::isfinite(tau)) {
    throw InputError(origin, key, "expected a finite relaxation time tau > 0, got " + format_number(tau));
  }
}

void check_chain(long chain, const Origin& origin, std::string_view key) {
  if (chain < 1 || chain > max_chain) {
    throw InputError(origin, key,
                     "expected an integer from 1 to " + std::to_string(max_chain) +
                         " (the Nose-Hoover chain's length), got " + std::to_string(chain));
  }
}

void check_seed(long long seed, const Origin& origin, std::string_view key) {
  if (seed < 0) {
    throw InputError(origin, key, "expected an integer from 0 to 2^63 - 1 (the noise's key), got " + std::to_string(seed));
  }
}

void check_thermostat_method(const Scene& scene, const Origin& origin, std::string_view key) {
  if (!scene.thermostat) return;
  const std::string& method = scene.integrator.method;
  if (method == "sesi2") return;
  if (method == "auto") {
    if (scene.thermostat->kind != "brownian") return;
    throw InputError(origin, key,
                     "method \"auto\" meets an energy error, but a brownian thermostat's overdamped step conserves no "
                     "energy; give method = \"sesi2\" and dt");
  }
  throw InputError(origin, key,
                   "a thermostat runs with method \"sesi2\" (its stages sit in the kick-drift-kick Strang step; "
                   "docs/thermostats.md), or \"auto\", which then picks sesi2; got \"" + cut_input(method) + "\"");
}

void check_thermostat(const ThermostatSpec& spec, const Origin& origin) {
  const auto keys = thermostat_keys(spec.kind);
  if (keys.empty()) {
    throw InputError(origin, "thermostat.kind",
                     "unknown thermostat kind '" + cut_input(spec.kind) + "' (expected " + one_of(thermostat_kind_names) + ")");
  }
  const auto takes = [&](std::string_view key) { return std::find(keys.begin(), keys.end(), key) != keys.end(); };
  if (spec.schedule.empty()) throw InputError(origin, "thermostat.temperature", "missing (no temperature)");
  for (std::size_t k = 0; k < spec.schedule.size(); ++k) {
    const std::string key = "thermostat.temperature[" + std::to_string(k + 1) + "]";
    const auto [t, kT] = spec.schedule[k];
    if (!std::isfinite(t)) throw InputError(origin, key + "[1]", "expected a finite time, got " + format_number(t));
    if (k > 0 && !(t > spec.schedule[k - 1].first)) {
      throw InputError(origin, key + "[1]", "the schedule's times must increase strictly, got " + format_number(t) +
                                                " after " + format_number(spec.schedule[k - 1].first));
    }
    check_temperature(kT, spec.kind, origin, key + "[2]");
  }
  if (takes("gamma")) check_friction(spec.gamma, origin, "thermostat.gamma");
  if (takes("tau")) check_relaxation_time(spec.tau, origin, "thermostat.tau");
  if (takes("chain")) check_chain(spec.chain, origin, "thermostat.chain");
  if (spec.seed > static_cast<std::uint64_t>(std::numeric_limits<long long>::max())) {
    throw InputError(origin, "thermostat.seed", "expected an integer from 0 to 2^63 - 1, got " + std::to_string(spec.seed));
  }
}

void check_box(const std::vector<double>& box, SpaceKind kind, int dim, const Origin& origin, std::string_view key) {
  if (kind != SpaceKind::euclidean) {
    throw InputError(origin, key,
                     "a periodic box is for a euclidean space (kind = \"euclidean\")" +
                         std::string(kind == SpaceKind::hyperbolic
                                         ? "; on a hyperbolic space give genus = g (a compact surface, dim = 2)"
                                         : "; the sphere is compact and needs none"));
  }
  if (static_cast<int>(box.size()) != dim) {
    throw InputError(origin, key,
                     "expected an array of " + std::to_string(dim) + " numbers (the box's edges, one per axis of E^" +
                         std::to_string(dim) + "), got " + std::to_string(box.size()) +
                         (box.size() == 1 ? " number" : " numbers"));
  }
  for (std::size_t k = 0; k < box.size(); ++k) {
    if (!(box[k] > 0.0) || !std::isfinite(box[k])) {
      throw InputError(origin, std::string(key) + "[" + std::to_string(k + 1) + "]",
                       "expected a finite edge > 0, got " + format_number(box[k]));
    }
  }
}

void check_genus(long genus, SpaceKind kind, int dim, const Origin& origin, std::string_view key) {
  constexpr int most = sesi::HyperbolicSurface<double>::max_genus;
  if (kind != SpaceKind::hyperbolic) {
    throw InputError(origin, key,
                     "a genus (a compact surface H^2/Gamma) is for a hyperbolic space (kind = \"hyperbolic\", dim = 2)" +
                         std::string(kind == SpaceKind::euclidean ? "; on a euclidean space give box = [L1, ..., Ln]"
                                                                  : "; the sphere is compact and needs none"));
  }
  if (dim != 2) {
    throw InputError(origin, key,
                     "a compact surface of genus g is 2-dimensional: expected dim = 2, got dim = " + std::to_string(dim));
  }
  if (genus < 2 || genus > most) {
    throw InputError(origin, key,
                     "expected an integer from 2 to " + std::to_string(most) +
                         " (the genus of a compact hyperbolic surface; docs/topology.md), got " + std::to_string(genus));
  }
}

double max_cutoff(const SpaceSpec& space) {
  if (!space.box.empty()) {
    return sesi::PeriodicBox<double, Eigen::Dynamic>(Eigen::Map<const Eigen::VectorXd>(
                                                         space.box.data(), static_cast<Eigen::Index>(space.box.size())))
        .max_cutoff();
  }
  if (space.genus != 0) return sesi::HyperbolicSurface<double>(space.genus, space.radius).max_cutoff();
  return std::numeric_limits<double>::infinity();
}

std::string topology_noun(const SpaceSpec& space) {
  if (!space.box.empty()) return "the periodic box";
  return "the genus-" + std::to_string(space.genus) + " surface of radius " + format_number(space.radius);
}

void check_topology_potential(const PotentialSpec& spec, const SpaceSpec& space, const KeyPlace& place) {
  if (!space.has_topology()) return;
  const auto fail = [&](std::string_view key, const std::string& message) {
    const auto [origin, path] = place(key);
    throw InputError(origin, path, message);
  };
  const std::string kind(potential_kind(spec));
  if (const auto* lj = std::get_if<LennardJonesSpec>(&spec)) {
    const double largest = max_cutoff(space);
    if (!(lj->cutoff <= largest)) {
      fail("cutoff", "cutoff " + format_number(lj->cutoff) + " is too long for " + topology_noun(space) +
                         " (a pair would meet two images of a body): the largest allowed cutoff is " +
                         format_number(largest));
    }
    return;
  }
  if (std::holds_alternative<CentralCotangentSpec>(spec) || std::holds_alternative<FunctionExternalSpec>(spec)) {
    fail("kind", "a " + kind + " potential is an external term, which " + topology_noun(space) +
                     " does not support (a force centre has images too); only short-range pair terms (lennard-jones)");
  }
  fail("kind", "a " + kind + " potential has no cutoff, and on " + topology_noun(space) +
                   " only short-range pair terms (lennard-jones, with a cutoff) are supported: a pair term without a "
                   "range would sum over every image");
}

void check_topology_method(const Scene& scene, const Origin& origin, std::string_view key) {
  if (!scene.space.has_topology()) return;
  const std::string& method = scene.integrator.method;
  if (method == "auto" || is_composition_method(method)) return;
  throw InputError(origin, key,
                   "on " + topology_noun(scene.space) + " the method must be a chart composition that is not processed (" +
                       one_of(composition_method_names()) +
                       ") or \"auto\": bodies are brought back into the domain between steps; got \"" +
                       cut_input(method) + "\"");
}

void check_scene_model(const Scene& scene, const Origin& origin) {
  if (scene.space.dim < 1) throw InputError(origin, "space.dim", "expected an integer >= 1, got " + std::to_string(scene.space.dim));
  if (scene.space.kind != SpaceKind::euclidean) check_radius(scene.space.radius, origin, "space.radius");
  if (!scene.space.box.empty()) check_box(scene.space.box, scene.space.kind, scene.space.dim, origin, "space.box");
  if (scene.space.genus != 0) check_genus(scene.space.genus, scene.space.kind, scene.space.dim, origin, "space.genus");
  for (std::size_t b = 0; b < scene.bodies.size(); ++b) {
    check_mass(scene.bodies[b].mass, origin, "bodies[" + std::to_string(b + 1) + "].mass");
  }
  for (std::size_t k = 0; k < scene.potentials.size(); ++k) {
    const std::string term = "potential[" + std::to_string(k + 1) + "].";
    const KeyPlace place = [&](std::string_view key) { return std::pair{origin, term + std::string(key)}; };
    check_potential(scene.potentials[k], place);
    check_topology_potential(scene.potentials[k], scene.space, place);
  }
  const IntegratorSpec& in = scene.integrator;
  check_method(in.method, origin, "integrator.method");
  check_topology_method(scene, origin, "integrator.method");
  if (!in.dt || !in.t_end) throw InputError(origin, "integrator", "missing dt or t_end");
  check_dt(*in.dt, origin, "integrator.dt");
  check_t_end(*in.t_end, origin, "integrator.t_end");
  check_step_count(*in.t_end, *in.dt, origin, "integrator");
  check_output_every(in.output_every, origin, "integrator.output_every");
  check_threads(in.threads, origin, "integrator.threads");
  if (in.check_every != 0) check_check_every(in.check_every, origin, "integrator.check_every");  // 0: default
  if (in.checkpoint_every != 0) check_checkpoint_every(in.checkpoint_every, origin, "integrator.checkpoint_every");
  check_neighbour_skin(in.neighbour_skin, origin, "integrator.neighbour_skin");
  if (in.energy_guard && *in.energy_guard != 0.0) check_energy_guard(*in.energy_guard, origin, "integrator.energy_guard");
  if (in.tolerance) check_tolerance(*in.tolerance, origin, "integrator.tolerance");
  if (scene.thermostat) {
    check_thermostat(*scene.thermostat, origin);
    check_thermostat_method(scene, origin, "integrator.method");
  }
}

}  // namespace sesi::program
