#include "analyze_command.hpp"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <vector>

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include "analysis.hpp"
#include "csv_writer.hpp"
#include "errors.hpp"
#include "output_dir.hpp"

extern char** environ;

namespace sesi::program {

namespace fs = std::filesystem;

namespace {

/// The pictures, drawn by matplotlib as the project's other figures are (tools/): argv is
/// rdf.csv msd.csv vacf.csv-or-"" rdf-picture msd-picture title saturation-or-"nan".
/// Exit status 3: no matplotlib.
constexpr const char* picture_script = R"PY(
import csv, math, sys
try:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
except ImportError:
    sys.exit(3)
rdf, msd, vacf, rdf_png, msd_png, title, saturation = sys.argv[1:8]
def columns(path):
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    return {name: [float(r[k]) for r in rows[1:]] for k, name in enumerate(rows[0])}
g = columns(rdf)
fig, ax = plt.subplots(figsize=(6.4, 4.2))
ax.plot(g["r"], g["g"], color="C0", linewidth=1.4)
ax.axhline(1.0, color="grey", linewidth=0.6, linestyle="--")
ax.set_xlabel("geodesic distance r")
ax.set_ylabel("g(r)")
ax.set_title(title + ": g(r)")
fig.tight_layout()
fig.savefig(rdf_png, format="png", dpi=120)
m = columns(msd)
panels = 2 if vacf else 1
fig, axes = plt.subplots(1, panels, figsize=(6.4 * panels, 4.2), squeeze=False)
ax = axes[0][0]
ax.plot(m["t"], m["msd"], color="C1", linewidth=1.4, label="MSD")
if saturation != "nan":
    ax.axhline(float(saturation), color="grey", linewidth=0.6, linestyle="--",
               label="uniform points' mean squared distance")
    ax.legend()
ax.set_xlabel("lag t")
ax.set_ylabel("mean squared geodesic displacement")
ax.set_title(title + ": MSD")
if vacf:
    v = columns(vacf)
    ax = axes[0][1]
    ax.plot(v["t"], v["vacf_normalised"], color="C2", linewidth=1.4)
    ax.axhline(0.0, color="grey", linewidth=0.6)
    ax.set_xlabel("lag t")
    ax.set_ylabel("VACF / VACF(0)")
    ax.set_title(title + ": velocity autocorrelation")
fig.tight_layout()
fig.savefig(msd_png, format="png", dpi=120)
)PY";

/// python3: Debian's (it has python3-matplotlib) when there, else the first in PATH.
std::string python3() { return ::access("/usr/bin/python3", X_OK) == 0 ? "/usr/bin/python3" : "python3"; }

/// Runs the picture script; its exit status, or -1 when python3 cannot be started.
int draw(const std::vector<std::string>& script_args) {
  std::vector<std::string> args = {python3(), "-c", picture_script};
  args.insert(args.end(), script_args.begin(), script_args.end());
  std::vector<char*> argv;
  for (std::string& arg : args) argv.push_back(arg.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  pid_t pid = 0;
  const int error = posix_spawnp(&pid, argv[0], &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (error != 0) return -1;
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) return -1;
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

/// A CSV file written under NAME.tmp and renamed into place.
void write_csv(const fs::path& path, const std::vector<std::string>& header,
               const std::vector<std::vector<double>>& rows) {
  const fs::path temporary = path.string() + ".tmp";
  {
    CsvWriter csv(temporary, header);
    for (const auto& row : rows) csv.row(row);
    csv.close();
  }
  std::error_code ec;
  fs::rename(temporary, path, ec);
  if (ec) throw std::runtime_error("cannot write " + path.string() + ": " + ec.message());
}

}  // namespace

CLI::App* add_analyze_subcommand(CLI::App& app, AnalyzeOptions& options) {
  CLI::App* a = app.add_subcommand(
      "analyze", "The observables of a finished run from its outputs: g(r), MSD, velocity autocorrelation.");
  a->add_option("DIR", options.dir, "A finished run's output directory (trajectory.csv or trajectory.h5).")
      ->type_name("DIR")
      ->required();
  a->add_option("--rdf-max", options.rdf_max,
                "Largest geodesic distance of g(r) (default: pi R on S^n, the largest allowed cutoff on a periodic "
                "box or compact surface (also the most it may be), elsewhere a quarter of the bodies' extent in the "
                "first frame read; at most ten mean spacings (V/N)^(1/n)).")
      ->type_name("R");
  a->add_option("--bins", options.bins, "Bins of g(r) over [0, R), 1 to 10^6 (default 100).")->type_name("N");
  a->add_option("--from", options.from, "First time read (default: the first frame).")->type_name("T");
  a->add_option("--to", options.to, "Last time read (default: the last frame).")->type_name("T");
  a->add_option("--every", options.every, "Read every K-th frame of those, >= 1 (default 1).")->type_name("K");
  a->add_option("--max-lag", options.max_lag,
                "Longest lag of the MSD and VACF in frames read, >= 0 (default: half the frames).")
      ->type_name("L");
  a->add_flag("--no-picture", [&options](std::int64_t) { options.picture = false; },
              "Write no pictures (rdf.png, msd.png).");
  a->add_flag("--quiet,-q", options.quiet, "No report on stdout.");
  a->footer(
      "\nWrites into DIR, beside the run's outputs (and into its manifest, so a run repeated into DIR\n"
      "replaces them): rdf.csv (r_lo, r_hi, r, g, count, expected), msd.csv (lag, t, msd, samples),\n"
      "vacf.csv (lag, t, vacf, vacf_normalised, samples), per_body.csv (body, msd, mean_speed2), and\n"
      "rdf.png, msd.png (with python3-matplotlib). Definitions and normalisation: docs/observables.md.\n"
      "\nEXIT STATUS:\n"
      "  0 done;  2 bad argument, or DIR is not a finished sesi run (one line on stderr, nothing\n"
      "    written);  1 other failure (e.g. a write error).\n");
  return a;
}

int analyze_command(const AnalyzeOptions& options) {
  if (options.dir.empty()) throw InputError(Origin{}, "DIR", "expected a directory, got an empty path");
  fs::path dir = options.dir;
  if (dir.filename().empty() && dir.has_relative_path()) dir = dir.parent_path();
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) {
    throw InputError(Origin{dir.string()}, "", "not a directory (expected a finished sesi run's output directory)");
  }
  if (options.every < 1) throw InputError(Origin{}, "--every", "expected a whole number >= 1, got " + std::to_string(options.every));
  if (options.max_lag && *options.max_lag < 0) {
    throw InputError(Origin{}, "--max-lag", "expected a whole number >= 0, got " + std::to_string(*options.max_lag));
  }
  for (const auto& [key, value] : {std::pair{"--from", options.from}, std::pair{"--to", options.to}}) {
    if (value && !std::isfinite(*value)) throw InputError(Origin{}, key, "expected a finite time");
  }
  // No run may replace DIR while its observables are written into it.
  DirLock lock;
  lock_output_dir(lock, fs::absolute(dir, ec).lexically_normal(), dir.string());
  const analysis::RunInfo info = analysis::read_run_info(dir);
  if (!has_manifest(dir)) {
    throw InputError(Origin{dir.string()}, "", "has no sesi-manifest.txt: not the outputs of this sesi");
  }

  analysis::ReadOptions read;
  if (options.from) read.from = *options.from;
  if (options.to) read.to = *options.to;
  read.every = options.every;
  const analysis::Frames frames = analysis::read_frames(dir, info, read);
  const SpaceSpec& space = info.space;

  const double r_max = options.rdf_max ? *options.rdf_max : analysis::default_rdf_max(space, frames.x.front());
  analysis::Rdf rdf(space, r_max, options.bins);
  const bool velocities = frames.v.size() == frames.x.size();
  const std::vector<std::string> csvs = velocities ? std::vector<std::string>{"rdf.csv", "msd.csv", "vacf.csv", "per_body.csv"}
                                                   : std::vector<std::string>{"rdf.csv", "msd.csv", "per_body.csv"};
  std::vector<std::string> names = csvs;
  if (options.picture) names.insert(names.end(), {"rdf.png", "msd.png"});
  for (const std::string& name : names) {
    if (fs::exists(fs::symlink_status(dir / name, ec)) && !manifest_lists(dir, name)) {
      throw InputError(Origin{dir.string()}, "",
                       "holds " + name + ", which sesi did not write; move it away to analyse this run here");
    }
  }

  for (const Eigen::MatrixXd& x : frames.x) rdf.accumulate(x);
  const long max_lag = options.max_lag ? *options.max_lag : -1;
  const analysis::Correlation m = analysis::msd(frames, max_lag);
  analysis::Correlation v;
  if (velocities) v = analysis::vacf(frames, max_lag);

  // In the manifest first: a file that appears is then always one a rerun into DIR replaces.
  add_to_manifest(dir, names);
  {
    const std::vector<double> e = rdf.edges(), c = rdf.centers(), g = rdf.g();
    std::vector<std::vector<double>> rows;
    for (int k = 0; k < rdf.bins(); ++k) {
      const auto s = static_cast<std::size_t>(k);
      rows.push_back({e[s], e[s + 1], c[s], g[s], static_cast<double>(rdf.counts()[s]), rdf.expected()[s]});
    }
    write_csv(dir / "rdf.csv", {"r_lo", "r_hi", "r", "g", "count", "expected"}, rows);
  }
  {
    std::vector<std::vector<double>> rows;
    for (std::size_t k = 0; k < m.value.size(); ++k) {
      rows.push_back({static_cast<double>(k), m.lag_time[k], m.value[k], static_cast<double>(m.samples[k])});
    }
    write_csv(dir / "msd.csv", {"lag", "t", "msd", "samples"}, rows);
  }
  if (velocities) {
    std::vector<std::vector<double>> rows;
    for (std::size_t k = 0; k < v.value.size(); ++k) {
      rows.push_back({static_cast<double>(k), v.lag_time[k], v.value[k], v.value[k] / v.value.front(),
                      static_cast<double>(v.samples[k])});
    }
    write_csv(dir / "vacf.csv", {"lag", "t", "vacf", "vacf_normalised", "samples"}, rows);
  }
  {
    // Per body: the MSD at the longest lag and the mean squared speed (the VACF at lag 0).
    const analysis::Correlation speed = velocities ? analysis::vacf(frames, 0) : analysis::Correlation{};
    std::vector<std::vector<double>> rows;
    for (int b = 0; b < frames.bodies(); ++b) {
      const auto s = static_cast<std::size_t>(b);
      rows.push_back({static_cast<double>(b + 1), m.per_body_last[s],
                      velocities ? speed.per_body_last[s] : std::nan("")});
    }
    write_csv(dir / "per_body.csv", {"body", "msd", "mean_speed2"}, rows);
  }
  const double saturation = analysis::msd_saturation(space);
  bool pictures = false;
  if (options.picture) {
    std::string title = std::string(space_name(space.kind)) + " dim " + std::to_string(space.dim);
    if (!space.box.empty()) title += ", periodic box";
    if (space.genus != 0) title += ", genus " + std::to_string(space.genus);
    const fs::path rdf_tmp = dir / "rdf.png.tmp", msd_tmp = dir / "msd.png.tmp";
    const int status = draw({(dir / "rdf.csv").string(), (dir / "msd.csv").string(),
                             velocities ? (dir / "vacf.csv").string() : std::string(), rdf_tmp.string(),
                             msd_tmp.string(), title, std::isnan(saturation) ? "nan" : format_number(saturation)});
    if (status == 0) {
      fs::rename(rdf_tmp, dir / "rdf.png", ec);
      if (!ec) fs::rename(msd_tmp, dir / "msd.png", ec);
      pictures = !ec;
    }
    fs::remove(rdf_tmp, ec);
    fs::remove(msd_tmp, ec);
    if (!pictures) {
      std::fprintf(stderr, "sesi: warning: no pictures: %s\n",
                   status == 3    ? "matplotlib is missing (Debian: python3-matplotlib)"
                   : status == -1 ? "python3 cannot be started"
                                  : "the picture script failed");
    }
  }
  if (!options.quiet) {
    std::printf("%s: %zu frames from t = %s to %s, %d bodies\n", dir.string().c_str(), frames.t.size(),
                format_number(frames.t.front()).c_str(), format_number(frames.t.back()).c_str(), frames.bodies());
    std::printf("  rdf.csv   g(r) over [0, %s) in %d bins, %ld shell centres", format_number(r_max).c_str(),
                options.bins, rdf.centres());
    if (space.has_topology()) {
      std::printf(" (minimum image on this %s; largest allowed cutoff %s)", space.box.empty() ? "surface" : "box",
                  format_number(analysis::max_cutoff(space)).c_str());
    }
    std::printf("\n  msd.csv   lags 0 to %zu frames", m.value.size() - 1);
    if (space.has_topology()) {
      std::printf(" of the unwrapped positions (%s)", space.box.empty() ? "words" : "image counts");
    }
    if (!std::isnan(saturation)) std::printf("; saturates at %s on this sphere", format_short(saturation).c_str());
    std::printf("\n");
    if (velocities) {
      std::printf("  vacf.csv  velocity autocorrelation (parallel transport), VACF(0) = %s\n",
                  format_short(v.value.front()).c_str());
    } else {
      std::printf("  vacf.csv  not written: the bodies' masses are not in summary.json\n");
    }
    if (pictures) std::printf("  rdf.png, msd.png\n");
  }
  return std::fflush(stdout) == 0 ? exit_ok : exit_internal;
}

}  // namespace sesi::program
