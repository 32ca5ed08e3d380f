#pragma once
/// @file h5md_writer.hpp
/// The trajectory as an H5MD 1.1 file (https://nongnu.org/h5md/h5md.html), written frame by
/// frame into extensible, chunked, compressed datasets (HDF5's C API; built with SESI_HAVE_HDF5):
///
///   h5md                      version [1, 1]; author/name, creator/name, creator/version
///   particles/all/box         dimension = D (ambient), boundary = ["none"] * D; on an E^n box
///                             boundary = ["periodic"] * D and edges [D]; on an H^2 surface the
///                             attributes sesi_topology = "hyperbolic-surface", genus, radius
///   particles/all/position    step [frames], time [frames], value [frames][N][D]: embedding x
///   particles/all/chart_position  value [frames][N][dim]: chart q (step, time: hard links)
///   particles/all/chart_momentum  value [frames][N][dim]: momenta p (likewise)
///   particles/all/image       value [frames][N][dim], int64: an E^n box's image counts (likewise)
///   particles/all/unwrapped_position  value [frames][N][3]: an H^2 surface's u = W x (likewise)
///   particles/all/word        value [frames][N], variable-length strings: its words (likewise)
///   particles/all/mass        [N]
///   observables/energy        value [frames] (likewise)
///   observables/temperature, kinetic_temperature, configurational_temperature, heat, conserved
///                             value [frames] (likewise): a thermostatted run's, as in diagnostics.csv
///   parameters                space, dim, radius (S^n, H^n) as attributes
///
/// The numbers are the doubles of trajectory.csv, bit for bit. HDF5 failures throw
/// std::runtime_error naming the file.

#include <filesystem>
#include <memory>

#include "run_types.hpp"
#include "scene.hpp"

namespace sesi::program {

class H5mdWriter {
 public:
  /// Creates (truncates) path and the layout above, with no frames yet.
  H5mdWriter(const std::filesystem::path& path, const Scene& scene);
  /// Closes quietly (a run that failed before finish()).
  ~H5mdWriter();
  H5mdWriter(const H5mdWriter&) = delete;
  H5mdWriter& operator=(const H5mdWriter&) = delete;

  /// Appends one frame: step, t, x, q, p, the topology's images and the energy of s.
  void write(const Snapshot& s);
  /// Writes again, through write(), the first `frames` frames of the earlier file `from` (a run
  /// resumed from a checkpoint): the same calls with the same numbers as the uninterrupted run's,
  /// so the same bytes. Throws InputError when `from` cannot be read or has fewer frames.
  void replay(const std::filesystem::path& from, unsigned long long frames);
  /// Flushes and closes; throws if anything failed to reach the file.
  void close();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace sesi::program
