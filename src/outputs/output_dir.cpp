#include "output_dir.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iterator>
#include <mutex>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string_view>
#include <system_error>

#include <fcntl.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

namespace sesi::program {

namespace fs = std::filesystem;

namespace {

/// Written into each staging directory when it is made: the owner's process id. A staging
/// directory without it is not sesi's to remove.
constexpr std::string_view marker_name = ".sesi-staging";

/// Every name sesi (and tools/plot_run.py) writes into an output directory: the one list.
bool is_sesi_name(std::string_view name) {
  static constexpr std::array<std::string_view, 7> names = {
      "trajectory.csv", "trajectory.h5", "diagnostics.csv", "exact.csv", "summary.json", "checkpoint", marker_name};
  static constexpr std::array<std::string_view, 3> plots = {".png", ".pdf", ".svg"};
  if (std::find(names.begin(), names.end(), name) != names.end()) return true;
  return std::any_of(plots.begin(), plots.end(), [&](std::string_view extension) {
    return name.size() > extension.size() && name.ends_with(extension);
  });
}

/// A sesi output: a regular file with a sesi name.
bool is_sesi_output(const fs::directory_entry& entry) {
  std::error_code ec;
  return entry.is_regular_file(ec) && is_sesi_name(entry.path().filename().string());
}

/// A file sesi writes under a temporary name before renaming it (NAME.tmp); only in staging.
bool is_sesi_temporary(const fs::directory_entry& entry) {
  std::error_code ec;
  const std::string name = entry.path().filename().string();
  return entry.is_regular_file(ec) && name.ends_with(".tmp") && is_sesi_name(name.substr(0, name.size() - 4));
}

using Id = std::pair<dev_t, ino_t>;

std::optional<Id> identity(const fs::path& path) {
  struct stat st {};
  if (::lstat(path.c_str(), &st) != 0) return std::nullopt;
  return Id{st.st_dev, st.st_ino};
}

void warn(const std::string& message) {
  std::fprintf(stderr, "sesi: warning: %s\n", message.c_str());
  std::fflush(stderr);
}

std::string join(const std::vector<std::string>& items, const char* separator = ", ") {
  std::string out;
  for (const std::string& item : items) out += (out.empty() ? "" : separator) + item;
  return out;
}

/// Swap two directory entries atomically; false if the file system cannot.
bool exchange(const fs::path& a, const fs::path& b) {
#ifdef RENAME_EXCHANGE
  return renameat2(AT_FDCWD, a.c_str(), AT_FDCWD, b.c_str(), RENAME_EXCHANGE) == 0;
#else
  (void)a;
  (void)b;
  errno = ENOSYS;
  return false;
#endif
}

/// Rename without replacing anything at `to` (atomically where the file system can); 0 or -1
/// with errno (EEXIST if `to` exists).
int rename_noreplace(const fs::path& from, const fs::path& to) {
#ifdef RENAME_NOREPLACE
  if (renameat2(AT_FDCWD, from.c_str(), AT_FDCWD, to.c_str(), RENAME_NOREPLACE) == 0) return 0;
  if (errno != EINVAL && errno != ENOSYS) return -1;
#endif
  if (identity(to)) {
    errno = EEXIST;
    return -1;
  }
  return std::rename(from.c_str(), to.c_str());
}

bool pid_alive(long pid) { return pid > 0 && (::kill(static_cast<pid_t>(pid), 0) == 0 || errno == EPERM); }

/// The process id in a lock file or staging marker; 0 if there is none.
long read_pid(const fs::path& file) {
  std::ifstream in(file);
  long pid = 0;
  if (!(in >> pid) || pid <= 0) return 0;
  return pid;
}

/// Whether `dir` holds a finished run: its summary.json says "complete": true.
bool holds_complete_run(const fs::path& dir) {
  std::ifstream in(dir / "summary.json");
  if (!in) return false;
  const std::string text{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  const std::string key = "\"complete\"";
  std::size_t at = text.find(key);
  if (at == std::string::npos) return false;
  at += key.size();
  while (at < text.size() && (std::isspace(static_cast<unsigned char>(text[at])) || text[at] == ':')) ++at;
  return text.compare(at, 4, "true") == 0;
}

/// Absent, or a directory (not a symbolic link to one) that outputs can replace.
bool replaceable(const fs::path& dir, bool allow_complete) {
  std::error_code ec;
  const fs::file_status status = fs::symlink_status(dir, ec);
  if (!fs::exists(status)) return true;
  return fs::is_directory(status) && (allow_complete || !holds_complete_run(dir));
}

/// The first of BASE.SUFFIX, BASE.SUFFIX-2, ... that is absent (or, with `replace`, that
/// `replaceable` accepts).
fs::path beside(const fs::path& base, const std::string& suffix, bool replace) {
  for (int k = 1;; ++k) {
    const fs::path candidate = base.string() + "." + suffix + (k > 1 ? "-" + std::to_string(k) : "");
    std::error_code ec;
    if (replace ? replaceable(candidate, false) : !fs::exists(fs::symlink_status(candidate, ec))) return candidate;
  }
}

/// The sesi outputs in `dir` now (name and identity).
std::vector<std::pair<std::string, Id>> sesi_entries(const fs::path& dir) {
  std::vector<std::pair<std::string, Id>> out;
  std::error_code ec;
  for (const fs::directory_entry& entry : fs::directory_iterator(dir, ec)) {
    if (!is_sesi_output(entry)) continue;
    if (const auto id = identity(entry.path())) out.emplace_back(entry.path().filename().string(), *id);
  }
  return out;
}

/// Staging directories that are live in this process: where writers' messages point instead.
std::mutex live_mutex;
std::vector<std::pair<fs::path, fs::path>> live_staging;  // staging, target

void set_live(const fs::path& staging, const fs::path* target) {
  const std::lock_guard<std::mutex> guard(live_mutex);
  std::erase_if(live_staging, [&](const auto& item) { return item.first == staging; });
  if (target) live_staging.emplace_back(staging, *target);
}

/// Why `dir` (".NAME.sesi-REST" beside the target, found while holding the target's lock) is
/// not a killed run's staging directory that can be removed; empty if it was removed.
std::string remove_if_stale(const fs::path& dir, const std::string& rest) {
  std::error_code ec;
  if (!fs::is_directory(fs::symlink_status(dir, ec))) return "not a directory";
  const bool named = rest.size() == 6 && std::all_of(rest.begin(), rest.end(), [](char c) {
                       return std::isalnum(static_cast<unsigned char>(c)) != 0;
                     });
  const long pid = read_pid(dir / marker_name);
  if (!named || pid == 0) return "no sesi marker in it";
  // The lock proves no live run into this directory owns it; a live pid was reused.
  if (pid_alive(pid)) return "its process " + std::to_string(pid) + " is alive";
  std::vector<fs::path> files;
  for (const fs::directory_entry& entry : fs::directory_iterator(dir, ec)) {
    const std::string name = entry.path().filename().string();
    if (name == "checkpoint") return "it holds the killed run's checkpoint, which sesi resume finds";
    if (!is_sesi_output(entry) && !is_sesi_temporary(entry)) return "it holds '" + name + "', which sesi did not write";
    files.push_back(entry.path());
  }
  if (ec) return "cannot read it: " + ec.message();
  // File by file, never remove_all: anything that appears meanwhile stops the removal.
  for (const fs::path& file : files) {
    if (!fs::remove(file, ec) && ec) return "cannot remove " + file.filename().string() + ": " + ec.message();
  }
  if (!fs::remove(dir, ec)) return "cannot remove it: " + ec.message();
  return {};
}

/// Remove the staging directories of killed runs into `target`, and name the folders that look
/// like them but are not sesi's to remove; one line on stderr.
void clean_stale(const fs::path& parent, const fs::path& target, const fs::path& resuming) {
  const fs::path shown = target.parent_path();  // as the user gave it ("" rather than ".")
  const std::string prefix = "." + target.filename().string() + ".sesi-";
  std::vector<std::string> removed, left;
  std::error_code ec;
  for (const fs::directory_entry& entry : fs::directory_iterator(parent, ec)) {
    const std::string name = entry.path().filename().string();
    if (!name.starts_with(prefix) || name == prefix + "lock") continue;
    if (!resuming.empty() && entry.path().filename() == resuming.filename()) continue;  // sesi resume's source
    const std::string why = remove_if_stale(entry.path(), name.substr(prefix.size()));
    if (why.empty()) {
      removed.push_back((shown / name).string());
    } else {
      left.push_back((shown / name).string() + " (" + why + ")");
    }
  }
  std::vector<std::string> parts;
  if (!removed.empty()) parts.push_back("removed the staging folders of killed runs: " + join(removed));
  if (!left.empty()) parts.push_back("left " + join(left) + "; remove them if they are not needed");
  if (!parts.empty()) warn(target.string() + ": " + join(parts, "; "));
}

/// After `dest` received the new outputs, `old` holds what was there before: remove the earlier
/// sesi outputs (`earlier`) and move everything else into `dest`; what cannot move is kept
/// beside it. Nothing but `earlier` files and a staging marker is deleted.
void keep_others(const fs::path& old, const fs::path& dest, const std::vector<std::pair<std::string, Id>>& earlier) {
  std::vector<std::string> kept, stuck;
  std::error_code ec;
  for (const fs::directory_entry& entry : fs::directory_iterator(old, ec)) {
    const std::string name = entry.path().filename().string();
    const auto id = identity(entry.path());
    const bool ours = name == marker_name ||
                      (id && std::find(earlier.begin(), earlier.end(), std::pair{name, *id}) != earlier.end());
    std::error_code remove_ec;
    if (ours && fs::remove(entry.path(), remove_ec)) continue;
    if (!ours && rename_noreplace(entry.path(), dest / name) == 0) {
      kept.push_back(name + (fs::is_directory(fs::symlink_status(dest / name, remove_ec)) ? "/" : ""));
      continue;
    }
    stuck.push_back(name);
  }
  std::string message = kept.empty() ? std::string() : "kept what sesi did not write: " + join(kept);
  if (!fs::remove(old, ec)) {
    // Something could not move (a name the new outputs use, or added just now): keep it in sight.
    const fs::path aside = beside(dest, "kept", false);
    const fs::path where = rename_noreplace(old, aside) == 0 ? aside : old;
    message += (message.empty() ? "" : "; ") + (stuck.empty() ? std::string("what was added last") : join(stuck)) +
               " could not join the new outputs: kept in " + where.string();
  }
  if (!message.empty()) warn(dest.string() + ": " + message);
}

}  // namespace

DirLock::~DirLock() {
  if (fd_ < 0) return;
  // Remove the file while still holding the lock; a run that opened it meanwhile sees that it is
  // gone once it gets the lock, and tries again with a new file.
  ::unlink(file_.c_str());
  ::close(fd_);
}

void DirLock::acquire(const fs::path& file, const std::string& key) {
  const Origin origin{};
  for (int attempt = 0; attempt < 100; ++attempt) {
    const int fd = ::open(file.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (fd < 0) {
      throw InputError(origin, key, std::string("cannot write to the parent directory: ") + std::strerror(errno));
    }
    if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
      const int error = errno;
      ::close(fd);
      if (error != EWOULDBLOCK) {
        throw InputError(origin, key, "cannot lock " + file.string() + ": " + std::strerror(error));
      }
      const long pid = read_pid(file);
      const std::string holder = pid > 0 ? " (pid " + std::to_string(pid) + ")" : std::string();
      throw InputError(origin, key,
                       "is in use by another sesi run" + holder + "; wait for it or choose another directory");
    }
    struct stat held {}, now {};
    if (::fstat(fd, &held) == 0 && ::stat(file.c_str(), &now) == 0 && held.st_dev == now.st_dev &&
        held.st_ino == now.st_ino) {
      const std::string pid = std::to_string(::getpid()) + "\n";
      if (::ftruncate(fd, 0) != 0 || ::pwrite(fd, pid.data(), pid.size(), 0) != static_cast<ssize_t>(pid.size())) {
        const int error = errno;
        ::close(fd);
        throw InputError(origin, key, std::string("cannot write to the parent directory: ") + std::strerror(error));
      }
      fd_ = fd;
      file_ = file;
      return;
    }
    ::close(fd);  // the previous holder removed it after we opened it
  }
  throw InputError(origin, key, "cannot lock " + file.string());
}

StagingDir::StagingDir(fs::path target, const std::string& option, const fs::path& resuming)
    : target_(std::move(target)) {
  const Origin origin{};
  const std::string key = option + " " + target_.string();
  std::error_code ec;
  if (target_.empty()) throw InputError(origin, option, "expected a directory, got an empty path");
  // "out/" names the directory out; ".", ".." and "/a/.." name it by where they lead.
  if (target_.filename().empty() && target_.has_relative_path()) target_ = target_.parent_path();
  if (target_.filename() == "." || target_.filename() == "..") {
    target_ = fs::absolute(target_, ec).lexically_normal();
    if (target_.filename().empty() && target_.has_relative_path()) target_ = target_.parent_path();
  }
  if (target_.filename().empty()) throw InputError(origin, key, "expected a directory with a name");
  const fs::file_status status = fs::symlink_status(target_, ec);
  if (fs::exists(status) && !fs::is_directory(status)) {
    throw InputError(origin, key, "exists and is not a directory (or is a symbolic link)");
  }
  fs::path parent = target_.parent_path();
  if (parent.empty()) parent = ".";
  fs::create_directories(parent, ec);
  if (ec) throw InputError(origin, key, "cannot create the parent directory: " + ec.message());
  lock_.acquire(parent / ("." + target_.filename().string() + ".sesi-lock"), key);

  // From here no other sesi run changes the target or its staging directories.
  if (fs::exists(status)) {
    for (const fs::directory_entry& entry : fs::directory_iterator(target_, ec)) {
      if (!is_sesi_output(entry)) {
        throw InputError(origin, key,
                         "exists and holds '" + entry.path().filename().string() +
                             "', which sesi did not write; choose another directory or empty it");
      }
      if (const auto id = identity(entry.path())) earlier_.emplace_back(entry.path().filename().string(), *id);
    }
    if (ec) throw InputError(origin, key, "cannot read the directory: " + ec.message());
    if (const auto id = identity(target_)) earlier_dir_ = *id;
  }
  clean_stale(parent, target_, resuming);

  std::string pattern = (parent / ("." + target_.filename().string() + ".sesi-XXXXXX")).string();
  if (mkdtemp(pattern.data()) == nullptr) {
    throw InputError(origin, key, std::string("cannot write to the parent directory: ") + std::strerror(errno));
  }
  staging_ = pattern;
  std::ofstream marker(staging_ / marker_name);
  marker << ::getpid() << '\n';
  marker.close();
  if (!marker) {
    const int error = errno;
    fs::remove_all(staging_, ec);  // made just now, by this run
    throw InputError(origin, key, std::string("cannot write to the parent directory: ") + std::strerror(error));
  }
  // mkdtemp makes the directory private (0700); give it the usual permissions.
  const mode_t mask = umask(0);
  umask(mask);
  chmod(staging_.c_str(), 0777 & ~mask);
  set_live(staging_, &target_);
}

StagingDir::~StagingDir() {
  set_live(staging_, nullptr);
  if (published_) return;
  std::error_code ec;
  fs::remove_all(staging_, ec);  // made by this run, holds only what it wrote
}

fs::path StagingDir::publish(bool complete) {
  if (!complete && holds_complete_run(target_)) {
    const fs::path dest = beside(target_, "incomplete", true);
    warn(target_.string() + " holds a complete earlier run, which is kept; the outputs of this run go to " +
         dest.string());
    return publish_to(dest, sesi_entries(dest));
  }
  if (!replaceable(target_, true)) {
    const fs::path dest = beside(target_, "new", true);
    warn(target_.string() + " was replaced by something else during the run; the outputs go to " + dest.string());
    return publish_to(dest, sesi_entries(dest));
  }
  // Only what was there when the run started is the earlier run's; the rest was added since.
  std::vector<Entry> earlier;
  if (identity(target_) == std::optional<Id>(earlier_dir_)) earlier = earlier_;
  return publish_to(target_, earlier);
}

fs::path StagingDir::publish_to(const fs::path& dest, const std::vector<Entry>& earlier) {
  std::error_code ec;
  if (rename_noreplace(staging_, dest) == 0) {
    published_ = true;
    set_live(staging_, nullptr);
    fs::remove(dest / marker_name, ec);
    return dest;
  }
  if (errno != EEXIST && errno != ENOTEMPTY) {
    throw std::runtime_error("cannot move the outputs to " + dest.string() + ": " + std::strerror(errno));
  }
  // Replace the earlier outputs: swap atomically, else move them aside first.
  fs::path old = staging_;
  if (!exchange(staging_, dest)) {
    old = staging_.string() + ".old";
    if (std::rename(dest.c_str(), old.c_str()) != 0) {
      throw std::runtime_error("cannot replace " + dest.string() + ": " + std::strerror(errno));
    }
    if (std::rename(staging_.c_str(), dest.c_str()) != 0) {
      const int error = errno;
      std::rename(old.c_str(), dest.c_str());  // put the earlier outputs back
      throw std::runtime_error("cannot move the outputs to " + dest.string() + ": " + std::strerror(error));
    }
  }
  published_ = true;
  set_live(staging_, nullptr);
  fs::remove(dest / marker_name, ec);
  keep_others(old, dest, earlier);
  return dest;
}

bool remove_superseded(const fs::path& dir) {
  std::error_code ec;
  if (!fs::is_directory(fs::symlink_status(dir, ec))) return false;
  std::vector<fs::path> files;
  for (const fs::directory_entry& entry : fs::directory_iterator(dir, ec)) {
    if (!is_sesi_output(entry) && !is_sesi_temporary(entry)) return false;
    files.push_back(entry.path());
  }
  if (ec) return false;
  for (const fs::path& file : files) {
    if (!fs::remove(file, ec) && ec) return false;
  }
  return fs::remove(dir, ec);
}

fs::path shown_path(const fs::path& path) {
  const std::lock_guard<std::mutex> guard(live_mutex);
  for (const auto& [staging, target] : live_staging) {
    const fs::path relative = path.lexically_relative(staging);
    if (relative.empty() || *relative.begin() == "..") continue;
    return relative == "." ? target : target / relative;
  }
  return path;
}

}  // namespace sesi::program
