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

/// The run's manifest, written into every output directory: the files sesi wrote there, one
/// name a line after a first line that says what it is. A run repeated into the directory
/// replaces exactly these and keeps everything else (tools/plot_run.py adds its plot).
constexpr std::string_view manifest_name = "sesi-manifest.txt";
constexpr std::string_view manifest_head = "# sesi-manifest 1:";

/// Every name sesi writes into an output directory (pictures are sesi's only by a manifest).
bool is_sesi_name(std::string_view name) {
  static constexpr std::array<std::string_view, 9> names = {"trajectory.csv", "trajectory.h5", "diagnostics.csv",
                                                            "exact.csv",      "summary.json",  "checkpoint",
                                                            "profile.csv",    marker_name,     manifest_name};
  return std::find(names.begin(), names.end(), name) != names.end();
}

bool is_picture(std::string_view name) {
  static constexpr std::array<std::string_view, 3> plots = {".png", ".pdf", ".svg"};
  return std::any_of(plots.begin(), plots.end(), [&](std::string_view extension) {
    return name.size() > extension.size() && name.ends_with(extension);
  });
}

/// A sesi output: a regular file with a sesi name.
bool is_sesi_output(const fs::directory_entry& entry) {
  std::error_code ec;
  return entry.is_regular_file(ec) && is_sesi_name(entry.path().filename().string());
}

/// The names dir's manifest lists (with the manifest itself); nullopt when dir has none (an
/// older sesi's outputs) or the file of that name is not sesi's.
std::optional<std::vector<std::string>> read_manifest(const fs::path& dir) {
  std::ifstream in(dir / manifest_name);
  std::string line;
  if (!in || !std::getline(in, line) || !line.starts_with(manifest_head)) return std::nullopt;
  std::vector<std::string> names = {std::string(manifest_name)};
  while (std::getline(in, line)) {
    if (!line.empty() && line != "." && line != ".." && line.find('/') == std::string::npos) names.push_back(line);
  }
  return names;
}

/// Whether `entry` of a directory with `manifest` (or none) is a file sesi wrote there.
bool is_owned(const fs::directory_entry& entry, const std::optional<std::vector<std::string>>& manifest) {
  if (!manifest) return is_sesi_output(entry);
  std::error_code ec;
  const std::string name = entry.path().filename().string();
  return entry.is_regular_file(ec) && std::find(manifest->begin(), manifest->end(), name) != manifest->end();
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

/// The files sesi wrote in `dir` (by its manifest), now (name and identity).
std::vector<std::pair<std::string, Id>> sesi_entries(const fs::path& dir) {
  std::vector<std::pair<std::string, Id>> out;
  const auto manifest = read_manifest(dir);
  std::error_code ec;
  for (const fs::directory_entry& entry : fs::directory_iterator(dir, ec)) {
    if (!is_owned(entry, manifest)) continue;
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

/// Remove the staging directories of killed runs into `target` (the entries PREFIX-XXXXXX of
/// `where`, shown as in `shown`), and name the folders that look like them but are not sesi's to
/// remove; one line on stderr.
void clean_stale(const fs::path& where, const fs::path& shown, const std::string& prefix, const fs::path& target,
                 const fs::path& resuming) {
  std::vector<std::string> removed, left;
  std::error_code ec;
  for (const fs::directory_entry& entry : fs::directory_iterator(where, ec)) {
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

/// Whether `dir` (a directory) is a mount point, which no rename can replace: its device differs
/// from its parent's, or (a bind mount of the same file system) statx says it is a mount's root.
bool is_mount_point(const fs::path& dir, const fs::path& parent) {
  struct stat own {}, up {};
  if (::stat(dir.c_str(), &own) != 0 || ::stat(parent.c_str(), &up) != 0) return false;
  if (own.st_dev != up.st_dev) return true;
#if defined(STATX_ATTR_MOUNT_ROOT)
  struct statx sx {};
  if (::statx(AT_FDCWD, dir.c_str(), AT_SYMLINK_NOFOLLOW, STATX_BASIC_STATS, &sx) == 0 &&
      (sx.stx_attributes_mask & STATX_ATTR_MOUNT_ROOT) != 0) {
    return (sx.stx_attributes & STATX_ATTR_MOUNT_ROOT) != 0;
  }
#endif
  return own.st_ino == up.st_ino;  // "/" is its own parent
}

/// A staging directory's or lock's name inside a mount point (".sesi-XXXXXX", ".sesi-lock").
constexpr std::string_view inside_prefix = ".sesi-";

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
  // The outputs take the place of the target: never the directory the user works in, or one above.
  const fs::path cwd = fs::current_path(ec);
  const fs::path resolved = fs::weakly_canonical(fs::absolute(target_, ec), ec);
  if (!cwd.empty() && !resolved.empty()) {
    const fs::path inside = cwd.lexically_relative(resolved);
    if (!inside.empty() && *inside.begin() != "..") {
      throw InputError(origin, key,
                       std::string(inside == "." ? "is" : "holds") +
                           " the current directory, which the outputs would replace; " +
                           (option == "--out" ? "name a directory for them (for example --out run1)"
                                              : "run it from another directory"));
    }
  }
  const fs::file_status status = fs::symlink_status(target_, ec);
  if (fs::exists(status) && !fs::is_directory(status)) {
    throw InputError(origin, key, "exists and is not a directory (or is a symbolic link)");
  }
  fs::path parent = target_.parent_path();
  if (parent.empty()) parent = ".";
  fs::create_directories(parent, ec);
  if (ec) throw InputError(origin, key, "cannot create the parent directory: " + ec.message());
  // A mount point cannot be renamed over: the run stages inside it and moves its files in.
  inside_ = fs::exists(status) && is_mount_point(target_, parent);
  const fs::path where = inside_ ? target_ : parent;
  const std::string prefix = inside_ ? std::string(inside_prefix) : "." + target_.filename().string() + ".sesi-";
  const std::string place = inside_ ? "the directory" : "the parent directory";
  lock_.acquire(where / (prefix + "lock"), key);

  // From here no other sesi run changes the target or its staging directories.
  if (fs::exists(status)) {
    const auto manifest = read_manifest(target_);
    for (const fs::directory_entry& entry : fs::directory_iterator(target_, ec)) {
      const std::string name = entry.path().filename().string();
      if (inside_ && name.starts_with(inside_prefix)) continue;  // the lock and staging directories
      if (is_owned(entry, manifest)) {
        if (const auto id = identity(entry.path())) earlier_.emplace_back(name, *id);
        continue;
      }
      // What sesi did not write is kept: pictures (a user's, or any in an older sesi's outputs,
      // which have no manifest). Anything else is refused, so that a mistyped --out is refused.
      if (!is_picture(name)) {
        throw InputError(origin, key,
                         "exists and holds '" + name + "', which sesi did not write; choose another directory or "
                         "empty it");
      }
    }
    if (ec) throw InputError(origin, key, "cannot read the directory: " + ec.message());
    if (const auto id = identity(target_)) earlier_dir_ = *id;
  }
  clean_stale(where, inside_ ? target_ : target_.parent_path(), prefix, target_, resuming);

  std::string pattern = (where / (prefix + "XXXXXX")).string();
  if (mkdtemp(pattern.data()) == nullptr) {
    throw InputError(origin, key, "cannot write to " + place + ": " + std::strerror(errno));
  }
  staging_ = pattern;
  std::ofstream marker(staging_ / marker_name);
  marker << ::getpid() << '\n';
  marker.close();
  if (!marker) {
    const int error = errno;
    fs::remove_all(staging_, ec);  // made just now, by this run
    throw InputError(origin, key, "cannot write to " + place + ": " + std::strerror(error));
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
  write_manifest();
  if (inside_) return publish_inside(complete);
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
      // A mount point that is_mount_point missed: the files go in one by one (same file system).
      if (errno == EBUSY) return move_into(dest, earlier);
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

void StagingDir::write_manifest() {
  // Everything in the staging directory is this run's (but the marker, removed on publishing).
  std::vector<std::string> names;
  std::error_code ec;
  for (const fs::directory_entry& entry : fs::directory_iterator(staging_, ec)) {
    const std::string name = entry.path().filename().string();
    if (name != marker_name && name != manifest_name) names.push_back(name);
  }
  std::sort(names.begin(), names.end());  // the same bytes for the same outputs
  std::ofstream out(staging_ / manifest_name);
  out << manifest_head
      << " the files sesi wrote here; a run repeated into this directory replaces them and deletes nothing else\n";
  for (const std::string& name : names) out << name << '\n';
  out.close();
  if (!out || ec) {
    throw std::runtime_error("cannot write " + (target_ / manifest_name).string() + ": " +
                             (ec ? ec.message() : std::string(std::strerror(errno))));
  }
}

fs::path StagingDir::publish_inside(bool complete) {
  if (!complete && holds_complete_run(target_)) {
    // Beside the complete run, inside the mount point (the parent may be another file system).
    fs::path free = target_ / "incomplete";
    for (int k = 2; !replaceable(free, false); ++k) free = target_ / ("incomplete-" + std::to_string(k));
    warn(target_.string() + " holds a complete earlier run, which is kept; the outputs of this run go to " +
         free.string());
    return publish_to(free, sesi_entries(free));
  }
  std::vector<Entry> earlier;
  if (identity(target_) == std::optional<Id>(earlier_dir_)) earlier = earlier_;
  return move_into(target_, earlier);
}

fs::path StagingDir::move_into(const fs::path& dest, const std::vector<Entry>& earlier) {
  // File by file: remove the earlier run's files (those there when this run started), then
  // rename this run's in, the summary and the manifest last; anything else stays where it is.
  std::error_code ec;
  for (const auto& [name, id] : earlier) {
    if (identity(dest / name) == std::optional<Id>(id)) fs::remove(dest / name, ec);
  }
  std::vector<std::string> names, aside;
  for (const fs::directory_entry& entry : fs::directory_iterator(staging_, ec)) {
    const std::string name = entry.path().filename().string();
    if (name != marker_name) names.push_back(name);
  }
  const auto rank = [](const std::string& name) { return name == manifest_name ? 2 : name == "summary.json" ? 1 : 0; };
  std::sort(names.begin(), names.end(),
            [&](const std::string& a, const std::string& b) { return std::pair(rank(a), a) < std::pair(rank(b), b); });
  for (const std::string& name : names) {
    if (rename_noreplace(staging_ / name, dest / name) == 0) continue;
    int error = errno;
    if (error == EEXIST) {  // a file of that name added during the run: kept beside
      const fs::path kept = beside(dest / name, "kept", false);
      if (rename_noreplace(dest / name, kept) == 0) {
        aside.push_back(name + " -> " + kept.filename().string());
        if (rename_noreplace(staging_ / name, dest / name) == 0) continue;
      }
      error = errno;
    }
    throw std::runtime_error("cannot move the outputs to " + (dest / name).string() + ": " + std::strerror(error));
  }
  published_ = true;
  set_live(staging_, nullptr);
  fs::remove(staging_ / marker_name, ec);
  fs::remove(staging_, ec);
  if (!aside.empty()) warn(dest.string() + ": kept what sesi did not write, renamed: " + join(aside));
  return dest;
}

bool remove_superseded(const fs::path& dir) {
  std::error_code ec;
  if (!fs::is_directory(fs::symlink_status(dir, ec))) return false;
  const auto manifest = read_manifest(dir);
  std::vector<fs::path> files;
  for (const fs::directory_entry& entry : fs::directory_iterator(dir, ec)) {
    if (!is_owned(entry, manifest) && !is_sesi_output(entry) && !is_sesi_temporary(entry)) return false;
    files.push_back(entry.path());
  }
  if (ec) return false;
  for (const fs::path& file : files) {
    if (!fs::remove(file, ec) && ec) return false;
  }
  return fs::remove(dir, ec);
}

void lock_output_dir(DirLock& lock, const fs::path& dir, const std::string& key) {
  fs::path parent = dir.parent_path();
  if (parent.empty()) parent = ".";
  // As StagingDir: inside a mount point, else beside the directory.
  if (is_mount_point(dir, parent)) {
    lock.acquire(dir / (std::string(inside_prefix) + "lock"), key);
  } else {
    lock.acquire(parent / ("." + dir.filename().string() + ".sesi-lock"), key);
  }
}

bool has_manifest(const fs::path& dir) { return read_manifest(dir).has_value(); }

bool manifest_lists(const fs::path& dir, const std::string& name) {
  const auto manifest = read_manifest(dir);
  return manifest && std::find(manifest->begin(), manifest->end(), name) != manifest->end();
}

void add_to_manifest(const fs::path& dir, const std::vector<std::string>& names) {
  std::ifstream in(dir / manifest_name);
  std::string head;
  std::getline(in, head);
  std::vector<std::string> listed = read_manifest(dir).value_or(std::vector<std::string>{});
  std::erase(listed, std::string(manifest_name));
  listed.insert(listed.end(), names.begin(), names.end());
  std::sort(listed.begin(), listed.end());
  listed.erase(std::unique(listed.begin(), listed.end()), listed.end());
  const fs::path temporary = dir / (std::string(manifest_name) + ".tmp");
  std::ofstream out(temporary);
  out << (head.starts_with(manifest_head) ? head : std::string(manifest_head)) << '\n';
  for (const std::string& name : listed) out << name << '\n';
  out.close();
  std::error_code ec;
  if (out) fs::rename(temporary, dir / manifest_name, ec);
  if (!out || ec) {
    fs::remove(temporary, ec);
    throw std::runtime_error("cannot write " + (dir / manifest_name).string());
  }
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

void write_file_atomically(const std::filesystem::path& path, const std::string& text) {
  write_file_atomically(path, [&](std::FILE* file) { return std::fwrite(text.data(), 1, text.size(), file) == text.size(); });
}

void write_file_atomically(const std::filesystem::path& path, const std::function<bool(std::FILE*)>& write) {
  const std::filesystem::path temporary = path.string() + ".tmp";
  std::FILE* file = std::fopen(temporary.c_str(), "w");
  bool ok = file != nullptr;
  if (ok) ok = write(file);
  if (file) ok = std::fclose(file) == 0 && ok;
  if (ok) ok = std::rename(temporary.c_str(), path.c_str()) == 0;
  if (!ok) {
    const int error = errno;
    std::remove(temporary.c_str());  // (no half-written file left beside the outputs)
    throw std::runtime_error("cannot write " + shown_path(path).string() + ": " + std::strerror(error));
  }
}

}  // namespace sesi::program
