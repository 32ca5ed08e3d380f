#pragma once
/// @file analyze_command.hpp
/// `sesi analyze DIR` (docs/observables.md): the observables of a finished run from its outputs,
/// written into DIR beside them: rdf.csv (g(r)), msd.csv (mean-squared geodesic displacement),
/// vacf.csv (velocity autocorrelation), per_body.csv, and the pictures rdf.png and msd.png
/// (matplotlib). Each file appears atomically and is added to DIR's manifest, so that a run
/// repeated into DIR replaces it; a file of the same name that sesi did not write is refused.

#include <optional>
#include <string>

#include <CLI/CLI.hpp>

namespace sesi::program {

struct AnalyzeOptions {
  std::string dir;
  std::optional<double> rdf_max;  ///< default: pi R on S^n, a quarter of the bodies' extent elsewhere
  int bins = 100;
  std::optional<double> from, to;
  long every = 1;
  std::optional<long> max_lag;  ///< frames; default half the frames read
  bool picture = true;
  bool quiet = false;
};

/// Add the `analyze` subcommand to app; its values go to options.
CLI::App* add_analyze_subcommand(CLI::App& app, AnalyzeOptions& options);

/// Returns the exit status; bad input throws InputError before anything is written.
int analyze_command(const AnalyzeOptions& options);

}  // namespace sesi::program
