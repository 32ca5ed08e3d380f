#include "sweep_runs.hpp"

#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <sstream>
#include <stdexcept>
#include <string_view>
#include <system_error>
#include <utility>

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <toml++/toml.h>

#include "errors.hpp"

extern char** environ;

namespace sesi::program {

namespace fs = std::filesystem;

namespace {

constexpr std::string_view marker_name = "sweep-run.toml";
/// In a run's staging directory while the run goes: "PID START HOST", the run's process id, its
/// start time (field 22 of /proc/PID/stat, so that a reused pid is not taken for the run) and
/// the host. The sweep holds an flock on it from before the run starts, and the run inherits it,
/// so it stays locked while either lives.
constexpr std::string_view staging_marker_name = ".sesi-sweep-staging";
constexpr std::string_view csv_name = "sweep.csv";
constexpr std::string_view csv_header_start = "index,";

/// What a sweep writes into a run's directory; a run directory holding anything else is not
/// replaced (nor is a folder without the marker).
bool is_run_file(std::string_view name) {
  static constexpr std::array<std::string_view, 10> names = {
      "scene.toml", "log.txt", marker_name, "trajectory.csv", "trajectory.h5", "diagnostics.csv",
      "exact.csv", "summary.json", "checkpoint", "sesi-manifest.txt"};  // the last: sesi run's (output_dir.cpp)
  return std::find(names.begin(), names.end(), name) != names.end();
}

/// What `sesi run --out out` leaves in a killed sweep's staging directory, besides run files:
/// out/ (or its staging directory .out.sesi-XXXXXX) with sesi outputs, its lock, temporaries,
/// and old/, an earlier run being replaced.
bool is_staging_entry(const fs::path& path, int depth = 0) {
  const std::string name = path.filename().string();
  std::error_code ec;
  const fs::file_status status = fs::symlink_status(path, ec);
  if (fs::is_regular_file(status)) {
    const std::string base = name.ends_with(".tmp") ? name.substr(0, name.size() - 4) : name;
    return is_run_file(base) || name == ".sesi-staging" || name == ".out.sesi-lock" || name == staging_marker_name;
  }
  if (!fs::is_directory(status) || depth > 0) return false;
  // out/ or its staging directory, or old/: a replaced run moved aside
  if (name != "out" && name != "old" && !name.starts_with(".out.sesi-")) return false;
  for (const fs::directory_entry& entry : fs::directory_iterator(path, ec)) {
    if (!is_staging_entry(entry.path(), depth + 1)) return false;
  }
  return !ec;
}

/// Whether `name` is "NNNN" of some run of a sweep of `total` runs; its index.
std::optional<long> run_index(std::string_view name, long total) {
  if (name.empty() || name.find_first_not_of("0123456789") != std::string_view::npos) return std::nullopt;
  const long index = std::strtol(std::string(name).c_str(), nullptr, 10);
  if (index >= total || run_name(index, total) != name) return std::nullopt;
  return index;
}

/// Remove a directory the sweep wrote (checked by the caller): files first, then folders.
void remove_tree(const fs::path& dir) {
  std::error_code ec;
  fs::remove_all(dir, ec);
  if (ec) throw std::runtime_error("cannot remove " + dir.string() + ": " + ec.message());
}

std::string read_file(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void write_file(const fs::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << text;
  out.close();
  if (!out) throw std::runtime_error("cannot write " + path.string() + ": " + std::strerror(errno));
}

/// The number after "key": in the JSON object text.
std::optional<double> json_number(std::string_view text, std::string_view key) {
  const std::string quoted = "\"" + std::string(key) + "\"";
  std::size_t at = text.find(quoted);
  if (at == std::string_view::npos) return std::nullopt;
  at = text.find(':', at);
  if (at == std::string_view::npos) return std::nullopt;
  const std::string rest(text.substr(at + 1, 64));
  char* end = nullptr;
  const double value = std::strtod(rest.c_str(), &end);
  if (end == rest.c_str()) return std::nullopt;
  return value;
}

/// Energy errors from summary.json: E_final - E0, max |E - E0|, its relative form. A thermostatted
/// run's energy changes by the heat on purpose: its errors are those of the quantity its energy
/// guard judges, thermostat.conserved (E + the thermostat's offset; null, so empty, for brownian).
void read_energy(const fs::path& summary, RunResult& result) {
  const std::string text = read_file(summary);
  if (const std::size_t c = text.find("\"conserved\""); c != std::string::npos) {
    const std::size_t end = text.find('}', c);
    const std::string_view conserved = std::string_view(text).substr(c, end == std::string::npos ? end : end - c);
    const auto initial = json_number(conserved, "initial"), final = json_number(conserved, "final");
    const auto drift = json_number(conserved, "max_abs_drift");
    if (initial && final) result.final_energy_error = format_number(*final - *initial);
    if (drift) result.max_energy_error = format_number(*drift);
    if (initial && drift && *initial != 0.0) result.max_rel_energy_error = format_number(*drift / std::abs(*initial));
    return;
  }
  const std::size_t at = text.find("\"energy\"");
  if (at == std::string::npos) return;
  const std::size_t end = text.find('}', at);
  const std::string_view energy = std::string_view(text).substr(at, end == std::string::npos ? end : end - at);
  const auto initial = json_number(energy, "initial"), final = json_number(energy, "final");
  if (initial && final) result.final_energy_error = format_number(*final - *initial);
  if (const auto max = json_number(energy, "max_abs_error")) result.max_energy_error = format_number(*max);
  if (const auto rel = json_number(energy, "max_rel_error")) result.max_rel_energy_error = format_number(*rel);
}

/// The run's error line from its log ("sesi: error: ..."), without the prefix.
std::string error_line(const fs::path& log) {
  std::istringstream in(read_file(log));
  std::string line, found;
  while (std::getline(in, line)) {
    static constexpr std::string_view prefix = "sesi: error: ";
    if (line.starts_with(prefix)) found = line.substr(prefix.size());
  }
  return found;
}

std::string csv_cell(const std::string& text) {
  if (text.find_first_of(",\"\n\r") == std::string::npos) return text;
  std::string out = "\"";
  for (char c : text) {
    if (c == '"') out += '"';
    out += c == '\n' || c == '\r' ? ' ' : c;
  }
  return out + "\"";
}

fs::path self_exe() {
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (ec) throw std::runtime_error("cannot find the sesi program (/proc/self/exe): " + ec.message());
  return exe;
}

/// A process's start time (clock ticks after boot, field 22 of /proc/PID/stat); 0 if unknown or
/// if it has ended (a zombie, which an orphan stays until something reaps it).
unsigned long long start_time(long pid) {
  const std::string stat = read_file("/proc/" + std::to_string(pid) + "/stat");
  const std::size_t paren = stat.rfind(')');  // the command name may hold spaces and ')'
  if (paren == std::string::npos) return 0;
  std::istringstream fields(stat.substr(paren + 1));
  std::string field;
  for (int k = 3; k <= 22 && fields >> field; ++k) {
    if (k == 3 && (field == "Z" || field == "X" || field == "x")) return 0;
    if (k == 22) return std::strtoull(field.c_str(), nullptr, 10);
  }
  return 0;
}

/// What a staging directory's marker says about its run.
struct StagingOwner {
  bool live = false;    ///< its run (or the sweep that started it) is still going here
  bool foreign = false; ///< it was made on another host, where this process cannot look
  long pid = 0;
  std::string host;
};

StagingOwner staging_owner(const fs::path& staging) {
  StagingOwner owner;
  const fs::path marker = staging / staging_marker_name;
  const int fd = ::open(marker.c_str(), O_RDONLY | O_CLOEXEC | O_NOFOLLOW);
  if (fd < 0) return owner;  // no marker: an older sweep's folder, or one killed before its run started
  if (::flock(fd, LOCK_SH | LOCK_NB) != 0) {
    owner.live = errno == EWOULDBLOCK;  // held by the sweep or by the run, which inherited it
  } else {
    ::flock(fd, LOCK_UN);
  }
  ::close(fd);
  std::istringstream in(read_file(marker));
  unsigned long long start = 0;
  in >> owner.pid >> start >> owner.host;
  if (!owner.host.empty() && owner.host != host_name()) {
    owner.foreign = !owner.live;
    return owner;
  }
  // The lock alone fails where flock is emulated per process (NFS): a live pid with the same
  // start time is the run too.
  if (owner.pid > 0 && (::kill(static_cast<pid_t>(owner.pid), 0) == 0 || errno == EPERM) && start != 0 &&
      start_time(owner.pid) == start) {
    owner.live = true;
  }
  return owner;
}

/// mkdtemp with the usual permissions (mkdtemp makes it 0700).
fs::path make_staging(const fs::path& runs, const std::string& name) {
  std::string pattern = (runs / ("." + name + ".sweep-XXXXXX")).string();
  if (mkdtemp(pattern.data()) == nullptr) {
    throw std::runtime_error("cannot make a run directory in " + runs.string() + ": " + std::strerror(errno));
  }
  const mode_t mask = umask(0);
  umask(mask);
  chmod(pattern.c_str(), 0777 & ~mask);
  return pattern;
}

}  // namespace

std::string host_name() {
  char name[256] = {};
  if (gethostname(name, sizeof name - 1) != 0) return "unknown";
  return name;
}

std::string marker_text(const RunResult& r) {
  toml::table table{{"index", r.index},
                    {"status", r.status},
                    {"exit_status", r.exit_status},
                    {"final_energy_error", r.final_energy_error},
                    {"max_energy_error", r.max_energy_error},
                    {"max_rel_energy_error", r.max_rel_energy_error},
                    {"wall_seconds", r.wall_seconds},
                    {"rank", r.rank},
                    {"host", r.host},
                    {"message", r.message}};
  std::ostringstream out;
  out << "# sesi sweep: this run's row of sweep.csv; a rerun of the sweep skips the run while this file is here\n"
      << table << "\n";
  return out.str();
}

std::optional<RunResult> parse_marker(const std::string& text) {
  toml::table table;
  try {
    table = toml::parse(text);
  } catch (const toml::parse_error&) {
    return std::nullopt;
  }
  RunResult r;
  const auto index = table["index"].value<std::int64_t>();
  const auto status = table["status"].value<std::string>();
  const auto exit_status = table["exit_status"].value<std::int64_t>();
  if (!index || !status || !exit_status) return std::nullopt;
  r.index = static_cast<long>(*index);
  r.status = *status;
  r.exit_status = static_cast<int>(*exit_status);
  r.final_energy_error = table["final_energy_error"].value_or(std::string());
  r.max_energy_error = table["max_energy_error"].value_or(std::string());
  r.max_rel_energy_error = table["max_rel_energy_error"].value_or(std::string());
  r.wall_seconds = table["wall_seconds"].value_or(0.0);
  r.rank = static_cast<int>(table["rank"].value_or(std::int64_t{-1}));
  r.host = table["host"].value_or(std::string());
  r.message = table["message"].value_or(std::string());
  return r;
}

int sweep_status(const std::vector<RunResult>& results) {
  int worst = exit_ok;
  const auto rank = [](int status) {
    switch (status) {
      case exit_ok: return 0;
      case exit_run_failed: return 1;
      case exit_internal: return 2;
      default: return 3;  // exit_interrupted
    }
  };
  for (const RunResult& r : results) {
    int status = exit_ok;
    if (r.status == "failed") status = exit_run_failed;
    if (r.status == "error") status = exit_internal;
    if (r.status == "interrupted") status = exit_interrupted;
    if (rank(status) > rank(worst)) worst = status;
  }
  return worst;
}

SweepDir::SweepDir(fs::path dir, const Sweep& sweep) : dir_(std::move(dir)), sweep_(sweep) {
  const Origin origin{};
  const std::string key = "--out " + dir_.string();
  std::error_code ec;
  const fs::file_status status = fs::symlink_status(dir_, ec);
  if (fs::exists(status) && !fs::is_directory(status)) {
    throw InputError(origin, key, "exists and is not a directory (or is a symbolic link)");
  }
  fs::create_directories(dir_, ec);
  if (ec) throw InputError(origin, key, "cannot create the directory: " + ec.message());
  lock_.acquire(dir_ / ".sesi-sweep-lock", key);

  const fs::path csv = dir_ / csv_name;
  if (fs::exists(fs::symlink_status(csv, ec))) {
    const std::string text = read_file(csv);
    if (!fs::is_regular_file(fs::symlink_status(csv, ec)) || !text.starts_with(csv_header_start)) {
      throw InputError(origin, key, "holds sweep.csv, which sesi did not write; choose another directory or move it");
    }
  }
  const fs::path runs = dir_ / "runs";
  const fs::file_status runs_status = fs::symlink_status(runs, ec);
  if (fs::exists(runs_status) && !fs::is_directory(runs_status)) {
    throw InputError(origin, key, "holds 'runs', which is not a directory; choose another directory or move it");
  }
  fs::create_directories(runs, ec);
  if (ec) throw InputError(origin, key, "cannot create runs/: " + ec.message());

  const long total = static_cast<long>(sweep_.variants.size());
  done_.assign(sweep_.variants.size(), std::nullopt);
  std::vector<std::string> removed, left;
  // First the runs of a killed sweep that still go (each is its own process): refused before
  // anything is removed, so that their folders are never taken from under them.
  for (const fs::directory_entry& entry : fs::directory_iterator(runs, ec)) {
    const std::string name = entry.path().filename().string();
    std::error_code item;
    if (!name.starts_with(".") || name.find(".sweep-") == std::string::npos || entry.is_symlink(item) ||
        !entry.is_directory(item)) {
      continue;
    }
    const StagingOwner owner = staging_owner(entry.path());
    if (owner.live) {
      const std::string run = name.substr(1, name.find(".sweep-") - 1);
      throw InputError(origin, key,
                       "run " + run + " of an earlier sweep is still running in runs/" + name +
                           (owner.pid > 0 ? " (pid " + std::to_string(owner.pid) + ")" : std::string()) +
                           "; wait for it to end or stop it, then run the sweep again");
    }
  }
  if (ec) throw InputError(origin, key, "cannot read runs/: " + ec.message());
  for (const fs::directory_entry& entry : fs::directory_iterator(runs, ec)) {
    const std::string name = entry.path().filename().string();
    if (name.starts_with(".") && name.find(".sweep-") != std::string::npos) {
      // A killed sweep's staging directory (no sweep is live here: we hold the lock; no run of
      // it goes on here: checked above). One made on another host is left: its run may go on.
      bool ours = entry.is_directory(ec) && !entry.is_symlink(ec) && !staging_owner(entry.path()).foreign;
      for (const fs::directory_entry& item : fs::directory_iterator(entry.path(), ec)) {
        ours = ours && is_staging_entry(item.path());
      }
      if (ours && !ec) {
        remove_tree(entry.path());
        removed.push_back(name);
      } else {
        left.push_back(name);
      }
      continue;
    }
    const std::optional<long> index = run_index(name, total);
    if (!index) continue;  // not a place this sweep writes
    const std::string shown = "runs/" + name;
    if (!entry.is_directory(ec) || entry.is_symlink(ec)) {
      throw InputError(origin, key, "holds " + shown + ", which is not a run directory; move it away");
    }
    std::optional<RunResult> result;
    if (fs::exists(entry.path() / marker_name, ec)) result = parse_marker(read_file(entry.path() / marker_name));
    const bool same_scene = read_file(entry.path() / "scene.toml") == sweep_.variants[*index].scene_text;
    if (result && result->index == *index && same_scene && (result->status == "ok" || result->status == "failed")) {
      done_[*index] = result;  // skipped: what else is in it (plots) is left alone
      continue;
    }
    // To be run again, and then replaced: it must hold only what a sweep writes.
    if (!result) {
      throw InputError(origin, key, "holds " + shown + " without a readable sesi sweep marker (" +
                                        std::string(marker_name) + "), so sesi did not write it; move it away or choose another directory");
    }
    for (const fs::directory_entry& item : fs::directory_iterator(entry.path(), ec)) {
      if (!item.is_regular_file(ec) || !is_run_file(item.path().filename().string())) {
        throw InputError(origin, key, "holds " + shown + "/" + item.path().filename().string() +
                                          ", which sesi did not write, and that run is to be run again; move it away");
      }
    }
  }
  if (ec) throw InputError(origin, key, "cannot read runs/: " + ec.message());
  if (!removed.empty() || !left.empty()) {
    std::string message;
    for (const std::string& name : removed) message += (message.empty() ? "" : ", ") + name;
    if (!message.empty()) message = "removed the staging folders of killed runs: " + message;
    for (std::size_t i = 0; i < left.size(); ++i) {
      message += std::string(i == 0 ? (message.empty() ? "left " : "; left ") : ", ") + left[i];
    }
    if (!left.empty()) {
      message += " (not only sesi's, or made on another host, where their runs may still go); remove them if "
                 "they are not needed";
    }
    std::fprintf(stderr, "sesi: warning: %s: %s\n", (dir_ / "runs").string().c_str(), message.c_str());
  }
}

void SweepDir::write_csv(const std::vector<RunResult>& results) const {
  std::string text = "index";
  for (const std::string& column : sweep_.columns) text += "," + csv_cell(column);
  text += ",status,exit_status,final_energy_error,max_energy_error,max_rel_energy_error,wall_seconds,rank,host,message\n";
  for (std::size_t i = 0; i < results.size(); ++i) {
    const RunResult& r = results[i];
    text += std::to_string(i);
    for (const std::string& value : sweep_.variants[i].values) text += "," + csv_cell(value);
    char wall[32] = "";
    if (r.status != "pending") std::snprintf(wall, sizeof wall, "%.3f", r.wall_seconds);
    text += "," + r.status + "," + (r.exit_status >= 0 ? std::to_string(r.exit_status) : "") + "," +
            r.final_energy_error + "," + r.max_energy_error + "," + r.max_rel_energy_error + "," + wall + "," +
            (r.rank >= 0 ? std::to_string(r.rank) : "") + "," + csv_cell(r.host) + "," + csv_cell(r.message) + "\n";
  }
  const fs::path temporary = dir_ / ".sweep.csv.tmp";
  write_file(temporary, text);
  if (std::rename(temporary.c_str(), (dir_ / csv_name).c_str()) != 0) {
    throw std::runtime_error("cannot write " + (dir_ / csv_name).string() + ": " + std::strerror(errno));
  }
}

RunProcess::RunProcess(const fs::path& dir, const Sweep& sweep, const Variant& variant, bool one_thread)
    : index_(variant.index),
      name_(run_name(variant.index, static_cast<long>(sweep.variants.size()))),
      runs_(dir / "runs"),
      trajectory_(sweep.trajectory) {
  staging_ = make_staging(runs_, name_);
  // The marker, locked before the run starts: a rerun after this sweep was killed sees the lock
  // (the run inherits it) and keeps the folder while the run goes.
  const fs::path marker = staging_ / staging_marker_name;
  marker_fd_ = ::open(marker.c_str(), O_RDWR | O_CREAT | O_EXCL | O_CLOEXEC, 0644);
  if (marker_fd_ < 0 || ::flock(marker_fd_, LOCK_EX | LOCK_NB) != 0) {
    const int error = errno;
    if (marker_fd_ >= 0) ::close(std::exchange(marker_fd_, -1));
    std::error_code ec;
    fs::remove_all(staging_, ec);
    throw std::runtime_error("cannot write " + marker.string() + ": " + std::strerror(error));
  }
  write_file(staging_ / "scene.toml", variant.scene_text);
  const std::string log = (staging_ / "log.txt").string();
  const std::string exe = self_exe().string();
  std::vector<std::string> args = {exe, "run", "scene.toml", "--out", "out"};
  if (one_thread) args.insert(args.end(), {"--threads", "1"});
  std::vector<char*> argv;
  for (std::string& arg : args) argv.push_back(arg.data());
  argv.push_back(nullptr);

  posix_spawn_file_actions_t actions;
  posix_spawnattr_t attributes;
  posix_spawn_file_actions_init(&actions);
  posix_spawnattr_init(&attributes);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, STDOUT_FILENO, STDERR_FILENO);
  // The run inherits the marker's lock through a copy of the descriptor (not close-on-exec).
  posix_spawn_file_actions_adddup2(&actions, marker_fd_, marker_fd_ == 3 ? 4 : 3);
  posix_spawn_file_actions_addchdir_np(&actions, staging_.c_str());
  // Its own process group: a Ctrl-C reaches the sweep, which stops its runs once (stop()).
  sigset_t defaults, none;
  sigemptyset(&defaults);
  for (int s : {SIGINT, SIGTERM, SIGHUP, SIGPIPE}) sigaddset(&defaults, s);
  sigemptyset(&none);
  posix_spawnattr_setsigdefault(&attributes, &defaults);
  posix_spawnattr_setsigmask(&attributes, &none);
  posix_spawnattr_setpgroup(&attributes, 0);
  posix_spawnattr_setflags(&attributes, POSIX_SPAWN_SETSIGDEF | POSIX_SPAWN_SETSIGMASK | POSIX_SPAWN_SETPGROUP);
  start_ = std::chrono::steady_clock::now();
  const int error = posix_spawn(&pid_, exe.c_str(), &actions, &attributes, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  posix_spawnattr_destroy(&attributes);
  if (error != 0) {
    ::close(std::exchange(marker_fd_, -1));
    std::error_code ec;
    fs::remove_all(staging_, ec);
    throw std::runtime_error("cannot start run " + name_ + ": " + std::strerror(error));
  }
  const std::string owner =
      std::to_string(pid_) + " " + std::to_string(start_time(pid_)) + " " + host_name() + "\n";
  if (::pwrite(marker_fd_, owner.data(), owner.size(), 0) != static_cast<ssize_t>(owner.size())) {
    // Without the pid the lock still tells (where flock is not emulated per process).
    std::fprintf(stderr, "sesi: warning: cannot write %s: %s\n", marker.c_str(), std::strerror(errno));
  }
}

RunProcess::RunProcess(RunProcess&& other) noexcept { *this = std::move(other); }

RunProcess& RunProcess::operator=(RunProcess&& other) noexcept {
  index_ = other.index_;
  name_ = std::move(other.name_);
  runs_ = std::move(other.runs_);
  staging_ = std::move(other.staging_);
  trajectory_ = other.trajectory_;
  pid_ = std::exchange(other.pid_, -1);
  if (marker_fd_ >= 0) ::close(marker_fd_);
  marker_fd_ = std::exchange(other.marker_fd_, -1);
  wait_status_ = other.wait_status_;
  ended_ = other.ended_;
  stopped_ = other.stopped_;
  start_ = other.start_;
  return *this;
}

RunProcess::~RunProcess() {
  if (pid_ > 0 && !ended_) {
    // Only on the way out after an error: do not leave the run going.
    ::kill(pid_, SIGKILL);
    ::waitpid(pid_, &wait_status_, 0);
  }
  if (marker_fd_ >= 0) ::close(marker_fd_);
}

bool RunProcess::poll() {
  if (ended_) return true;
  const pid_t done = ::waitpid(pid_, &wait_status_, WNOHANG);
  if (done == pid_) ended_ = true;
  return ended_;
}

void RunProcess::wait() {
  while (!ended_) {
    if (::waitpid(pid_, &wait_status_, 0) == pid_) ended_ = true;
    else if (errno != EINTR) break;
  }
}

void RunProcess::stop() {
  if (!ended_ && !stopped_) ::kill(pid_, SIGTERM);
  stopped_ = true;
}

RunResult RunProcess::finish(int rank, const std::string& host) {
  wait();
  RunResult result;
  result.index = index_;
  result.rank = rank;
  result.host = host;
  result.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  const int code = WIFEXITED(wait_status_) ? WEXITSTATUS(wait_status_) : -1;
  result.exit_status = code >= 0 ? code : 128 + WTERMSIG(wait_status_);
  std::error_code ec;
  // The run has ended: its staging marker goes (a run directory holds only run files).
  fs::remove(staging_ / staging_marker_name, ec);
  if (marker_fd_ >= 0) ::close(std::exchange(marker_fd_, -1));
  if (code == exit_interrupted || (stopped_ && code != exit_ok && code != exit_run_failed)) {
    result.status = "interrupted";
    result.message = "interrupted; run again by a rerun of the sweep";
    remove_tree(staging_);
    return result;
  }
  // The run's outputs (in out/, published there by sesi run) join the scene and the log.
  const fs::path out = staging_ / "out";
  if (fs::is_directory(out, ec)) {
    for (const fs::directory_entry& entry : fs::directory_iterator(out, ec)) {
      fs::rename(entry.path(), staging_ / entry.path().filename(), ec);
      if (ec) throw std::runtime_error("cannot move " + entry.path().string() + ": " + ec.message());
    }
    fs::remove(out, ec);
  }
  if (!trajectory_) {
    fs::remove(staging_ / "trajectory.csv", ec);
    fs::remove(staging_ / "trajectory.h5", ec);
  }
  if (fs::exists(staging_ / "summary.json", ec)) read_energy(staging_ / "summary.json", result);
  result.status = code == exit_ok ? "ok" : code == exit_run_failed ? "failed" : "error";
  if (code != exit_ok) {
    result.message = error_line(staging_ / "log.txt");
    // The run's messages name its output directory as it was given to it, "out": name the run's.
    for (const std::string_view out : {" in out,", " in out;", " in out"}) {
      const std::size_t at = result.message.find(out);
      if (at != std::string::npos && (out.back() != 't' || at + out.size() == result.message.size())) {
        result.message.replace(at, out.size() - (out.back() == 't' ? 0 : 1), " in runs/" + name_);
        break;
      }
    }
    if (result.message.empty()) {
      result.message = code >= 0 ? "ended with exit status " + std::to_string(code)
                                 : "killed by signal " + std::to_string(WTERMSIG(wait_status_));
    }
  }
  write_file(staging_ / marker_name, marker_text(result));

  // Put it in place: DIR/runs/NNNN, replacing an earlier attempt (checked by SweepDir).
  const fs::path target = runs_ / name_;
  if (fs::exists(fs::symlink_status(target, ec))) {
    const fs::path old = make_staging(runs_, name_);
    if (std::rename(target.c_str(), (old / "old").c_str()) != 0) {
      throw std::runtime_error("cannot replace " + target.string() + ": " + std::strerror(errno));
    }
    if (std::rename(staging_.c_str(), target.c_str()) != 0) {
      throw std::runtime_error("cannot move run " + name_ + " into place: " + std::strerror(errno));
    }
    remove_tree(old);
  } else if (std::rename(staging_.c_str(), target.c_str()) != 0) {
    throw std::runtime_error("cannot move run " + name_ + " into place: " + std::strerror(errno));
  }
  return result;
}

}  // namespace sesi::program
