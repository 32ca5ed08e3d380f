#include "output_dir.hpp"

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <string_view>
#include <system_error>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

namespace sesi::program {

namespace fs = std::filesystem;

namespace {
/// Files sesi (and tools/plot_run.py) put into an output directory.
bool is_sesi_output(const fs::directory_entry& entry) {
  static constexpr std::array<std::string_view, 5> names = {"trajectory.csv", "trajectory.h5", "diagnostics.csv",
                                                            "exact.csv", "summary.json"};
  static constexpr std::array<std::string_view, 3> plots = {".png", ".pdf", ".svg"};
  std::error_code ec;
  if (!entry.is_regular_file(ec)) return false;
  const std::string name = entry.path().filename().string();
  const std::string extension = entry.path().extension().string();
  return std::find(names.begin(), names.end(), name) != names.end() ||
         std::find(plots.begin(), plots.end(), extension) != plots.end();
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
}  // namespace

StagingDir::StagingDir(fs::path target, const std::string& option) : target_(std::move(target)) {
  const Origin origin{};
  const std::string key = option + " " + target_.string();
  std::error_code ec;
  if (target_.empty()) throw InputError(origin, option, "expected a directory, got an empty path");
  const fs::file_status status = fs::symlink_status(target_, ec);
  if (fs::exists(status)) {
    if (!fs::is_directory(status)) {
      throw InputError(origin, key, "exists and is not a directory (or is a symbolic link)");
    }
    for (const fs::directory_entry& entry : fs::directory_iterator(target_, ec)) {
      if (!is_sesi_output(entry)) {
        throw InputError(origin, key,
                         "exists and holds '" + entry.path().filename().string() +
                             "', which sesi did not write; choose another directory or empty it");
      }
    }
    if (ec) throw InputError(origin, key, "cannot read the directory: " + ec.message());
  }
  fs::path parent = target_.parent_path();
  if (parent.empty()) parent = ".";
  fs::create_directories(parent, ec);
  if (ec) throw InputError(origin, key, "cannot create the parent directory: " + ec.message());
  std::string pattern = (parent / ("." + target_.filename().string() + ".sesi-XXXXXX")).string();
  if (mkdtemp(pattern.data()) == nullptr) {
    throw InputError(origin, key, std::string("cannot write to the parent directory: ") + std::strerror(errno));
  }
  staging_ = pattern;
  // mkdtemp makes the directory private (0700); give it the usual permissions.
  const mode_t mask = umask(0);
  umask(mask);
  chmod(staging_.c_str(), 0777 & ~mask);
}

StagingDir::~StagingDir() {
  if (published_) return;
  std::error_code ec;
  fs::remove_all(staging_, ec);
}

void StagingDir::publish() {
  std::error_code ec;
  if (!fs::exists(fs::symlink_status(target_, ec))) {
    if (std::rename(staging_.c_str(), target_.c_str()) != 0) {
      throw std::runtime_error("cannot move the outputs to " + target_.string() + ": " + std::strerror(errno));
    }
    published_ = true;
    return;
  }
  // Replace the earlier outputs: swap atomically, else move them aside first.
  if (exchange(staging_, target_)) {
    published_ = true;
    fs::remove_all(staging_, ec);  // now holds the earlier outputs
    return;
  }
  const fs::path aside = staging_.string() + ".old";
  if (std::rename(target_.c_str(), aside.c_str()) != 0) {
    throw std::runtime_error("cannot replace " + target_.string() + ": " + std::strerror(errno));
  }
  if (std::rename(staging_.c_str(), target_.c_str()) != 0) {
    const int error = errno;
    std::rename(aside.c_str(), target_.c_str());  // put the earlier outputs back
    throw std::runtime_error("cannot move the outputs to " + target_.string() + ": " + std::strerror(error));
  }
  published_ = true;
  fs::remove_all(aside, ec);
}

}  // namespace sesi::program
