#pragma once
/// @file validate.hpp
/// Rules on values shared by the scene reader and the command-line overrides. Each throws
/// InputError naming the origin and key when the value breaks the rule.

#include <functional>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "errors.hpp"
#include "scene.hpp"

namespace sesi::program {

/// The most steps a run may take (t_end / |dt|).
inline constexpr double max_steps = 1e12;

void check_method(std::string_view method, const Origin& origin, std::string_view key);
/// A method name or "auto" (method = "auto": the method and step chosen for a tolerance).
void check_method_or_auto(std::string_view method, const Origin& origin, std::string_view key);
/// The bounds of `tolerance` (method = "auto"): a max relative energy error from 1e-12 (double's
/// round-off over a long run) to 1e-2.
inline constexpr double min_tolerance = 1e-12, max_tolerance = 1e-2;
void check_tolerance(double tolerance, const Origin& origin, std::string_view key);
/// dt: finite and non-zero (negative integrates backwards in time).
void check_dt(double dt, const Origin& origin, std::string_view key);
/// t_end: finite and >= 0.
void check_t_end(double t_end, const Origin& origin, std::string_view key);
/// threads: >= 0 (0: all cores).
void check_threads(long threads, const Origin& origin, std::string_view key);
/// check_every: >= 1.
void check_check_every(long check_every, const Origin& origin, std::string_view key);
void check_checkpoint_every(long checkpoint_every, const Origin& origin, std::string_view key);
/// neighbour_skin: a number from 0 to 1.
void check_neighbour_skin(double skin, const Origin& origin, std::string_view key);
/// "csv" or "h5md" (h5md only in a build with HDF5).
TrajectoryFormat parse_trajectory_format(std::string_view name, const Origin& origin, std::string_view key);
/// output_every: >= 1.
void check_output_every(long output_every, const Origin& origin, std::string_view key);
/// t_end / |dt| within max_steps (both already checked on their own).
void check_step_count(double t_end, double dt, const Origin& origin, std::string_view key);

/// energy_guard: a finite threshold > 0 (relative energy error, sesi::EnergyGuard).
void check_energy_guard(double threshold, const Origin& origin, std::string_view key);
/// min_distance of a singular potential: a finite distance >= 0 (0 turns the check off).
void check_min_distance(double distance, const Origin& origin, std::string_view key);

/// The close-encounter floor of a potential on a space of length scale `length` (R, or 1 on
/// E^n): its min_distance, or the library's default for the term (sesi::default_min_distance
/// of R, or of sigma for Lennard-Jones) when min_distance < 0; 0 for terms that are not singular
/// or whose check is off.
double encounter_floor(const PotentialSpec& spec, double length);
/// Distance from a geodesic distance d (between two bodies, or a body and a center) to the
/// potential's singular set: d, or on the sphere for the cotangent terms min(d, pi R - d).
double singular_gap(const PotentialSpec& spec, SpaceKind kind, double radius, double d);

/// The number of steps of a run: ceil(t_end / |dt|) up to round-off (the last step is
/// shortened to end exactly at t_end).
long step_count(double t_end, double dt);

/// mass of a body: a finite number > 0.
void check_mass(double mass, const Origin& origin, std::string_view key);
/// radius of a curved space: a finite number > 0.
void check_radius(double radius, const Origin& origin, std::string_view key);
/// Where a failed check of one key of a table points: its origin and key path.
using KeyPlace = std::function<std::pair<Origin, std::string>(std::string_view key)>;
/// A potential term's parameters: all finite; theta0 in [0, pi]; d0 and epsilon >= 0; sigma and
/// cutoff > 0; min_distance as check_min_distance (< 0: the default).
void check_potential(const PotentialSpec& spec, const KeyPlace& place);
/// H^n, n >= 2: the coordinates of a point at distance r from the origin (world x, or chart q about
/// the origin) resolve it across the line of sight only to eps sinh(r/R) radii, their rounding
/// (8e-6 at 25 radii, 1e-3 at 30, 0.18 at 35, 6e5 at 50), and its velocity likewise. Bodies or a
/// force centre given farther out than where that passes this (32.1 radii) would have their
/// separations, distances to the centre and directions of motion known to fewer than two digits:
/// the scene is refused (the geodesic methods' limit, geodesic_reach_limit, is the same resolution
/// of their e^(2r/R) loss). docs/stability.md, "Far from the origin".
inline constexpr double far_resolution_limit = 1e-2;
/// eps sinh(radii): how well coordinates resolve a point `radii` = r/R from the origin of H^n.
double far_resolution(double radii);
/// Throws InputError at origin and key when far_resolution(radii) > far_resolution_limit, for a
/// body or force centre of a scene on H^dim (dim >= 2).
void check_far_resolution(double radii, int dim, const Origin& origin, std::string_view key);
/// The thermostat kinds of a [thermostat] table ("langevin", "nose-hoover", "csvr", "brownian"),
/// and the keys a kind takes ("kind" first; empty for an unknown kind). docs/scene-format.md.
std::span<const std::string_view> thermostat_kinds();
std::span<const std::string_view> thermostat_keys(std::string_view kind);
/// Every key some kind takes (for a table without kind), and the kinds that take a key, in words.
std::span<const std::string_view> all_thermostat_keys();
std::string kinds_taking(std::string_view key);
/// The longest Nose-Hoover chain (Martyna, Klein and Tuckerman use M = 3 to 5; a longer one only
/// costs time and checkpoint size).
inline constexpr long max_chain = 100;
/// A thermostat's temperature kT (k_B = 1): finite and >= 0; > 0 for nose-hoover, whose chain
/// masses Q_1 = N_f kT tau^2, Q_j = kT tau^2 vanish at kT = 0.
void check_temperature(double kT, std::string_view kind, const Origin& origin, std::string_view key);
/// gamma (langevin, brownian): a finite friction > 0 (1/time).
void check_friction(double gamma, const Origin& origin, std::string_view key);
/// tau (nose-hoover, csvr): a finite relaxation time > 0.
void check_relaxation_time(double tau, const Origin& origin, std::string_view key);
/// chain (nose-hoover): an integer from 1 to max_chain.
void check_chain(long chain, const Origin& origin, std::string_view key);
/// seed: an integer from 0 to 2^63 - 1 (TOML's integers are signed 64-bit).
void check_seed(long long seed, const Origin& origin, std::string_view key);
/// A thermostat runs with sesi2 only (its stages sit in the kick-drift-kick Strang step,
/// include/sesi/thermostat.hpp), or "auto" before it is resolved (which then picks sesi2; not for
/// brownian, whose step is no energy-conserving step). Nothing without a thermostat.
void check_thermostat_method(const Scene& scene, const Origin& origin, std::string_view key);
/// The whole of a ThermostatSpec by the rules above (keys named "thermostat.KEY", all at origin):
/// the kind, its schedule (times strictly increasing), its parameters.
void check_thermostat(const ThermostatSpec& spec, const Origin& origin);

// ---- topologies (issue #26; docs/topology.md): a periodic box on E^n, a compact surface H^2/Gamma ----

/// box of [space]: only on a euclidean space, dim edges, each finite and > 0 (key "space.box",
/// an edge "space.box[k]").
void check_box(const std::vector<double>& box, SpaceKind kind, int dim, const Origin& origin, std::string_view key);
/// genus of [space]: only on a hyperbolic space of dim 2, an integer from 2 to
/// sesi::HyperbolicSurface<double>::max_genus.
void check_genus(long genus, SpaceKind kind, int dim, const Origin& origin, std::string_view key);
/// The largest pair cutoff the space's topology allows (sesi::PeriodicBox / HyperbolicSurface::
/// max_cutoff(): beyond it a pair would meet two images, or one the neighbour search does not
/// see); +inf without a topology. The space's box or genus must have passed the checks above.
double max_cutoff(const SpaceSpec& space);
/// "the periodic box" / "the genus-2 surface of radius 1.5" (for messages).
std::string topology_noun(const SpaceSpec& space);
/// A potential on a space with a topology: only short-range pair terms (lennard-jones), whose
/// cutoff is at most max_cutoff(space). A pair term without a range (a sum over every image)
/// and an external term (a force centre is not periodic) are refused. Nothing without a topology.
void check_topology_potential(const PotentialSpec& spec, const SpaceSpec& space, const KeyPlace& place);
/// A method on a space with a topology: a chart composition that is not processed (sesi2 ..
/// sesi8-kahan-li: the integrator reduces the bodies into the domain between steps, which a
/// processed kernel's variables or a geodesic method's embedding state do not allow), or "auto"
/// (which then picks among those). Nothing without a topology.
void check_topology_method(const Scene& scene, const Origin& origin, std::string_view key);

/// A scene model that did not come from a scene file (a checkpoint's), by the rules the scene
/// reader applies to one: the radius, the masses, the potentials and the integrator's settings
/// (keys named as in a scene file, all at origin).
void check_scene_model(const Scene& scene, const Origin& origin);

}  // namespace sesi::program
