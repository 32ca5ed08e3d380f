#pragma once
/// @file view_page.hpp
/// The viewer's page (issue #28, docs/view.md): one self-contained HTML file that plays a run's
/// trajectory in the browser. The page's template, style and scripts (src/view/page/) are
/// embedded into the binary at build time (embed_assets.cmake), so writing a page needs no file
/// at run time. The data goes into the page as a meta JSON ("format": "sesi-view 1") and one
/// text line per frame: base64 (RFC 4648) of the little-endian positions (f32 or f64), then of
/// the speeds (f32) and the jump flags (bytes), comma-separated. In stream mode the lines are
/// left out and the page fetches frames/<k> (`sesi view --serve`).

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "analysis.hpp"
#include "scene.hpp"

namespace sesi::view {

/// A diagnostic plotted under the time slider (at most max_series_points points).
struct Series {
  std::string name;
  std::vector<double> t, y;
};

/// What a page shows.
struct ViewData {
  program::SpaceSpec space;                      ///< kind, dim, radius, box, genus
  std::string title;
  std::vector<double> t;                         ///< per frame
  std::vector<Eigen::MatrixXd> x;                ///< per frame: ambient x N embedding points
  std::vector<Eigen::VectorXf> speed;            ///< per frame N speeds, or empty
  std::vector<std::vector<std::uint8_t>> jumps;  ///< per frame N flags, or empty
  std::vector<double> masses;                    ///< N or empty
  double body_radius = 0.0;                      ///< display radius in the space's units; 0: unknown
  bool complete = true;
  std::string status;                            ///< why the run is not complete
  std::vector<Series> diagnostics;
  std::string trajectory;                        ///< the file the frames came from ("" from Python)
  long thinned_from = 0;                         ///< frames before thinning; 0: not thinned
};

enum class Precision { automatic, f32, f64 };

struct PageOptions {
  Precision precision = Precision::automatic;
  bool stream = false;  ///< frames fetched from frames/<k>, not in the page
};

/// The most points a diagnostic series keeps (thin_series).
inline constexpr std::size_t max_series_points = 2000;

/// The whole page: the template with its markers replaced by the style, the meta JSON, the
/// frame lines (none in stream mode) and the scripts.
/// @throws std::logic_error when the embedded template lacks a marker or holds one twice
/// @throws program::InputError when data's sizes do not match (frames, bodies, speeds, jumps)
std::string page_html(const ViewData& data, const PageOptions& options);
/// The meta JSON alone ("</" written "<\/"), as page_html puts it in the page.
std::string meta_json(const ViewData& data, Precision resolved, bool stream);
/// Frame line k (f32 or f64 positions, then the speeds and jumps when data has them).
std::string frame_line(const ViewData& data, std::size_t k, Precision resolved);
/// The bytes of all frame lines (with their newlines), computed from the sizes alone.
std::size_t frame_bytes(const ViewData& data, Precision resolved);
/// automatic: f64 for a hyperbolic run without a genus whose bodies reach beyond 5 R from the
/// origin (x_last > R cosh 5: f32 keeps ~7 digits of x_last ~ R e^{d/R} / 2, too few to place
/// them), else f32. The other requests are returned as they are.
Precision resolve_precision(const ViewData& data, Precision requested);

/// |v|^2 of a tangent vector v in the space's metric: Euclidean on S^n (embedded isometrically in
/// R^{n+1}) and E^n; on H^n the Minkowski form v_1^2 + ... + v_n^2 - v_{n+1}^2 >= 0 (Ratcliffe,
/// Foundations of Hyperbolic Manifolds, 3.2), clamped at 0 against rounding.
double speed_squared(const program::SpaceSpec& space, const Eigen::Ref<const Eigen::VectorXd>& v);

/// The kinetic temperature of each frame, sum_b m_b |v_b|^2 / (N n) with k_B = 1 (2K over the
/// N n degrees of freedom: equipartition, Frenkel and Smit, Understanding Molecular Simulation,
/// 4.1). Needs frames.v and frames.masses; an empty series without them.
Series kinetic_temperature(const analysis::Frames& frames);

/// RFC 4648 base64 with '=' padding.
std::string base64(const void* bytes, std::size_t size);

/// Frames from analysis::Frames: speeds |v| in the space's metric (from frames.v, when known),
/// jumps where a body's image counts or word changed since the previous kept frame; thinned to
/// at most max_frames evenly spaced frames, keeping the first and the last (max_frames <= 0: all).
/// @throws program::InputError on mismatched sizes
ViewData from_frames(const analysis::Frames& frames, std::string title, long max_frames);

/// The series thinned to at most max_points: the points split into buckets of consecutive
/// points, each kept by its point of largest |y| (so spikes survive).
Series thin_series(Series series, std::size_t max_points = max_series_points);

struct ReadViewOptions {
  double from = -std::numeric_limits<double>::infinity();
  double to = std::numeric_limits<double>::infinity();
  long every = 1;
  long max_frames = 1000;
};

/// A run directory: summary.json (also an unfinished run: complete false, status its reason),
/// trajectory.csv or .h5, diagnostics.csv (the "relative energy error", or "energy error" when the
/// energy at t0 is 0, and the "kinetic temperature" written by a thermostatted run, else computed
/// from the speeds and masses), and the scene's smallest Lennard-Jones sigma for body_radius.
/// @throws program::InputError (one line naming the file) when the directory, summary.json or
/// the trajectory is missing or unreadable
ViewData read_view_data(const std::filesystem::path& dir, const ReadViewOptions& options);

}  // namespace sesi::view
