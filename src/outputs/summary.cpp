#include "summary.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <span>
#include <variant>

#include <sesi/parallel.hpp>

#include "json_writer.hpp"
#include "output_dir.hpp"
#include "methods.hpp"
#include "validate.hpp"

namespace sesi::program {

namespace {
void write_space(JsonWriter& json, const Scene& scene) {
  json.begin_object("space");
  json.string("kind", space_name(scene.space.kind));
  json.integer("dim", scene.space.dim);
  if (scene.space.kind != SpaceKind::euclidean) json.number("radius", scene.space.radius);
  // A topology: the box's edges or the surface's genus, and the largest pair cutoff it allows
  // (the space's own max_cutoff(): half the shortest edge; on a surface, include/sesi/topologies/
  // hyperbolic_surface.hpp).
  if (!scene.space.box.empty()) json.numbers("box", scene.space.box);
  if (scene.space.genus > 0) json.integer("genus", scene.space.genus);
  if (scene.space.has_topology()) json.number("max_cutoff", max_cutoff(scene.space));
  json.end_object();
}

void write_final_state(JsonWriter& json, const Snapshot& s) {
  json.begin_object("final_state");
  json.integer("step", s.step);
  json.number("t", s.t);
  json.begin_array("bodies");
  // In blocks of bodies: across ranks from their owners (for_each_block), one block at a time.
  for_each_block(s, field_q | field_p | field_x | field_v | field_n, [&](const BodyBlock& block) {
    const auto q = block.q(), p = block.p(), x = block.x(), v = block.v();
    const auto n = block.image_counts();
    for (Eigen::Index k = 0; k < block.count; ++k) {
      const Eigen::Index b = block.first + k;
      json.begin_object();
      // (A column of a column-major matrix: contiguous.)
      const auto column = [k](const BodyBlock::Map& m) {
        return std::span<const double>(m.col(k).data(), static_cast<std::size_t>(m.rows()));
      };
      json.numbers("q", column(q));
      json.numbers("p", column(p));
      json.numbers("x", column(x));
      json.numbers("v", column(v));
      // On a topology: the image counts (E^n box), or the unwrapped point and the word (H^2
      // surface; one process only, s whole).
      if (n.rows() > 0) json.numbers("n", Eigen::VectorXd(n.col(k).cast<double>()));
      if (s.unwrapped.cols() > b) json.numbers("u", Eigen::VectorXd(s.unwrapped.col(b)));
      if (static_cast<Eigen::Index>(s.words.size()) > b) json.string("word", word_text(s.words[static_cast<std::size_t>(b)]));
      json.end_object();
    }
  });
  json.end_array();
  json.end_object();
}

/// The most threads a loop of the run was given (include/sesi/parallel.hpp): loops over bodies
/// one per min_parallel_bodies bodies (threads_for); from System::rows_from (= min_parallel_bodies)
/// bodies on, a long-range pair term (all but Lennard-Jones and the central term) sums tiles of
/// the pair triangle, up to four per thread (System::tiling, for_chunks).
int threads_used(const Scene& scene) {
  const int n = scene.body_count();
  int used = sesi::parallel::threads_for(n);
  const bool tiled = std::any_of(scene.potentials.begin(), scene.potentials.end(), [](const PotentialSpec& p) {
    return !std::holds_alternative<LennardJonesSpec>(p) && !std::holds_alternative<CentralCotangentSpec>(p);
  });
  if (tiled && n >= sesi::parallel::min_parallel_bodies) {
    const int block = std::max(64, (n + 47) / 48), blocks = (n + block - 1) / block;
    const int threads = sesi::parallel::threads();
    const int chunks = std::min(blocks * (blocks + 1) / 2, 4 * threads);
    used = std::max(used, std::min(threads, (chunks + 3) / 4));
  }
  return used;
}

int method_order(std::string_view name) {
  for (const MethodInfo& m : method_catalogue()) {
    if (m.name == name) return m.order;
  }
  return 0;
}
}  // namespace

double scene_chart_p_error(double distance, double radius) {
  return std::numeric_limits<double>::epsilon() * std::exp(2.0 * distance / radius);
}

namespace {
/// What method = "auto" picked and why (run/auto_method.cpp).
void write_auto(JsonWriter& json, const AutoChoice& a, double max_rel_error) {
  json.begin_object("auto");
  json.number("tolerance", a.tolerance);
  // The run's own max relative energy error over the tolerance: above 10, the pilot runs did not
  // see what the run met (e.g. a close approach after them); the program then says so on stderr.
  json.number("error_over_tolerance", max_rel_error / a.tolerance);
  json.string("reason", a.reason);
  if (a.given_dt) {
    json.number("replaced_dt", *a.given_dt);
    json.integer("replaced_output_every", a.given_output_every);
  } else {
    json.null("replaced_dt");
  }
  json.number("predicted_max_rel_energy_error", a.predicted_error);
  json.number("pilot_t_end", a.pilot_t_end);
  json.integer("pilot_steps", a.pilot_steps);
  json.number("pilot_seconds", a.pilot_seconds);
  json.begin_array("candidates");
  for (const AutoCandidate& c : a.candidates) {
    json.begin_object();
    json.string("method", c.method);
    json.number("pilot_dt", c.pilot_dt);
    json.number("pilot_max_rel_energy_error", c.pilot_error);
    json.boolean("second_pilot", c.refined);
    json.number("dt", c.dt);
    // steps x stages x stage cost; null: no pilot run of it had an error below 1e-2
    json.number("predicted_cost", c.cost);
    json.end_object();
  }
  json.end_array();
  json.end_object();
}

/// The thermostat's settings (P1, src/scene: the [thermostat] table as read, or as --temperature
/// and --seed changed it): temperature a number when constant, else the [[t, kT], ...] knots.
void write_thermostat_settings(JsonWriter& json, const ThermostatSpec& th) {
  json.string("kind", th.kind);
  if (th.schedule.size() == 1 && th.schedule.front().first == 0.0) {
    json.number("temperature", th.schedule.front().second);
  } else {
    json.begin_array("temperature");
    for (const auto& [t, kT] : th.schedule) json.numbers("", std::array{t, kT});
    json.end_array();
  }
  const auto keys = thermostat_keys(th.kind);
  const auto takes = [&](std::string_view key) { return std::find(keys.begin(), keys.end(), key) != keys.end(); };
  if (takes("gamma")) json.number("gamma", th.gamma);
  if (takes("tau")) json.number("tau", th.tau);
  if (takes("chain")) json.integer("chain", th.chain);
  if (takes("seed")) json.integer("seed", static_cast<long>(th.seed));
}

/// A thermostatted run: its settings (write_thermostat_settings), then what it did: the mean
/// kinetic temperature over the rows, the configurational temperature as the ratio of the rows'
/// sums (Rugh 1997: the estimator is <|grad V|^2> / <Laplacian V>, a ratio of averages, not an
/// average of ratios), the heat the thermostat put in, and the conserved quantity over the
/// checked steps, which the energy guard judges (brownian conserves nothing: its guard is off).
void write_thermostat(JsonWriter& json, const ThermostatSpec& t, const InvariantStats& inv, const Snapshot& last) {
  json.begin_object("thermostat");
  write_thermostat_settings(json, t);
  const bool brownian = t.kind == "brownian";
  const double rows = static_cast<double>(inv.thermostat_rows);
  json.number("mean_kinetic_temperature", inv.sum_kinetic_temperature / rows);
  json.number("configurational_temperature", inv.sum_grad_squared / inv.sum_laplacian);
  json.number("final_heat", last.heat);
  json.begin_object("conserved");
  json.number("initial", inv.conserved_initial);
  json.number("final", inv.conserved_final);
  json.number("max_abs_drift", inv.max_abs_conserved_drift);
  json.end_object();
  json.string("energy_guard", brownian ? "off: overdamped dynamics conserve nothing"
                                       : "judges the conserved quantity, E + the thermostat's offset");
  json.end_object();
}

/// summary.json into json.
void write_summary_into(JsonWriter& json, const SummaryData& d) {
  const Scene& scene = d.scene;
  const InvariantStats& inv = d.invariants;
  json.begin_object();
  json.string("scene", scene.name);
  json.string("source", scene.source);
  json.boolean("complete", d.outcome.complete());
  json.string("stop_reason", stop_reason_name(d.outcome.reason));
  write_space(json, scene);
  json.integer("bodies", scene.body_count());
  {
    // The masses, for what is computed from the trajectory (sesi analyze: velocities from q, p).
    std::vector<double> masses;
    for (const Body& b : scene.bodies) masses.push_back(b.mass);
    json.numbers("masses", masses);
  }
  json.begin_array("potentials");
  for (const PotentialSpec& p : scene.potentials) json.string("", potential_kind(p));
  json.end_array();
  json.string("method", scene.integrator.method);
  json.integer("order", method_order(scene.integrator.method));
  json.number("dt", *scene.integrator.dt);
  json.integer("steps", d.outcome.steps_done);
  json.integer("planned_steps", d.planned_steps);
  json.number("t_end", *scene.integrator.t_end);
  json.integer("output_every", scene.integrator.output_every);
  json.string("trajectory", scene.integrator.trajectory_format == TrajectoryFormat::h5md ? "trajectory.h5"
                                                                                          : "trajectory.csv");
  json.number("wall_seconds", d.wall_seconds);
  // --threads (0: all cores), or fewer for a scene too small to pay for them.
  json.integer("threads_used", threads_used(scene));
  // The processes and the threads each ran with (--threads per rank; 0 resolved to the cores).
  json.integer("ranks", d.ranks);
  json.integer("threads_per_rank", sesi::parallel::threads());
  if (scene.thermostat) write_thermostat(json, *scene.thermostat, inv, d.final_state);
  if (const auto& a = scene.integrator.auto_choice) write_auto(json, *a, inv.max_rel_energy_error);

  json.begin_object("energy");
  json.number("initial", inv.energy_initial);
  json.number("final", inv.energy_final);
  json.number("max_abs_error", inv.max_abs_energy_error);
  json.number("max_rel_error", inv.max_rel_energy_error);
  json.end_object();

  json.begin_object("momentum_map");
  json.begin_array("components");
  for (const std::string& name : inv.momentum_names) json.string("", name);
  json.end_array();
  json.numbers("initial", inv.momentum_initial);
  json.numbers("final", inv.momentum_final);
  json.number("max_abs_drift", inv.max_momentum_drift);
  json.end_object();

  write_final_state(json, d.final_state);

  if (scene.space.kind == SpaceKind::hyperbolic) {
    // How far the q, p columns can be trusted (x and v are accurate at any distance).
    json.begin_object("scene_chart");
    json.number("max_distance", inv.max_distance);
    json.number("p_relative_error", scene_chart_p_error(inv.max_distance, scene.space.radius));
    json.end_object();
  }

  if (!d.exact.solution.empty()) {
    json.begin_object("exact");
    json.string("solution", d.exact.solution);
    json.numbers("max_position_error", d.exact.max_position_error);
    json.numbers("final_position_error", d.exact.final_position_error);
    json.end_object();
  }
  if (!d.outcome.complete()) {
    json.begin_object("failure");
    json.string("reason", stop_reason_name(d.outcome.reason));
    if (d.outcome.failed_step > 0) {
      json.integer("step", d.outcome.failed_step);
      json.number("t", d.outcome.failed_t);
    }
    if (d.outcome.failed_body > 0) {
      json.integer("body", d.outcome.failed_body);
    } else {
      json.null("body");
    }
    json.string("message", d.outcome.detail);
    json.end_object();
  }
  json.end_object();
}

}  // namespace

void write_summary(const SummaryData& d, const std::filesystem::path& path) {
  write_file_atomically(path, [&](std::FILE* file) {
    JsonWriter json(file);
    write_summary_into(json, d);
    return json.flush();
  });
}

}  // namespace sesi::program
