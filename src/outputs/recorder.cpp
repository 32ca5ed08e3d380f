#include "recorder.hpp"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <functional>
#include <stdexcept>
#include <string>
#include <string_view>

#include "exact_track.hpp"
#include "output_dir.hpp"
#include "validate.hpp"
#ifdef SESI_HAVE_HDF5
#include "h5md_writer.hpp"
#endif

namespace sesi::program {

namespace {
int ambient_dim(const SpaceSpec& space) {
  return space.kind == SpaceKind::euclidean ? space.dim : space.dim + 1;
}

/// trajectory.csv's column names, one at a time (CsvWriter::HeaderNames).
void trajectory_header(const Scene& scene, const std::function<void(std::string_view)>& emit) {
  emit("t");
  const int n = scene.dim(), a = ambient_dim(scene.space);
  std::string name;
  const auto column = [&](const std::string& body, const char* what, int i) {
    name = body;
    name += what;
    name += std::to_string(i);
    emit(name);
  };
  for (int b = 1; b <= scene.body_count(); ++b) {
    const std::string body = "b" + std::to_string(b) + "_";
    for (int i = 1; i <= n; ++i) column(body, "q", i);
    for (int i = 1; i <= n; ++i) column(body, "p", i);
    for (int i = 1; i <= a; ++i) column(body, "x", i);
    // On a topology: the image counts (E^n box), or the unwrapped point and the word (H^2 surface).
    if (!scene.space.box.empty()) {
      for (int i = 1; i <= n; ++i) column(body, "n", i);
    } else if (scene.space.genus > 0) {
      for (int i = 1; i <= a; ++i) column(body, "u", i);
      emit(body + "word");
    }
  }
}

std::vector<std::string> diagnostics_header(const Scene& scene, const std::vector<std::string>& momentum_names) {
  std::vector<std::string> names{"t", "energy", "energy_error"};
  names.insert(names.end(), momentum_names.begin(), momentum_names.end());
  if (scene.thermostat) {
    for (const char* name :
         {"temperature", "kinetic_temperature", "configurational_temperature", "heat", "conserved"}) {
      names.emplace_back(name);
    }
  }
  return names;
}

}  // namespace

std::vector<std::string> momentum_names(int ambient_dim, bool translations) {
  std::vector<std::string> names;
  if (translations) {
    for (int a = 1; a <= ambient_dim; ++a) names.push_back("P" + std::to_string(a));
  }
  for (int a = 1; a <= ambient_dim; ++a) {
    for (int b = a + 1; b <= ambient_dim; ++b) names.push_back("M" + std::to_string(a) + "_" + std::to_string(b));
  }
  return names;
}

Recorder::Recorder(const Scene& scene, std::filesystem::path dir, std::vector<std::string> momentum_names)
    : scene_(scene),
      dir_(std::move(dir)),
      diagnostics_(dir_ / "diagnostics.csv", diagnostics_header(scene, momentum_names)) {
  if (scene.integrator.trajectory_format == TrajectoryFormat::h5md) {
#ifdef SESI_HAVE_HDF5
    trajectory_h5md_ = std::make_unique<H5mdWriter>(dir_ / "trajectory.h5", scene);
#else
    // parse_trajectory_format refuses "h5md" in a build without HDF5.
    throw std::logic_error("trajectory_format h5md in a build without HDF5");
#endif
  } else {
    trajectory_csv_.emplace(dir_ / "trajectory.csv",
                            [&](const std::function<void(std::string_view)>& emit) { trajectory_header(scene, emit); });
  }
  stats_.momentum_names = std::move(momentum_names);
  if (scene.exact == ExactSolution::paper) {
    exact_ = std::make_unique<ExactTrack>(dir_ / "exact.csv", scene.body_count());
  }
}

namespace {
/// dir/name as the first `bytes` bytes of from_dir/name.
void copy_prefix(const std::filesystem::path& from_dir, const std::filesystem::path& dir, const char* name,
                 std::uint64_t bytes) {
  std::error_code ec;
  const std::filesystem::path from = from_dir / name;
  const std::uintmax_t size = std::filesystem::file_size(from, ec);
  if (ec || size < bytes) {
    throw InputError(Origin{from.string()}, "",
                     ec ? "missing, but the checkpoint goes on from it"
                        : "shorter (" + std::to_string(size) + " bytes) than the checkpoint says (" +
                              std::to_string(bytes) + ")");
  }
  std::filesystem::copy_file(from, dir / name, std::filesystem::copy_options::overwrite_existing);
  std::filesystem::resize_file(dir / name, bytes);
}
}  // namespace

Recorder::Recorder(const Scene& scene, std::filesystem::path dir, std::vector<std::string> momentum_names,
                   const Checkpoint& from, const std::filesystem::path& from_dir)
    : scene_(scene),
      dir_(std::move(dir)),
      diagnostics_((copy_prefix(from_dir, dir_, "diagnostics.csv", from.outputs.diagnostics_bytes),
                    dir_ / "diagnostics.csv")) {
  if (scene.integrator.trajectory_format == TrajectoryFormat::h5md) {
#ifdef SESI_HAVE_HDF5
    trajectory_h5md_ = std::make_unique<H5mdWriter>(dir_ / "trajectory.h5", scene);
    trajectory_h5md_->replay(from_dir / "trajectory.h5", from.outputs.trajectory_frames);
#else
    throw InputError(Origin{from_dir.string()}, "", "the run writes H5MD, and this sesi is built without HDF5");
#endif
  } else {
    copy_prefix(from_dir, dir_, "trajectory.csv", from.outputs.trajectory_bytes);
    trajectory_csv_.emplace(dir_ / "trajectory.csv");
  }
  frames_ = from.outputs.trajectory_frames;
  stats_ = from.recorder.stats;
  stats_.momentum_names = std::move(momentum_names);
  tracking_ = from.recorder.tracking;
  if (scene.exact == ExactSolution::paper) {
    copy_prefix(from_dir, dir_, "exact.csv", from.outputs.exact_bytes);
    exact_ = std::make_unique<ExactTrack>(dir_ / "exact.csv", from.recorder.exact_max_error,
                                          from.recorder.exact_last_error);
  }
}

Recorder::~Recorder() = default;

RecorderState Recorder::state() const {
  RecorderState out;
  out.tracking = tracking_;
  out.stats = stats_;
  out.stats.momentum_names.clear();
  if (exact_) {
    out.exact_max_error = exact_->max_error();
    out.exact_last_error = exact_->last_error();
  }
  return out;
}

OutputCursor Recorder::cursor() {
  OutputCursor out;
  if (trajectory_csv_) out.trajectory_bytes = trajectory_csv_->flushed_bytes();
  // trajectory.h5 is not flushed here: its bytes would then depend on where checkpoints fell.
  // A resumed run reads its frames back from the file a stopped run closed (H5mdWriter::replay).
  out.trajectory_frames = frames_;
  out.diagnostics_bytes = diagnostics_.flushed_bytes();
  if (exact_) out.exact_bytes = exact_->flushed_bytes();
  return out;
}

void Recorder::track(double energy, const Eigen::VectorXd& momentum) {
  if (!tracking_) {
    tracking_ = true;
    stats_.energy_initial = energy;
    stats_.momentum_initial = momentum;
  }
  stats_.energy_final = energy;
  stats_.momentum_final = momentum;
  const double error = std::abs(energy - stats_.energy_initial);
  stats_.max_abs_energy_error = std::max(stats_.max_abs_energy_error, error);
  stats_.max_rel_energy_error = stats_.energy_initial != 0.0
                                    ? stats_.max_abs_energy_error / std::abs(stats_.energy_initial)
                                    : std::nan("");
  if (momentum.size() > 0) {
    stats_.max_momentum_drift =
        std::max(stats_.max_momentum_drift, (momentum - stats_.momentum_initial).cwiseAbs().maxCoeff());
  }
}

void Recorder::track_conserved(double conserved) {
  if (!stats_.conserved_tracking) {
    stats_.conserved_tracking = true;
    stats_.conserved_initial = conserved;
  }
  stats_.conserved_final = conserved;
  // (NaN for brownian, which conserves nothing: the drift stays NaN.)
  const double drift = std::abs(conserved - stats_.conserved_initial);
  stats_.max_abs_conserved_drift = std::isnan(drift) ? drift : std::max(stats_.max_abs_conserved_drift, drift);
}

void Recorder::write_row(const Snapshot& s) {
  // Across ranks the other ranks serve s's columns until the row is written (for_each_block).
  const ServedUntil served(s);
  const bool hyperbolic = scene_.space.kind == SpaceKind::hyperbolic;
  // The distance from the chart's origin: R acosh(x_time / R), time-like coordinate last.
  const auto farthest = [&](const BodyBlock::Map& x) {
    const double radius = scene_.space.radius;
    for (Eigen::Index b = 0; b < x.cols(); ++b) {
      const double far = radius * std::acosh(std::max(1.0, x(x.rows() - 1, b) / radius));
      stats_.max_distance = std::max(stats_.max_distance, far);
    }
  };
  bool measured = false;  // whether a pass over the points took the distances
  if (trajectory_csv_ && !scene_.space.has_topology()) {
    // In blocks of bodies (a row of 10^6 bodies would be 56 MB of doubles held at once).
    CsvWriter& csv = *trajectory_csv_;
    csv.begin_row();
    csv.number(s.t);
    for_each_block(s, field_q | field_p | field_x, [&](const BodyBlock& block) {
      const auto q = block.q(), p = block.p(), x = block.x();
      row_.clear();
      for (Eigen::Index b = 0; b < block.count; ++b) {
        row_.insert(row_.end(), q.col(b).data(), q.col(b).data() + q.rows());
        row_.insert(row_.end(), p.col(b).data(), p.col(b).data() + p.rows());
        row_.insert(row_.end(), x.col(b).data(), x.col(b).data() + x.rows());
      }
      csv.numbers(row_);
      if (hyperbolic) farthest(x);
    });
    measured = true;
    csv.end_row();
  } else if (trajectory_csv_) {
    check_topology(s);
    CsvWriter& csv = *trajectory_csv_;
    csv.begin_row();
    csv.number(s.t);
    const auto numbers = [&](const auto& column) {
      for (Eigen::Index i = 0; i < column.size(); ++i) csv.number(column(i));
    };
    for_each_block(s, field_q | field_p | field_x | field_n, [&](const BodyBlock& block) {
      const auto q = block.q(), p = block.p(), x = block.x();
      const auto n = block.image_counts();
      for (Eigen::Index k = 0; k < block.count; ++k) {
        const Eigen::Index b = block.first + k;
        numbers(q.col(k));
        numbers(p.col(k));
        numbers(x.col(k));
        if (!scene_.space.box.empty()) {
          for (Eigen::Index i = 0; i < n.rows(); ++i) csv.integer(n(i, k));
        } else {
          // (A surface: its words and unwrapped points whole, across ranks too: DomainIntegrator::own_state.)
          numbers(s.unwrapped.col(b));
          csv.text(word_text(s.words[static_cast<std::size_t>(b)]));
        }
      }
      if (hyperbolic) farthest(x);
    });
    measured = true;
    csv.end_row();
  }
#ifdef SESI_HAVE_HDF5
  if (trajectory_h5md_ && s.gather) {
    // Across ranks the frame is put together on rank 0 (H5mdWriter writes each dataset's frame
    // in one piece, so that the file's chunks are laid out as one process lays them).
    Snapshot whole;
    whole.step = s.step;
    whole.t = s.t;
    whole.energy = s.energy;
    whole.thermostat = s.thermostat;
    whole.temperature = s.temperature;
    whole.kinetic_temperature = s.kinetic_temperature;
    whole.heat = s.heat;
    whole.conserved = s.conserved;
    whole.configurational = s.configurational;
    const Eigen::Index bodies = body_count(s);
    whole.q.resize(s.q.rows(), bodies);
    whole.p.resize(s.p.rows(), bodies);
    whole.x.resize(s.x.rows(), bodies);
    whole.image_counts.resize(s.image_counts.rows(), s.image_counts.rows() > 0 ? bodies : 0);
    whole.words = s.words;  // (a surface's: whole on rank 0 already)
    whole.unwrapped = s.unwrapped;
    for_each_block(s, field_q | field_p | field_x | field_n, [&](const BodyBlock& block) {
      whole.q.middleCols(block.first, block.count) = block.q();
      whole.p.middleCols(block.first, block.count) = block.p();
      whole.x.middleCols(block.first, block.count) = block.x();
      if (block.n_rows > 0) whole.image_counts.middleCols(block.first, block.count) = block.image_counts();
      if (hyperbolic && !measured) farthest(block.x());
    });
    measured = true;
    trajectory_h5md_->write(whole);
  } else if (trajectory_h5md_) {
    trajectory_h5md_->write(s);
  }
#endif
  if (hyperbolic && !measured) for_each_block(s, field_x, [&](const BodyBlock& block) { farthest(block.x()); });
  row_.assign({s.t, s.energy, s.energy - stats_.energy_initial});
  row_.insert(row_.end(), s.momentum.data(), s.momentum.data() + s.momentum.size());
  if (scene_.thermostat) {
    row_.insert(row_.end(),
                {s.temperature, s.kinetic_temperature, s.configurational_temperature(), s.heat, s.conserved});
    ++stats_.thermostat_rows;
    stats_.sum_kinetic_temperature += s.kinetic_temperature;
    // (A row without them, NaN: a failed run's last, or a potential with no Laplacian.)
    if (!std::isnan(s.configurational[1])) {
      stats_.sum_grad_squared += s.configurational[0];
      stats_.sum_laplacian += s.configurational[1];
    }
    stats_.heat = s.heat;
  }
  diagnostics_.row(row_);
  if (exact_) exact_->row(s);
  ++frames_;
}

void Recorder::check_topology(const Snapshot& s) const {
  // The run loop fills them in on a topology (run_loop.cpp, observe_topology).
  const auto bodies = static_cast<Eigen::Index>(scene_.body_count());
  // (Across ranks a rank's snapshot holds its own bodies.)
  const auto held = s.gather ? static_cast<Eigen::Index>(s.ids.size()) : bodies;
  const bool fits = !scene_.space.box.empty()
                        ? s.image_counts.rows() == scene_.dim() && s.image_counts.cols() == held
                        : static_cast<Eigen::Index>(s.words.size()) == bodies && s.unwrapped.cols() == bodies &&
                              s.unwrapped.rows() == s.x.rows();
  if (!fits) throw std::logic_error("Recorder::write_row: a snapshot without its topology's images");
}

void Recorder::set_final(Snapshot last) { final_ = std::move(last); }

std::vector<double> Recorder::max_exact_error() const {
  return exact_ ? exact_->max_error() : std::vector<double>{};
}

void Recorder::release_final() {
  if (final_released_) return;
  final_released_ = true;
  const ServedUntil served(final_);
}

void Recorder::finish(const RunOutcome& outcome, double wall_seconds, int ranks) {
  // Across ranks the other ranks serve the final state's columns until the summary is written
  // (or this failed before it).
  struct Release {
    Recorder& r;
    ~Release() { r.release_final(); }
  } release{*this};
  if (trajectory_csv_) trajectory_csv_->close();
#ifdef SESI_HAVE_HDF5
  if (trajectory_h5md_) trajectory_h5md_->close();
#endif
  diagnostics_.close();
  ExactStats exact;
  if (exact_) {
    exact_->close();
    exact.solution = "paper";
    exact.max_position_error = exact_->max_error();
    exact.final_position_error = exact_->last_error();
  }
  const long planned = step_count(*scene_.integrator.t_end, *scene_.integrator.dt);
  const SummaryData data{scene_, outcome, planned, wall_seconds, stats_, final_, exact, ranks};
  write_summary(data, dir_ / "summary.json");
}

}  // namespace sesi::program
