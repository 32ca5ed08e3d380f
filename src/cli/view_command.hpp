#pragma once
/// @file view_command.hpp
/// `sesi view DIR` (issue #28, docs/view.md): a run's trajectory as one self-contained page,
/// DIR/view.html (src/view/view_page.hpp), written atomically and added to DIR's manifest like
/// `sesi analyze`'s outputs; or, with --serve, served on 127.0.0.1 with frames fetched on demand.

#include <optional>
#include <string>

#include <CLI/CLI.hpp>

namespace sesi::program {

struct ViewOptions {
  std::string dir;
  std::string out;  ///< default DIR/view.html
  std::optional<double> from, to;
  long every = 1;
  long max_frames = 1000;
  std::string precision = "auto";  ///< auto, 32 or 64
  bool serve = false;
  int port = 8765;
  bool quiet = false;
};

/// Add the `view` subcommand to app; its values go to options.
CLI::App* add_view_subcommand(CLI::App& app, ViewOptions& options);

/// Returns the exit status; bad input throws InputError before anything is written.
int view_command(const ViewOptions& options);

}  // namespace sesi::program
