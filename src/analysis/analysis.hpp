#pragma once
/// @file analysis.hpp
/// Observables of a run with the space's own geometry (docs/observables.md): the radial
/// distribution function g(r) in geodesic distance, normalised by the exact shell measure; the
/// mean-squared geodesic displacement over time origins; the velocity autocorrelation with
/// parallel transport; per-body averages. They work on frames of embedding points (and
/// velocities), read from a run's outputs by read_run (trajectory.csv or trajectory.h5) or
/// handed in from Python: one library behind `sesi analyze` and `sesi.analysis`.
/// On a quotient (a periodic box on E^n, SpaceSpec::box; a compact surface H^2/Gamma,
/// SpaceSpec::genus) distances are minimum-image geodesic distances (the topology's own
/// nearest_image), g(r) is normalised by the covering space's shell over the domain's volume up to
/// the topology's largest cutoff, and the MSD follows the unwrapped positions (image counts, words).

#include <cstdint>
#include <filesystem>
#include <limits>
#include <memory>
#include <optional>
#include <string_view>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "scene.hpp"

namespace sesi::analysis {

using program::SpaceKind;
using program::SpaceSpec;

// ---- the space's topology ----------------------------------------------------------------------

/// A group element of a compact surface as a word: letters 0..4g-1 (side indices), freely
/// reduced; the body's unwrapped point is W x (include/sesi/topologies/hyperbolic_surface.hpp).
using Word = std::vector<std::int16_t>;
/// Image counts of a periodic box, dim x bodies: the unwrapped point of body b is x_b + L .* n_b.
using ImageCounts = Eigen::Matrix<std::int64_t, Eigen::Dynamic, Eigen::Dynamic>;

/// The topology's largest allowed cutoff (max_cutoff() of PeriodicBox or HyperbolicSurface:
/// below it the minimum image is unique); infinity without a topology.
/// @throws InputError when the box or genus is not one the library accepts
double max_cutoff(const SpaceSpec& space);

/// A word from its text in trajectory.csv and H5MD: "e" (the identity) or the 1-based side
/// numbers joined by '.' ("3.7.2" is g_2 g_6 g_1). @throws InputError naming the text
Word parse_word(std::string_view text, int genus);
/// The text of a word, as the outputs write it.
std::string word_text(const Word& word);

/// Each column of X (a world point) brought into the topology's domain by its isometries
/// (the box's [0, L_k); the surface's polygon); unchanged without a topology.
void reduce_into_domain(const SpaceSpec& space, Eigen::MatrixXd& X);

// ---- the space's measure ---------------------------------------------------------------------

/// Omega_{k}: the area of the unit k-sphere S^k in R^{k+1}, 2 pi^{(k+1)/2} / Gamma((k+1)/2).
double unit_sphere_area(int k);

/// The volume of the shell of geodesic radii [a, b] about a point:
/// Omega_{n-1} int_a^b s_R(s)^{n-1} ds, with s_R(s) = R sin(s/R) on S^n, R sinh(s/R) on H^n and
/// s on E^n; exact in closed form on E^n, else by 8-point Gauss-Legendre quadrature on pieces of
/// width <= R / (4 max(1, n - 1)) (error below 1e-16 relative: see shell_volume in analysis.cpp).
/// On S^n, radii beyond pi R hold nothing.
double shell_volume(const SpaceSpec& space, double a, double b);

/// S^n: the whole sphere's volume Omega_n R^n; a quotient: its domain's (the box's L_1 ... L_n,
/// the surface's 4 pi (g - 1) R^2, Gauss-Bonnet); else (H^n, E^n): the geodesic ball of radius D.
double total_volume(const SpaceSpec& space, double ball_radius = 0.0);

/// S^n: the mean squared geodesic distance of two independent uniform points, where the MSD of
/// a body that forgets its start saturates: R^2 (pi^2/2 - 2) on S^2, R^2 (pi^2/3 - 1/2) on S^3.
/// NaN on H^n and E^n (no saturation).
double msd_saturation(const SpaceSpec& space);

/// Geodesic distance of two embedding points (H^n: by radii and directions, accurate far out); on a
/// quotient, of their minimum images (x and y in the domain or near it).
double distance(const SpaceSpec& space, const Eigen::Ref<const Eigen::VectorXd>& x,
                const Eigen::Ref<const Eigen::VectorXd>& y);

/// <P v, w>: the tangent vector v at x carried to y by parallel transport along the geodesic,
/// paired with the tangent vector w at y in the space's metric (S^n, H^n: docs/observables.md;
/// E^n: v . w). S^n: NaN at exactly antipodal points, where no geodesic is unique.
double transported_dot(const SpaceSpec& space, const Eigen::Ref<const Eigen::VectorXd>& x,
                       const Eigen::Ref<const Eigen::VectorXd>& v, const Eigen::Ref<const Eigen::VectorXd>& y,
                       const Eigen::Ref<const Eigen::VectorXd>& w);

// ---- g(r) --------------------------------------------------------------------------------------

/// The region over which a frame's number density is taken on H^n and E^n: the geodesic ball
/// B(center, radius). Only bodies at least r_max inside it are centres of shells (their whole
/// shell lies in the region), and the others are counted around them at density
/// (N - 1) / volume(B).
struct Region {
  Eigen::VectorXd center;
  double radius = 0.0;
};

/// The default region of a frame on H^n and E^n: about the bodies' centre (E^n: their mean;
/// H^n: their Minkowski sum scaled back onto the hyperboloid), of the radius that holds every
/// body.
Region bounding_region(const SpaceSpec& space, const Eigen::MatrixXd& X);

/// The default largest distance of g(r): pi R on S^n (the whole sphere); on a quotient its
/// max_cutoff; on H^n and E^n a quarter of the radius of the first frame's bounding_region, so
/// that the bodies within its inner three quarters are shell centres; in all at most ten mean
/// spacings (V/N)^{1/n} (V the sphere's, the domain's or the region's volume), so that many
/// bodies still cost O(N) per frame.
double default_rdf_max(const SpaceSpec& space, const Eigen::MatrixXd& first_frame);

/// The minimum image of a quotient, shared by the observables (defined in analysis.cpp).
class Topology;

/// g(r) accumulated over frames (freud's RDF shape): bins of equal width over [0, r_max).
class Rdf {
 public:
  /// @throws InputError when r_max is not in (0, pi R] on S^n, (0, max_cutoff] on a quotient
  /// (the message names the largest) or (0, inf) elsewhere, or bins < 1
  Rdf(SpaceSpec space, double r_max, int bins);

  /// Adds one frame (columns: embedding points) through the neighbour index (O(N) for a fixed
  /// r_max and density). region: H^n and E^n only (default: bounding_region); ignored on S^n
  /// and on a quotient, where every body is a shell centre and the density is N / domain volume
  /// (the frame's points are first reduced into the domain; pairs across the box's faces or the
  /// polygon's sides come from ghost images).
  void accumulate(const Eigen::MatrixXd& X, const std::optional<Region>& region = std::nullopt);
  /// The same counts from all pairs, O(N^2): the reference of the tests.
  void accumulate_all_pairs(const Eigen::MatrixXd& X, const std::optional<Region>& region = std::nullopt);

  int bins() const { return bins_; }
  double r_max() const { return r_max_; }
  long frames() const { return frames_; }
  /// Bin edges (bins + 1) and centres.
  std::vector<double> edges() const;
  std::vector<double> centers() const;
  /// Ordered pairs (centre i, other j) with d(x_i, x_j) in each bin, over all frames.
  const std::vector<std::int64_t>& counts() const { return counts_; }
  /// The counts an ideal gas would give: sum over frames of centres x (N - 1) x shell / volume.
  const std::vector<double>& expected() const { return expected_; }
  /// counts / expected (NaN where expected is 0).
  std::vector<double> g() const;
  /// Shell centres counted over all frames.
  long centres() const { return centres_; }

 private:
  struct Frame;
  Frame prepare(const Eigen::MatrixXd& X, const std::optional<Region>& region) const;
  void add(double d);

  SpaceSpec space_;
  std::shared_ptr<const Topology> topology_;  ///< null without a topology
  double r_max_ = 0.0;
  int bins_ = 0;
  long frames_ = 0, centres_ = 0;
  std::vector<double> shell_;  ///< per bin, the exact shell volume
  std::vector<std::int64_t> counts_;
  std::vector<double> expected_;
};

// ---- dynamics ----------------------------------------------------------------------------------

/// Frames of a run: their times, embedding points (ambient x bodies) and, when the masses are
/// known, embedding velocities.
struct Frames {
  SpaceSpec space;
  std::vector<double> t;
  std::vector<Eigen::MatrixXd> x;
  std::vector<Eigen::MatrixXd> v;  ///< empty when the velocities are unknown
  std::vector<double> masses;      ///< empty when unknown
  /// E^n box: per frame, the image counts (dim x bodies). Empty otherwise.
  std::vector<ImageCounts> images;
  /// H^2 surface: per frame, per body, the word W_b. Empty otherwise.
  std::vector<std::vector<Word>> words;
  int bodies() const { return x.empty() ? 0 : static_cast<int>(x.front().cols()); }
};

/// A time correlation over lags 0..max_lag frames, averaged over all time origins and bodies.
struct Correlation {
  std::vector<double> lag_time;  ///< t[k] - t[0] of lag k (the frames are evenly spaced)
  std::vector<double> value;     ///< the mean over origins and bodies
  std::vector<long> samples;     ///< (origin, body) pairs averaged at each lag
  /// Per body: the mean over origins at the largest lag (the MSD's per-body value there).
  std::vector<double> per_body_last;
};

/// Mean-squared geodesic displacement <d(x_b(t0), x_b(t0 + lag))^2> over every time origin t0
/// and body b. max_lag < 0: half the frames. On a quotient d is the distance in the covering
/// space of the unwrapped points: on a box |(x_p - x_o) + L .* (n_p - n_o)|; on a surface
/// d(x_o, W_o^{-1} W_p x_p), the relative element taken from the words (so that a body far out
/// in the cover loses no digits). @throws InputError on a quotient without frames.images or
/// frames.words.
Correlation msd(const Frames& frames, long max_lag = -1);
/// Velocity autocorrelation <P v_b(t0), v_b(t0 + lag)> (transported_dot) over every time origin
/// and body; at lag 0, the mean squared speed (2K / m per body). Needs frames.v.
Correlation vacf(const Frames& frames, long max_lag = -1);

// ---- reading a run -------------------------------------------------------------------------------

struct ReadOptions {
  double from = -std::numeric_limits<double>::infinity();  ///< first time read (t >= from)
  double to = std::numeric_limits<double>::infinity();     ///< last time read (t <= to)
  long every = 1;                                          ///< every k-th frame of those
  bool velocities = true;                                  ///< read p and the masses for v
};

/// What summary.json says of a finished run (the space with its box or genus, the trajectory
/// file, the masses).
struct RunInfo {
  SpaceSpec space;
  std::string trajectory;  ///< "trajectory.csv" or "trajectory.h5"
  std::vector<double> masses;
  long bodies = 0;
  bool complete = true;            ///< summary.json's "complete"
  std::string status;              ///< an unfinished run's stop reason and failure message
  std::string source;              ///< the scene file as the run was given it
  std::vector<std::string> potentials;  ///< the potentials' kinds
};

/// Reads dir/summary.json; throws InputError naming dir when it is missing, not sesi's, or says
/// the run is unfinished ("complete": false) unless allow_incomplete (`sesi view` shows one).
RunInfo read_run_info(const std::filesystem::path& dir, bool allow_incomplete = false);

/// The frames of dir's trajectory (trajectory.csv, or trajectory.h5 in a build with HDF5)
/// between from and to: embedding points as written (on a quotient: in the domain, with the
/// image counts or words of the run); velocities from the chart coordinates and
/// momenta through the chart's velocity map, when the masses are known (summary.json, or
/// H5MD's particles/all/mass). Frames off the even time grid (a run's last row at a t_end off
/// it) are left out. Throws InputError with one line naming the file.
Frames read_frames(const std::filesystem::path& dir, const RunInfo& info, const ReadOptions& options);

}  // namespace sesi::analysis
