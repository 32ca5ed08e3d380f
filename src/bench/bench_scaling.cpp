#include "bench_scaling.hpp"

#include <fcntl.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include <sesi/parallel.hpp>
#include <sesi/topologies/hyperbolic_surface.hpp>

#include "bench_scaling_scenes.hpp"
#include "errors.hpp"
#include "integrator.hpp"
#include "methods.hpp"
#include "ranks.hpp"
#include "recorder.hpp"
#include "run_loop.hpp"
#include "validate.hpp"

namespace sesi::program::bench {

namespace {

/// What a child reports about one point.
struct Measured {
  double seconds_per_step = 0;
  long pairs = 0;  ///< pairs within the cutoff (all pairs for long-range terms)
  int threads = 0;
  double peak_rss_mb = 0;
};

/// One row of scaling.csv.
struct Row {
  int bodies;
  std::string space;
  int dim;
  std::string potential, method;
  Measured m;
  int stages;                   ///< force evaluations per step
  double center_distance = 0;   ///< H^n: the cluster's centre, radii from the chart origin
  std::string topology = {};    ///< "" | "box" (E^n periodic box) | "genus G" (compact surface)
};

std::string topology_label(const ScalingPoint& p) {
  return p.box ? "box" : (p.genus != 0 ? "genus " + std::to_string(p.genus) : std::string());
}

std::vector<long> parse_list(const std::string& text, const char* option, long least, long most) {
  std::vector<long> out;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    std::size_t used = 0;
    long value = 0;
    try {
      value = std::stol(item, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used == 0 || used != item.size() || value < least || value > most) {
      throw InputError(std::string(option) + ": '" + item + "' is not a whole number from " + std::to_string(least) +
                       " to " + std::to_string(most));
    }
    out.push_back(value);
  }
  if (out.empty()) throw InputError(std::string(option) + ": empty list");
  return out;
}

std::vector<double> parse_distances(const std::string& text) {
  std::vector<double> out;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    std::size_t used = 0;
    double value = -1;
    try {
      value = std::stod(item, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used == 0 || used != item.size() || !std::isfinite(value) || value < 0 || value > 30) {
      throw InputError("--center-distance: '" + item + "' is not a distance from 0 to 30 radii");
    }
    out.push_back(value);
  }
  if (out.empty()) throw InputError("--center-distance: empty list");
  return out;
}

std::vector<std::string> parse_names(const std::string& text) {
  std::vector<std::string> out;
  std::stringstream in(text);
  std::string item;
  while (std::getline(in, item, ',')) {
    if (!is_method(item)) throw InputError("--methods: unknown method '" + item + "' (see sesi methods)");
    out.push_back(item);
  }
  if (out.empty()) throw InputError("--methods: no method given");
  return out;
}

/// Seconds per step of `sesi run`'s loop on scene (default checks and cadence), timed from the
/// end of step `warm` to the end of step warm + steps inside one run of warm + steps + 1 steps:
/// set-up, the first steps and the rows at the ends stay outside the window, the checks of the
/// window inside it. Outputs go into dir.
double seconds_per_step(Scene scene, long warm, long steps, const std::filesystem::path& dir) {
  const long total = warm + steps + 1;
  scene.integrator.t_end = static_cast<double>(total) * *scene.integrator.dt;
  scene.integrator.output_every = total;
  const bool euclidean = scene.space.kind == SpaceKind::euclidean;
  Recorder recorder(scene, dir, momentum_names(euclidean ? scene.dim() : scene.dim() + 1, euclidean));
  const auto integrator = make_integrator(scene);
  std::chrono::steady_clock::time_point start, end;
  RunControl control;
  control.after_step = [&](long k) {
    if (k == warm) start = std::chrono::steady_clock::now();
    if (k == warm + steps) end = std::chrono::steady_clock::now();
  };
  const RunOutcome outcome = run_loop(scene, *integrator, recorder, control);
  if (!outcome.complete()) {
    throw std::runtime_error(outcome.detail + " at step " + std::to_string(outcome.failed_step));
  }
  return std::chrono::duration<double>(end - start).count() / static_cast<double>(steps);
}

/// Runs `measure` in a child process (its own peak memory; libgomp's threads start in it) and
/// returns what it reported. measure returns seconds per step, pairs and threads.
template <class Measure>
Measured in_child(Measure&& measure) {
  int channel[2];
  if (pipe(channel) != 0) throw std::runtime_error("sesi bench --scaling: pipe failed");
  std::fflush(nullptr);
  const pid_t pid = fork();
  if (pid < 0) throw std::runtime_error("sesi bench --scaling: fork failed");
  if (pid == 0) {
    close(channel[0]);
    std::string report;
    int status = 0;
    try {
      const Measured m = measure();
      char line[128];
      std::snprintf(line, sizeof line, "%.17g %ld %d", m.seconds_per_step, m.pairs, m.threads);
      report = line;
    } catch (const std::exception& e) {
      report = e.what();
      status = 1;
    }
    const ssize_t written = write(channel[1], report.data(), report.size());
    _exit(written == static_cast<ssize_t>(report.size()) ? status : 2);
  }
  close(channel[1]);
  std::string report;
  char buffer[256];
  for (ssize_t n; (n = read(channel[0], buffer, sizeof buffer)) > 0;) report.append(buffer, static_cast<std::size_t>(n));
  close(channel[0]);
  int status = 0;
  struct rusage usage {};
  if (wait4(pid, &status, 0, &usage) != pid) throw std::runtime_error("sesi bench --scaling: wait failed");
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    throw std::runtime_error("sesi bench --scaling: a point failed: " +
                             (report.empty() ? std::string("the child process died") : report));
  }
  Measured m;
  std::istringstream in(report);
  in >> m.seconds_per_step >> m.pairs >> m.threads;
  m.peak_rss_mb = static_cast<double>(usage.ru_maxrss) / 1024.0;  // kilobytes on Linux
  return m;
}

/// The thermostats timed against the NVE sesi2 step (issue #25): each a row whose method is
/// "sesi2+KIND", the scaling scene with a [thermostat] at the scene's own temperature (its
/// velocities have unit deviation per component: kT = 1), so that the dynamics, and with it the
/// neighbour lists' rebuilds, stay those of the NVE run.
const char* const timed_thermostats[] = {"langevin", "nose-hoover"};

ThermostatSpec thermostat_spec(const std::string& kind) {
  ThermostatSpec spec;
  spec.kind = kind;
  spec.schedule = {{0.0, 1.0}};
  spec.gamma = 1.0;  // langevin: friction 1 (LJ time units)
  spec.tau = 0.5;    // nose-hoover: relaxation time 0.5, chain 3
  spec.chain = 3;
  spec.seed = 1;
  return spec;
}

/// thermostat: "" (NVE) or a kind of timed_thermostats.
Measured measure_sesi(const ScalingPoint& point, int threads, long warm, long steps, const std::string& thermostat = {}) {
  return in_child([&] {
    sesi::parallel::set_threads(threads);
    Scene scene = scaling_scene(point);
    if (!thermostat.empty()) scene.thermostat = thermostat_spec(thermostat);
    Measured m;
    m.pairs = pairs_within(scene, point.potential == "lennard-jones" ? lj_cutoff : std::numeric_limits<double>::infinity());
    m.threads = sesi::parallel::threads();
    // The runs' outputs go to the temporary directory, so that a killed sweep leaves nothing in DIR.
    const std::filesystem::path work =
        std::filesystem::temp_directory_path() / ("sesi-scaling-" + std::to_string(getpid()));
    std::filesystem::create_directories(work);
    m.seconds_per_step = seconds_per_step(scene, warm, steps, work);
    std::filesystem::remove_all(work);
    return m;
  });
}

std::string space_label(SpaceKind kind) { return std::string(space_name(kind)); }

void write_row(std::FILE* csv, const Row& r) {
  const double pairs_per_step = static_cast<double>(r.m.pairs) * r.stages;
  std::fprintf(csv, "%d,%s,%d,%s,%s,%d,%.6g,%.6g,%.4g,%.1f,%g,%s\n", r.bodies, r.space.c_str(), r.dim,
               r.potential.c_str(), r.method.c_str(), r.m.threads, r.m.seconds_per_step, pairs_per_step,
               pairs_per_step > 0 ? r.m.seconds_per_step / pairs_per_step * 1e9 : 0.0, r.m.peak_rss_mb,
               r.center_distance, r.topology.c_str());
  std::fflush(csv);
  std::printf("  %7d bodies  %-10s %d  %-17s %-15s %d thr  %10.4g s/step  %8.1f ns/pair  %7.1f MB", r.bodies,
              r.space.c_str(), r.dim, r.potential.c_str(), r.method.c_str(), r.m.threads, r.m.seconds_per_step,
              pairs_per_step > 0 ? r.m.seconds_per_step / pairs_per_step * 1e9 : 0.0, r.m.peak_rss_mb);
  if (r.center_distance != 0) std::printf("  centre %g R away", r.center_distance);
  if (!r.topology.empty()) std::printf("  %s", r.topology.c_str());
  std::printf("\n");
  std::fflush(stdout);
}

std::string format_distance(double d) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", d);
  return text;
}

/// Exponents of time per step against N along each series, and the ratios to the references.
void print_summary(const std::vector<Row>& rows) {
  std::map<std::string, std::vector<const Row*>> series;
  for (const Row& r : rows) {
    std::string name = r.space + " " + std::to_string(r.dim) + " " + r.method + " " + std::to_string(r.m.threads) + " threads";
    if (r.center_distance != 0) name += " centre " + format_distance(r.center_distance) + " R";
    if (!r.topology.empty()) name += " " + r.topology;
    series[name].push_back(&r);
  }
  std::printf("\nexponent of seconds per step against N (log-log slope):\n");
  for (const auto& [name, s] : series) {
    if (s.size() < 2) continue;
    std::printf("  %-45s", name.c_str());
    for (std::size_t k = 1; k < s.size(); ++k) {
      std::printf(" %d-%d: %.2f", s[k - 1]->bodies, s[k]->bodies,
                  std::log(s[k]->m.seconds_per_step / s[k - 1]->m.seconds_per_step) /
                      std::log(double(s[k]->bodies) / s[k - 1]->bodies));
    }
    std::printf("  all: %.2f\n", std::log(s.back()->m.seconds_per_step / s.front()->m.seconds_per_step) /
                                     std::log(double(s.back()->bodies) / s.front()->bodies));
  }
  std::printf("\nratios per step (same N, same run):\n");
  for (const Row& r : rows) {
    if (r.space == "flat-periodic" || r.space == "lammps") continue;
    std::printf("  %7d bodies %-10s %d %-15s %d thr%s%s:", r.bodies, r.space.c_str(), r.dim, r.method.c_str(),
                r.m.threads, r.topology.empty() ? "" : " ", r.topology.c_str());
    for (const Row& q : rows) {
      if (q.bodies != r.bodies || &q == &r) continue;
      if (!r.topology.empty() || !q.topology.empty() || q.space == "lammps") {
        // issue #26: the box against LAMMPS on as many ranks as threads; a surface against the
        // box at the same N; a genus against genus 2 at the same N (so per body too).
        const bool same = q.method == r.method && q.m.threads == r.m.threads;
        if (q.space == "lammps" && r.topology == "box" && q.dim == r.dim && q.m.threads == r.m.threads) {
          std::printf("  / LAMMPS (%d ranks) %.2f", q.m.threads, r.m.seconds_per_step / q.m.seconds_per_step);
        } else if (q.space == "lammps" && r.space == "sphere" && q.dim == r.dim && q.m.threads == r.m.threads) {
          // issue #27: sesi on S^n against LAMMPS on the E^n box at the same N and density.
          std::printf("  / LAMMPS E^%d (%d ranks) %.2f", q.dim, q.m.threads, r.m.seconds_per_step / q.m.seconds_per_step);
        } else if (r.topology.starts_with("genus") && q.topology == "box" && q.dim == 2 && same) {
          std::printf("  / E^2 box %.2f", r.m.seconds_per_step / q.m.seconds_per_step);
        } else if (r.topology.starts_with("genus") && r.topology != "genus 2" && q.topology == "genus 2" && same) {
          std::printf("  / genus 2 %.2f", r.m.seconds_per_step / q.m.seconds_per_step);
        }
        continue;
      }
      if (q.space == "flat-periodic") {
        std::printf("  / flat cell list %.2f", r.m.seconds_per_step / q.m.seconds_per_step);
      } else if (q.space == "euclidean" && q.dim == 3 && q.method == r.method && q.m.threads == r.m.threads &&
                 !(r.space == "euclidean" && r.dim == 3)) {
        std::printf("  / sesi E^3 %.2f", r.m.seconds_per_step / q.m.seconds_per_step);
      } else if (r.center_distance != 0 && q.space == r.space && q.dim == r.dim && q.method == r.method &&
                 q.m.threads == r.m.threads && q.center_distance == 0) {
        std::printf("  far (%s R) / origin %.2f", format_distance(r.center_distance).c_str(),
                    r.m.seconds_per_step / q.m.seconds_per_step);
      } else if (r.method.starts_with("sesi2+") && q.method == "sesi2" && q.space == r.space && q.dim == r.dim &&
                 q.m.threads == r.m.threads && q.center_distance == 0) {
        std::printf("  / NVE sesi2 %.3f", r.m.seconds_per_step / q.m.seconds_per_step);
      }
    }
    std::printf("\n");
  }
  bool topology = false;
  for (const Row& r : rows) topology = topology || (!r.topology.empty() && r.space != "lammps");  // not S^n's LAMMPS rows
  if (!topology) return;
  std::printf("\nseconds per body-step (seconds per step / N):\n");
  for (const Row& r : rows) {
    if (r.topology.empty() && r.space != "lammps") continue;
    std::printf("  %7d bodies %-10s %d %-15s %d thr %-8s %.4g us\n", r.bodies, r.space.c_str(), r.dim,
                r.method.c_str(), r.m.threads, r.topology.c_str(), r.m.seconds_per_step / r.bodies * 1e6);
  }
}

std::vector<int> parse_genera(const std::string& text) {
  std::vector<int> out;
  for (const long g : parse_list(text, "--genus", 2, sesi::HyperbolicSurface<double>::max_genus)) {
    out.push_back(static_cast<int>(g));
  }
  return out;
}

// ---- --ranks (issue #27): threads in one process against MPI ranks ----------------------------

/// scene as a scene file that reads back to the same doubles (chart q and p, %.17g): what both
/// runs of a --ranks point read. The scaling scenes hold one Lennard-Jones term. The bodies go to
/// a CSV file beside it (`bodies = "bodies.csv"`, docs/scene-format.md): at 10^6 bodies, TOML
/// tables would cost each process ~1.6 GB to parse, more than the run.
void write_scene_file(const Scene& scene, const std::filesystem::path& path) {
  const std::filesystem::path csv_path = path.parent_path() / "bodies.csv";
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (!f) throw std::runtime_error("cannot write " + path.string());
  const auto& lj = std::get<LennardJonesSpec>(scene.potentials.at(0));
  std::fprintf(f, "name = \"%s\"\nbodies = \"bodies.csv\"\n[space]\nkind = \"%s\"\ndim = %d\nradius = %.17g\n",
               scene.name.c_str(), std::string(space_name(scene.space.kind)).c_str(), scene.space.dim,
               scene.space.radius);
  std::fprintf(f, "[[potential]]\nkind = \"lennard-jones\"\nepsilon = %.17g\nsigma = %.17g\ncutoff = %.17g\n", lj.epsilon,
               lj.sigma, lj.cutoff);
  const IntegratorSpec& in = scene.integrator;
  std::fprintf(f, "[integrator]\nmethod = \"%s\"\ndt = %.17g\nt_end = %.17g\noutput_every = %ld\nneighbour_skin = %.17g\n",
               in.method.c_str(), *in.dt, *in.t_end, in.output_every, in.neighbour_skin);
  if (in.check_every > 0) std::fprintf(f, "check_every = %ld\n", in.check_every);
  if (std::fclose(f) != 0) throw std::runtime_error("cannot write " + path.string());

  std::FILE* bodies = std::fopen(csv_path.c_str(), "w");
  if (!bodies) throw std::runtime_error("cannot write " + csv_path.string());
  std::fprintf(bodies, "mass");
  for (const char* column : {"q", "p"}) {
    for (int i = 1; i <= scene.dim(); ++i) std::fprintf(bodies, ",%s%d", column, i);
  }
  std::fprintf(bodies, "\n");
  for (const Body& b : scene.bodies) {
    std::fprintf(bodies, "%.17g", b.mass);
    for (const Eigen::VectorXd* v : {&b.q, &b.p}) {
      for (Eigen::Index k = 0; k < v->size(); ++k) std::fprintf(bodies, ",%.17g", (*v)(k));
    }
    std::fprintf(bodies, "\n");
  }
  if (std::fclose(bodies) != 0) throw std::runtime_error("cannot write " + csv_path.string());
}

/// What a child `sesi run` (or mpirun of it) gave: its exit status, the largest resident memory of
/// it and the processes it waited for (mpirun's ranks: the largest rank's), its output in log.
struct ChildRun {
  int status = -1;
  double peak_rss_mb = 0;
};

ChildRun run_child(const std::vector<std::string>& argv, const std::filesystem::path& log,
                   const std::vector<std::pair<std::string, std::string>>& env) {
  std::vector<char*> args;
  for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  // This environment with env's variables set.
  std::vector<std::string> entries;
  for (char** e = environ; *e; ++e) {
    const std::string entry = *e;
    bool replaced = false;
    for (const auto& kv : env) replaced = replaced || entry.rfind(kv.first + "=", 0) == 0;
    if (!replaced) entries.push_back(entry);
  }
  for (const auto& kv : env) entries.push_back(kv.first + "=" + kv.second);
  std::vector<char*> envp;
  for (std::string& e : entries) envp.push_back(e.data());
  envp.push_back(nullptr);
  // posix_spawn, not fork: the child never holds a copy of this process's pages, whose resident
  // size would count in its peak.
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, 1, 2);
  std::fflush(nullptr);
  pid_t pid = 0;
  const int failed = posix_spawn(&pid, args[0], &actions, nullptr, args.data(), envp.data());
  posix_spawn_file_actions_destroy(&actions);
  if (failed != 0) throw std::runtime_error("sesi bench --scaling --ranks: cannot start " + argv[0]);
  int status = 0;
  struct rusage usage {};
  if (wait4(pid, &status, 0, &usage) != pid) throw std::runtime_error("sesi bench --scaling --ranks: wait failed");
  ChildRun r;
  r.status = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + (WIFSIGNALED(status) ? WTERMSIG(status) : 0);
  r.peak_rss_mb = static_cast<double>(usage.ru_maxrss) / 1024.0;  // kilobytes on Linux
  return r;
}

/// The last line of a child's log (its error), or "".
std::string last_line(const std::filesystem::path& log) {
  std::ifstream in(log);
  std::string line, last;
  while (std::getline(in, line)) {
    if (!line.empty()) last = line;
  }
  return last;
}

/// Steps and seconds per step of a finished `sesi run --profile`: its profile.csv's row "step,all"
/// (calls = steps, wall_seconds = the steps' wall time on rank 0, set-up excluded).
std::pair<long, double> profiled_seconds_per_step(const std::filesystem::path& run_dir) {
  std::ifstream in(run_dir / "profile.csv");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("step,all,", 0) != 0) continue;
    std::istringstream cells(line.substr(9));
    std::string calls, wall;
    std::getline(cells, calls, ',');
    std::getline(cells, wall, ',');
    const long steps = std::stol(calls);
    if (steps > 0) return {steps, std::stod(wall) / static_cast<double>(steps)};
  }
  throw std::runtime_error("no step row in " + (run_dir / "profile.csv").string());
}

std::string file_bytes(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

int ranks_scaling(const BenchOptions& o) {
  // What a run across ranks takes (src/domain/domain_integrator.hpp), on the scene the issue's
  // target names: S^2 Lennard-Jones.
  if (o.space != "sphere" || o.dim != 2 || o.potential != "lennard-jones") {
    throw InputError("--ranks: on --space sphere --dim 2 --potential lennard-jones only");
  }
  if (o.box || !o.genera.empty() || !o.center_distances.empty()) {
    throw InputError("--ranks: not with --box, --genus or --center-distance");
  }
  if (o.repeats < 0 || o.repeats > 100) throw InputError("--repeats: from 1 to 100");
  if (o.check_every < 0) throw InputError("--check-every: must be >= 1 (or 0, the default cadence)");
  if (!(o.skin >= 0 && o.skin <= 1)) throw InputError("--skin: a number from 0 to 1");
  if (o.steps < 0) throw InputError("--steps: must be > 0");
  const std::vector<long> sizes = parse_list(o.sizes.empty() ? "100000" : o.sizes, "--n", 256, 10'000'000);
  const std::vector<long> counts = parse_list(o.threads.empty() ? "2" : o.threads, "--threads", 2, 1024);
  const std::vector<std::string> methods = parse_names(o.methods.empty() ? "sesi2" : o.methods);
  for (const std::string& method : methods) {
    if (is_embedded_method(method) || find_method_info(method)->output_stages > 0) {
      throw InputError("--methods: '" + method + "' does not run across ranks; take a sesi method that is not processed");
    }
  }
  if (!Ranks::available()) {
    throw InputError("--ranks: this sesi is built without MPI (SESI_BUILD_MPI; Debian: libopenmpi-dev openmpi-bin)");
  }
  const std::string mpirun = on_path("mpirun");
  if (mpirun.empty()) throw InputError("--ranks: no mpirun on PATH (Debian: openmpi-bin)");
  const std::string self = std::filesystem::read_symlink("/proc/self/exe").string();
  const int rounds = o.repeats > 0 ? o.repeats : 1;

  const std::filesystem::path dir = o.out.empty() ? "sesi-out/bench/scaling" : o.out;
  std::filesystem::create_directories(dir);
  const std::filesystem::path path = dir / "ranks.csv", partial = dir / "ranks.csv.partial";
  std::FILE* csv = std::fopen(partial.c_str(), "w");
  if (!csv) throw std::runtime_error("cannot write " + partial.string());
  std::fprintf(csv, "# sesi bench --scaling --ranks (issue #27; docs/parallel.md): S^2 Lennard-Jones at density 1/2 "
                    "(the scenes of --scaling), one scene file per N read by both runs\n");
  std::fprintf(csv, "# ranks = 1: sesi run --threads T; ranks = T: mpirun -np T sesi run --threads 1\n");
  std::fprintf(csv, "# seconds_per_step: the run's profile.csv (sesi run --profile), its steps' wall time on rank 0 "
                    "over the steps (scene reading and set-up excluded)%s\n",
               rounds > 1 ? ", minimum over the rounds" : "");
  std::fprintf(csv, "# peak_rss_mb: the largest resident memory of the process (mpirun: of its largest rank)\n");
  std::fprintf(csv, "# identical: trajectory.csv and diagnostics.csv of the two runs equal byte for byte\n");
#ifdef NDEBUG
  std::fprintf(csv, "# build: optimised (NDEBUG)\n");
#else
  std::fprintf(csv, "# build: NOT optimised (no NDEBUG): timings are not representative\n");
#endif
  std::fprintf(csv, "n_bodies,method,ranks,threads_per_rank,steps,seconds_per_step,peak_rss_mb,identical\n");
  std::printf("sesi bench --scaling --ranks: sphere, dim 2, lennard-jones; threads against MPI ranks (%s)\n",
              mpirun.c_str());

  // Open MPI's switches as environment variables, which other MPIs ignore: run as root (containers),
  // and more ranks than cores (the target's machine has two).
  std::vector<std::pair<std::string, std::string>> env = {{"OMPI_MCA_rmaps_base_oversubscribe", "1"}};
  if (geteuid() == 0) {
    env.emplace_back("OMPI_ALLOW_RUN_AS_ROOT", "1");
    env.emplace_back("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1");
  }
  const std::filesystem::path work =
      std::filesystem::temp_directory_path() / ("sesi-scaling-ranks-" + std::to_string(getpid()));
  std::filesystem::remove_all(work);
  std::filesystem::create_directories(work);
  bool all_identical = true;
  std::vector<std::string> ratios;
  try {
    for (const long n : sizes) {
      // About a second's worth of steps per run, as the other --scaling points (at least 40).
      const long steps = o.steps > 0 ? o.steps : std::max(40L, std::min(20000L, std::lround(2e6 / static_cast<double>(n))));
      for (const std::string& method : methods) {
        ScalingPoint point;
        point.bodies = static_cast<int>(n);
        point.method = method;
        point.check_every = o.check_every;
        point.neighbour_skin = o.skin;
        Scene scene = scaling_scene(point);
        // A first and a last output row only: the outputs compared stay small.
        scene.integrator.t_end = static_cast<double>(steps) * *scene.integrator.dt;
        scene.integrator.output_every = steps;
        const std::filesystem::path file = work / "scene.toml";
        write_scene_file(scene, file);
        scene = Scene{};  // not held while the children run
        for (const long t : counts) {
          struct Timed {
            long ranks, threads;
            std::filesystem::path out;
            long steps = 0;
            double seconds = 0, peak = 0;
          };
          Timed runs[2] = {{1, t, work / "threads"}, {t, 1, work / "ranks"}};
          for (int round = 0; round < rounds; ++round) {
            for (Timed& r : runs) {
              std::filesystem::remove_all(r.out);
              std::vector<std::string> argv;
              if (r.ranks > 1) argv = {mpirun, "-np", std::to_string(r.ranks)};
              argv.insert(argv.end(), {self, "run", file.string(), "--threads", std::to_string(r.threads), "--out",
                                       r.out.string(), "--quiet", "--profile"});
              const std::filesystem::path log = work / "log.txt";
              const ChildRun child = run_child(argv, log, env);
              if (child.status != 0) {
                throw std::runtime_error("sesi bench --scaling --ranks: " +
                                         std::string(r.ranks > 1 ? "mpirun -np " + std::to_string(r.ranks) + " " : "") +
                                         "sesi run --threads " + std::to_string(r.threads) + " failed (exit status " +
                                         std::to_string(child.status) + "): " + last_line(log));
              }
              const auto [timed_steps, seconds] = profiled_seconds_per_step(r.out);
              if (round == 0 || seconds < r.seconds) r.seconds = seconds;
              r.peak = round == 0 ? child.peak_rss_mb : std::min(r.peak, child.peak_rss_mb);
              r.steps = timed_steps;
            }
          }
          bool identical = true;
          for (const char* name : {"trajectory.csv", "diagnostics.csv"}) {
            identical = identical && file_bytes(runs[0].out / name) == file_bytes(runs[1].out / name);
          }
          all_identical = all_identical && identical;
          for (const Timed& r : runs) {
            std::fprintf(csv, "%ld,%s,%ld,%ld,%ld,%.6g,%.1f,%s\n", n, method.c_str(), r.ranks, r.threads, r.steps,
                         r.seconds, r.peak, identical ? "yes" : "no");
            std::printf("  %7ld bodies  %-8s %3ld rank%s x %3ld thread%s  %10.4g s/step  %8.1f MB%s\n", n, method.c_str(),
                        r.ranks, r.ranks > 1 ? "s" : " ", r.threads, r.threads > 1 ? "s" : " ", r.seconds, r.peak,
                        r.ranks > 1 ? " (largest rank)" : "");
          }
          std::fflush(csv);
          char line[256];
          std::snprintf(line, sizeof line,
                        "  %7ld bodies %-8s %ld ranks x 1 thread / 1 rank x %ld threads: time per step %.3f, peak memory "
                        "per process %.3f; outputs %s",
                        n, method.c_str(), t, t, runs[1].seconds / runs[0].seconds, runs[1].peak / runs[0].peak,
                        identical ? "identical" : "DIFFER");
          ratios.emplace_back(line);
          std::printf("%s\n", line);
          std::fflush(stdout);
        }
      }
    }
  } catch (...) {
    std::fclose(csv);
    std::filesystem::remove(partial);
    std::filesystem::remove_all(work);
    throw;
  }
  std::filesystem::remove_all(work);
  const bool ok = std::fclose(csv) == 0;
  if (!ok || std::rename(partial.c_str(), path.c_str()) != 0) throw std::runtime_error("cannot write " + path.string());
  std::printf("\nranks against threads (issue #27 targets on two cores: time per step <= 1.15 at 10^5 bodies, peak memory "
              "per process <= 0.6 at 10^6):\n");
  for (const std::string& line : ratios) std::printf("%s\n", line.c_str());
  std::printf("\nwrote %s\n", path.c_str());
  if (!all_identical) {
    std::fprintf(stderr, "sesi: error: the outputs on ranks differ from one process's (a bug: docs/parallel.md)\n");
    return 1;
  }
  return 0;
}

}  // namespace

int scaling_command(const BenchOptions& o) {
  if (o.ranks) return ranks_scaling(o);
  ScalingPoint base;
  if (o.space == "sphere") {
    base.space = SpaceKind::sphere;
  } else if (o.space == "hyperbolic") {
    base.space = SpaceKind::hyperbolic;
  } else if (o.space == "euclidean") {
    base.space = SpaceKind::euclidean;
  } else {
    throw InputError("--space: sphere, hyperbolic or euclidean, not '" + o.space + "'");
  }
  if (o.dim < 1 || o.dim > 16) throw InputError("--dim: from 1 to 16, not " + std::to_string(o.dim));
  base.dim = o.dim;
  if (o.potential != "lennard-jones" && o.potential != "cotangent-gravity") {
    throw InputError("--potential: lennard-jones or cotangent-gravity, not '" + o.potential + "'");
  }
  base.potential = o.potential;
  const std::vector<double> distances = parse_distances(o.center_distances.empty() ? "0" : o.center_distances);
  // Topologies (issue #26): --box on E^n, --genus on H^2; Lennard-Jones only (the program refuses
  // long-range terms on a quotient), chart methods only (it refuses the embedding methods there).
  const std::vector<int> genera = o.genera.empty() ? std::vector<int>{} : parse_genera(o.genera);
  if (o.box && base.space != SpaceKind::euclidean) throw InputError("--box: only on --space euclidean");
  if (!genera.empty() && (base.space != SpaceKind::hyperbolic || base.dim != 2)) {
    throw InputError("--genus: only on --space hyperbolic --dim 2");
  }
  const bool topology = o.box || !genera.empty();
  if (topology && base.potential != "lennard-jones") {
    throw InputError("--box, --genus: with --potential lennard-jones only (no long-range terms on a topology)");
  }
  if (topology && (distances.size() != 1 || distances[0] != 0)) {
    throw InputError("--center-distance: not with --genus (the bodies fill the surface)");
  }
  if (base.space != SpaceKind::hyperbolic && (distances.size() != 1 || distances[0] != 0)) {
    throw InputError("--center-distance: only on --space hyperbolic");
  }
  if (o.repeats < 0 || o.repeats > 100) throw InputError("--repeats: from 1 to 100");
  const int rounds = o.repeats > 0 ? o.repeats : 1;
  if (o.check_every < 0) throw InputError("--check-every: must be >= 1 (or 0, the default cadence)");
  if (!(o.skin >= 0 && o.skin <= 1)) throw InputError("--skin: a number from 0 to 1");
  const std::vector<long> sizes = parse_list(o.sizes.empty() ? default_sizes : o.sizes, "--n", 2, 10'000'000);
  const std::vector<long> threads = parse_list(o.threads.empty() ? "0" : o.threads, "--threads", 0, 1024);
  const std::vector<std::string> methods = parse_names(o.methods.empty() ? "sesi2" : o.methods);
  for (const std::string& method : methods) {
    if (topology && is_embedded_method(method)) {
      throw InputError("--methods: '" + method + "' does not run on a topology (--box, --genus); take a sesi method");
    }
    if (base.space == SpaceKind::euclidean && is_embedded_method(method)) {
      throw InputError("--methods: '" + method + "' runs on curved spaces only (--space sphere or hyperbolic)");
    }
  }
  const bool lj = base.potential == "lennard-jones";
  if (o.steps < 0) throw InputError("--steps: must be > 0");
  const long warm = lj ? 20 : 1;
  // LAMMPS rows: with --box on the same bodies (issue #26); on S^2 and S^3 on the E^n box at the
  // same N and density, the flat system a LAMMPS user would run (issue #27).
  const bool sphere_lammps = lj && !topology && base.space == SpaceKind::sphere && (base.dim == 2 || base.dim == 3);
  const bool lammps = !o.no_lammps && (o.box || sphere_lammps);
  std::set<std::string> lammps_reported;  // each reason for leaving LAMMPS rows out, printed once

  const std::filesystem::path dir = o.out.empty() ? "sesi-out/bench/scaling" : o.out;
  std::filesystem::create_directories(dir);
  const std::filesystem::path path = dir / "scaling.csv", partial = dir / "scaling.csv.partial";
  std::FILE* csv = std::fopen(partial.c_str(), "w");
  if (!csv) throw std::runtime_error("cannot write " + partial.string());
  std::fprintf(csv, "# sesi bench --scaling (issue #11; docs/benchmarks.md)\n");
  std::fprintf(csv,
               "# seconds_per_step: sesi run's loop (default checks and cadence) timed over steps %ld to %ld + S of "
               "one run (S: --steps, default about a second's worth), so set-up and the end rows stay out; "
               "flat-periodic: a plain 3-D LJ cell-list loop, velocity Verlet, one thread\n",
               warm + 1, warm);
  std::fprintf(csv, "# pairs_per_step: pairs within the cutoff (all pairs for gravity) x force evaluations per step\n");
  std::fprintf(csv, "# sesi2+langevin, sesi2+nose-hoover (with sesi2): the sesi2 step with a thermostat's stages (issue #25; "
                    "kT = 1, the scene's; langevin gamma = 1; nose-hoover tau = 0.5, chain 3), timed like the NVE rows\n");
  if (topology) {
    std::fprintf(csv, "# topology (issue #26): box = a periodic box of E^n, genus G = the compact surface of H^2 at the same "
                      "density; lammps rows: LAMMPS (lmp, mpirun -np threads) on the box's bodies, its own Loop time per "
                      "step (peak_rss_mb not measured)\n");
  }
  if (lammps && sphere_lammps) {
    std::fprintf(csv, "# lammps rows (issue #27): LAMMPS (lmp; mpirun -np threads) on a periodic box of E^%d with the "
                      "same N and density 1/2 (the bodies of --box), the same Lennard-Jones (cutoff 2.5, shifted), skin "
                      "(cutoff x neighbour_skin), dt and velocity Verlet; its own Loop time per step (peak_rss_mb not "
                      "measured); the summary prints sesi S^%d / LAMMPS E^%d at the same N and threads = ranks\n",
                 base.dim, base.dim, base.dim);
  }
  if (rounds > 1) {
    std::fprintf(csv, "# seconds_per_step and peak_rss_mb: minimum over %d rounds, each round timing every point of an N "
                 "once in turn\n", rounds);
  }
  if (o.check_every > 0) std::fprintf(csv, "# check_every = %ld (not sesi run's default)\n", o.check_every);
  if (o.skin != sesi::default_skin_fraction) std::fprintf(csv, "# neighbour_skin = %g (not sesi run's default)\n", o.skin);
#ifdef NDEBUG
  std::fprintf(csv, "# build: optimised (NDEBUG)\n");
#else
  std::fprintf(csv, "# build: NOT optimised (no NDEBUG): timings are not representative\n");
#endif
  std::fprintf(csv, "n_bodies,space,dim,potential,method,threads,seconds_per_step,pairs_per_step,ns_per_pair,peak_rss_mb,"
                    "center_distance,topology\n");

  std::printf("sesi bench --scaling: %s, dim %d, %s\n", o.space.c_str(), base.dim, base.potential.c_str());
  if (o.no_lammps && (o.box || sphere_lammps)) std::printf("  LAMMPS rows left out: --no-lammps\n");
  std::vector<Row> rows;
  const bool flat3 = base.space == SpaceKind::euclidean && base.dim == 3;
  for (const long n : sizes) {
    // Enough steps for about a second per point: the time per step is ~ N (Lennard-Jones) or
    // ~ N^2 (gravity), about 1 s for 2 10^6 / N steps of Lennard-Jones and 2 10^8 / N^2 of gravity.
    const double scale = lj ? 2e6 / static_cast<double>(n) : 2e8 / (static_cast<double>(n) * static_cast<double>(n));
    const long steps = o.steps > 0 ? o.steps : std::max(lj ? 40L : 4L, std::min(20000L, std::lround(scale)));
    // The points of this N, in the order they are timed; every round times each once, so that a
    // slow spell of the machine falls on all of them, and a row keeps its fastest round.
    struct Point {
      Row row;             ///< what is written; its time the fastest round's
      ScalingPoint scene;  ///< unused for the flat cell-list loop
      int threads;         ///< asked for (0: all cores)
      std::string thermostat = {};  ///< "" (NVE) or a kind of timed_thermostats
      bool dropped = false;         ///< a LAMMPS row without LAMMPS (or whose run failed)
    };
    std::vector<Point> points;
    for (const std::string& method : methods) {
      const int stages = find_method_info(method)->stages;
      for (const long t : threads) {
        ScalingPoint point = base;
        point.bodies = static_cast<int>(n);
        point.check_every = o.check_every;
        point.neighbour_skin = o.skin;
        point.method = method;
        if (topology) {
          // issue #26: the box (with LAMMPS rows below), or each genus and the E^2 box at the same N.
          const auto add = [&](const ScalingPoint& q) {
            points.push_back({{q.bodies, space_label(q.space), q.dim, q.potential, method, Measured{}, stages, 0,
                               topology_label(q)},
                              q, static_cast<int>(t)});
          };
          if (o.box) {
            point.box = true;
            add(point);
            continue;
          }
          for (const int g : genera) {
            point.genus = g;
            add(point);
          }
          ScalingPoint flat = base;
          flat.bodies = point.bodies;
          flat.check_every = point.check_every;
          flat.neighbour_skin = point.neighbour_skin;
          flat.method = method;
          flat.space = SpaceKind::euclidean;
          flat.dim = 2;
          flat.box = true;
          add(flat);
          continue;
        }
        for (const double d : distances) {
          point.center_distance = d;
          points.push_back({{point.bodies, space_label(point.space), point.dim, point.potential, method,
                             Measured{}, stages, d},
                            point, static_cast<int>(t)});
        }
        // The thermostats against the NVE sesi2 step, timed in the same rounds (distance 0).
        if (method == "sesi2") {
          ScalingPoint origin = point;
          origin.center_distance = 0;
          for (const char* kind : timed_thermostats) {
            points.push_back({{point.bodies, space_label(point.space), point.dim, point.potential,
                               method + "+" + kind, Measured{}, stages, 0},
                              origin, static_cast<int>(t), kind});
          }
        }
        // The same bodies' count and density on flat E^3, through sesi (not for a geodesic
        // method, which runs on S^n and H^n only).
        if (!flat3 && !is_embedded_method(method)) {
          ScalingPoint flat = point;
          flat.space = SpaceKind::euclidean;
          flat.dim = 3;
          flat.center_distance = 0;
          points.push_back({{flat.bodies, "euclidean", 3, flat.potential, method,
                             Measured{}, stages, 0},
                            flat, static_cast<int>(t)});
        }
      }
    }
    if (lj && !topology) {
      points.push_back({{static_cast<int>(n), "flat-periodic", 3, "lennard-jones", "velocity-verlet",
                         Measured{}, 1, 0},
                        ScalingPoint{}, 1});
    }
    if (lammps) {
      // LAMMPS on the E^n box of these N bodies (with --box the very bodies of the sesi rows), as
      // many MPI ranks as sesi's threads; sesi's skin, dt and Lennard-Jones (lammps_seconds_per_step).
      for (const long t : threads) {
        ScalingPoint point = base;
        point.space = SpaceKind::euclidean;
        point.bodies = static_cast<int>(n);
        point.neighbour_skin = o.skin;
        point.box = true;
        points.push_back({{point.bodies, "lammps", point.dim, "lennard-jones", "velocity-verlet", Measured{}, 1, 0,
                           "box"},
                          point, static_cast<int>(t)});
      }
    }
    for (int round = 0; round < rounds; ++round) {
      for (Point& p : points) {
        if (p.dropped) continue;
        if (p.row.space == "lammps") {
          // Threads 0 (all cores): as many ranks as the sesi rows' threads (sesi's default count;
          // this process never sets it).
          const int ranks = p.threads > 0 ? p.threads : std::max(1, sesi::parallel::threads());
          const std::string missing = lammps_unavailable(ranks);
          if (!missing.empty()) {
            if (lammps_reported.insert(missing).second) std::printf("  LAMMPS rows left out: %s\n", missing.c_str());
            p.dropped = true;
            continue;
          }
          // In a child process, as the sesi points: the box's scene is not left in this
          // process's memory, which the later points' children would count as theirs.
          Measured m;
          try {
            m = in_child([&] {
              const Scene scene = scaling_scene(p.scene);
              std::string why;
              const std::optional<double> seconds = lammps_seconds_per_step(scene, ranks, warm, steps, why);
              if (!seconds) throw std::runtime_error(why);
              Measured out;
              out.seconds_per_step = *seconds;
              out.threads = ranks;
              out.pairs = pairs_within(scene, lj_cutoff);
              return out;
            });
          } catch (const std::runtime_error& e) {
            std::printf("  no LAMMPS row at %d bodies, %d ranks: %s\n", p.row.bodies, ranks, e.what());
            p.dropped = true;
            continue;
          }
          m.peak_rss_mb = 0;  // that of the child, not of LAMMPS: not measured
          if (round == 0 || m.seconds_per_step < p.row.m.seconds_per_step) p.row.m = m;
          continue;
        }
        const Measured m = p.row.space == "flat-periodic" ? in_child([&] {
          Measured out;
          out.threads = 1;
          out.seconds_per_step = flat_cell_list_seconds_per_step(static_cast<int>(n), steps, out.pairs);
          return out;
        })
                                                           : measure_sesi(p.scene, p.threads, warm, steps, p.thermostat);
        const double peak = round == 0 ? m.peak_rss_mb : std::min(p.row.m.peak_rss_mb, m.peak_rss_mb);
        if (round == 0 || m.seconds_per_step < p.row.m.seconds_per_step) p.row.m = m;
        p.row.m.peak_rss_mb = peak;
      }
    }
    for (const Point& p : points) {
      if (p.dropped) continue;
      rows.push_back(p.row);
      write_row(csv, rows.back());
    }
  }
  const bool ok = std::fclose(csv) == 0;
  if (!ok || std::rename(partial.c_str(), path.c_str()) != 0) throw std::runtime_error("cannot write " + path.string());
  print_summary(rows);
  std::printf("\nwrote %s (%zu rows); plot: /usr/bin/python3 tools/plot_scaling.py %s\n", path.c_str(), rows.size(),
              dir.c_str());
  return 0;
}

}  // namespace sesi::program::bench
