#pragma once
/// @file validate.hpp
/// Rules on values shared by the scene reader and the command-line overrides. Each throws
/// InputError naming the origin and key when the value breaks the rule.

#include <string>
#include <string_view>

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

}  // namespace sesi::program
