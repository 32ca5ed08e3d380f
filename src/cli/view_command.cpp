#include "view_command.hpp"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include "errors.hpp"
#include "output_dir.hpp"
#include "serve.hpp"
#include "signals.hpp"
#include "view_page.hpp"

namespace sesi::program {

namespace fs = std::filesystem;

namespace {

/// The most frame data a packed page holds: beyond it a browser struggles to open one file.
constexpr std::size_t max_page_frame_bytes = std::size_t{1} << 30;

/// text written to a hidden temporary file beside path, flushed to disk and renamed onto path,
/// so that path is either the earlier file or the whole new one. A signal meanwhile removes the
/// temporary file (signals::set_unfinished_file).
void write_atomically(const fs::path& path, const std::string& text) {
  std::string temporary = (path.parent_path() / ("." + path.filename().string() + ".sesi-XXXXXX")).string();
  const int fd = ::mkstemp(temporary.data());
  if (fd < 0) throw std::runtime_error("cannot write " + path.string() + ": " + std::strerror(errno));
  signals::set_unfinished_file(temporary.c_str());
  const char* at = text.data();
  std::size_t left = text.size();
  bool ok = true;
  while (ok && left > 0) {
    const ssize_t n = ::write(fd, at, left);
    if (n < 0 && errno == EINTR) continue;
    ok = n > 0;
    if (ok) {
      at += n;
      left -= static_cast<std::size_t>(n);
    }
  }
  const int error = ok ? 0 : errno;
  ok = ok && ::fchmod(fd, 0644) == 0 && ::fsync(fd) == 0;
  ok = ::close(fd) == 0 && ok;
  std::error_code ec;
  if (ok) fs::rename(temporary, path, ec);
  if (!ok || ec) {
    fs::remove(temporary, ec);
    signals::set_unfinished_file(nullptr);
    throw std::runtime_error("cannot write " + path.string() + ": " +
                             (error != 0 ? std::strerror(error) : ec ? ec.message() : std::strerror(errno)));
  }
  signals::set_unfinished_file(nullptr);
}

/// The notes on stderr about what the page shows: frames thinned, a run that did not finish.
void say_what_is_shown(const fs::path& dir, const view::ViewData& data) {
  if (data.thinned_from > 0) {
    std::fprintf(stderr, "sesi: note: %s: %ld frames thinned to %zu, evenly with the first and last (--max-frames)\n",
                 dir.string().c_str(), data.thinned_from, data.x.size());
  }
  if (!data.complete) {
    std::fprintf(stderr, "sesi: warning: %s: the run did not finish (%s); the page says so\n", dir.string().c_str(),
                 data.status.c_str());
  }
}

std::string megabytes(std::size_t bytes) { return format_short(static_cast<double>(bytes) / 1e6) + " MB"; }

}  // namespace

CLI::App* add_view_subcommand(CLI::App& app, ViewOptions& options) {
  CLI::App* v = app.add_subcommand(
      "view", "A run's trajectory as an interactive page for the browser (DIR/view.html), or served with --serve.");
  v->add_option("DIR", options.dir, "A run's output directory (an unfinished one too).")->type_name("DIR")->required();
  v->add_option("--out,-o", options.out, "The page's file (default DIR/view.html).")->type_name("FILE");
  v->add_option("--from", options.from, "First time shown (default: the first frame).")->type_name("T");
  v->add_option("--to", options.to, "Last time shown (default: the last frame).")->type_name("T");
  v->add_option("--every", options.every, "Every K-th frame of those, >= 1 (default 1).")->type_name("K");
  v->add_option("--max-frames", options.max_frames,
                "At most N frames, >= 1, evenly spaced with the first and the last (default 1000).")
      ->type_name("N");
  v->add_option("--precision", options.precision,
                "Positions in the page: 32 (float), 64 (double) or auto (default: 64 only for H^n runs reaching "
                "beyond 5 radii from the origin, where floats cannot place the bodies).")
      ->type_name("auto|32|64");
  v->add_flag("--serve", options.serve,
              "Serve the page on http://127.0.0.1:PORT/ with the frames fetched on demand, until Ctrl-C; writes "
              "nothing.");
  v->add_option("--port", options.port, "The --serve port, 0 to 65535 (0: a free one; default 8765).")->type_name("P");
  v->add_flag("--quiet,-q", options.quiet, "No report on stdout (--serve still prints its URL).");
  v->footer(
      "\nThe page is one HTML file that needs no network: the run's frames (base64 of little-endian\n"
      "floats), its diagnostics and the viewer's scripts are inside it. It is added to DIR's manifest,\n"
      "so a run repeated into DIR replaces it; a view.html that sesi did not write is refused. A run\n"
      "that did not finish is shown with a banner saying why. Projections, controls and the page's\n"
      "format: docs/view.md.\n"
      "\nEXIT STATUS:\n"
      "  0 done (--serve: stopped by SIGINT or SIGTERM);  2 bad argument, or DIR is not a sesi run\n"
      "    (one line on stderr, nothing written);  1 other failure (e.g. a write error).\n");
  return v;
}

int view_command(const ViewOptions& options) {
  if (options.dir.empty()) throw InputError(Origin{}, "DIR", "expected a directory, got an empty path");
  fs::path dir = options.dir;
  if (dir.filename().empty() && dir.has_relative_path()) dir = dir.parent_path();
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) {
    throw InputError(Origin{dir.string()}, "", "not a directory (expected a sesi run's output directory)");
  }
  view::Precision precision = view::Precision::automatic;
  if (options.precision == "32") {
    precision = view::Precision::f32;
  } else if (options.precision == "64") {
    precision = view::Precision::f64;
  } else if (options.precision != "auto") {
    throw InputError(Origin{}, "--precision", "expected auto, 32 or 64, got '" + cut_input(options.precision) + "'");
  }
  if (options.every < 1) throw InputError(Origin{}, "--every", "expected a whole number >= 1, got " + std::to_string(options.every));
  if (options.max_frames < 1) {
    throw InputError(Origin{}, "--max-frames", "expected a whole number >= 1, got " + std::to_string(options.max_frames));
  }
  for (const auto& [key, value] : {std::pair{"--from", options.from}, std::pair{"--to", options.to}}) {
    if (value && !std::isfinite(*value)) throw InputError(Origin{}, key, "expected a finite time");
  }
  if (options.serve && !options.out.empty()) throw InputError(Origin{}, "--out", "not with --serve, which writes nothing");
  if (!options.serve && options.port != 8765) throw InputError(Origin{}, "--port", "only with --serve");

  view::ReadViewOptions read;
  if (options.from) read.from = *options.from;
  if (options.to) read.to = *options.to;
  read.every = options.every;
  read.max_frames = options.max_frames;

  if (options.serve) {
    view::Server server(options.port);  // bound before the run is read: a busy port fails at once
    const view::ViewData data = view::read_view_data(dir, read);
    const view::Precision resolved = view::resolve_precision(data, precision);
    say_what_is_shown(dir, data);
    const std::string page = view::page_html(data, {resolved, true});
    std::printf("serving %s at http://127.0.0.1:%d/ (Ctrl-C to stop)\n", dir.string().c_str(), server.port());
    std::fflush(stdout);
    signals::begin_run();  // from now on SIGINT and SIGTERM only ask the server to stop
    server.run(page, data, resolved, [] { return signals::stop_requested().load(); });
    return exit_ok;
  }

  // Where the page goes; inside DIR it is one of the run's outputs (its manifest).
  const fs::path out = options.out.empty() ? dir / "view.html" : fs::path(options.out);
  if (out.filename().empty() || fs::is_directory(out, ec)) {
    throw InputError(Origin{}, "--out", "expected a file name, got the directory '" + cut_input(out.string()) + "'");
  }
  const fs::path parent = out.has_parent_path() ? out.parent_path() : fs::path(".");
  if (!fs::is_directory(parent, ec)) {
    throw InputError(Origin{}, "--out", "no directory " + cut_input(parent.string()) + " to write the page into");
  }
  const bool in_dir = fs::equivalent(parent, dir, ec);
  // No run may replace DIR while the page is written into it.
  DirLock lock;
  if (in_dir) lock_output_dir(lock, fs::absolute(dir, ec).lexically_normal(), dir.string());
  const view::ViewData data = view::read_view_data(dir, read);
  const std::string name = out.filename().string();
  if (in_dir) {
    if (!has_manifest(dir)) {
      throw InputError(Origin{dir.string()}, "", "has no sesi-manifest.txt: not the outputs of this sesi (--out FILE "
                                                 "writes the page elsewhere)");
    }
    if (fs::exists(fs::symlink_status(out, ec)) && !manifest_lists(dir, name)) {
      throw InputError(Origin{dir.string()}, "",
                       "holds " + name + ", which sesi did not write; move it away, or write the page elsewhere "
                       "with --out FILE");
    }
  }
  const view::Precision resolved = view::resolve_precision(data, precision);
  const std::size_t frame_bytes = view::frame_bytes(data, resolved);
  if (frame_bytes > max_page_frame_bytes) {
    throw InputError(Origin{dir.string()}, "",
                     "the page would hold " + megabytes(frame_bytes) + " of frames, more than 1 GiB: show fewer with "
                     "--every K or --max-frames N, or serve them on demand with --serve");
  }
  const std::string page = view::page_html(data, {resolved, false});
  say_what_is_shown(dir, data);
  // In the manifest first: a file that appears is then always one a rerun into DIR replaces.
  if (in_dir) add_to_manifest(dir, {name});
  write_atomically(out, page);
  if (!options.quiet) {
    const fs::path shown = fs::absolute(out, ec).lexically_normal();
    std::printf("%s: %zu frames from t = %s to %s, %ld bodies, %s (%s)\n  file://%s\n", out.string().c_str(),
                data.x.size(), format_number(data.t.front()).c_str(), format_number(data.t.back()).c_str(),
                static_cast<long>(data.x.front().cols()), megabytes(page.size()).c_str(),
                resolved == view::Precision::f64 ? "f64" : "f32", shown.c_str());
  }
  return std::fflush(stdout) == 0 ? exit_ok : exit_internal;
}

}  // namespace sesi::program
