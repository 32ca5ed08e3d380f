#pragma once
/// @file exact_track.hpp
/// Scenes with a known exact solution (today the seed's, sesi::scenes::paper::Exact): the exact
/// embedding points at every output row (exact.csv) and the distance of each body from them.

#include <filesystem>
#include <vector>

#include "csv_writer.hpp"
#include "run_types.hpp"

namespace sesi::program {

class ExactTrack {
 public:
  ExactTrack(const std::filesystem::path& path, int bodies);
  /// Go on at the end of path with the errors so far (a run resumed from a checkpoint).
  ExactTrack(const std::filesystem::path& path, std::vector<double> max_error, std::vector<double> last_error);
  /// Writes the exact points at s.t and compares s.x with them.
  void row(const Snapshot& s);
  void close() { csv_.close(); }
  std::uint64_t flushed_bytes() { return csv_.flushed_bytes(); }

  /// Per body: the largest and the last distance from the exact point over the rows.
  const std::vector<double>& max_error() const { return max_error_; }
  const std::vector<double>& last_error() const { return last_error_; }

 private:
  int bodies_;
  CsvWriter csv_;
  std::vector<double> max_error_, last_error_, row_;
};

}  // namespace sesi::program
