#include "domain_integrator.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <string>
#include <utility>
#include <variant>
#include <vector>

#include <sesi/diagnostics.hpp>
#include <sesi/neighbours.hpp>
#include <sesi/parallel.hpp>

#include "errors.hpp"
#include "geometry.hpp"
#include "run_types.hpp"

namespace sesi::program {

namespace {

using Word = std::vector<std::int16_t>;  // a compact surface's group word (HyperbolicSurface::Word)

/// A word's letters as a message of doubles carries them (exact: letters are below 4g <= 64).
Word word_of(const double* letters, std::size_t count) {
  Word word(count);
  for (std::size_t i = 0; i < count; ++i) word[i] = static_cast<std::int16_t>(letters[i]);
  return word;
}

/// The domain's skin: twice the Verlet lists' (at least twice their default), a fraction of
/// the cutoff. A cut costs more than a list rebuild (the bodies change ranks, each rank's
/// integrator starts again), so the slabs are cut half as often, for a halo 2 skins wider.
double domain_skin(const Scene& scene) {
  return 2.0 * std::max(scene.integrator.neighbour_skin, sesi::default_skin_fraction) * short_range_cutoff(scene);
}
/// The halo's width about a slab: the cutoff and two domain skins (0 without a cutoff).
double halo_width(const Scene& scene) {
  const double cutoff = short_range_cutoff(scene);
  return cutoff > 0.0 ? cutoff + 2.0 * domain_skin(scene) : 0.0;
}

/// What of scene a run across ranks cannot hold yet, or empty.
std::string unsupported(const Scene& scene) {
  if (scene.space.genus != 0) {
    // A body's partners on the surface are images of bodies in D within the halo of D: they
    // must lie in the star of D (HyperbolicSurface::images, star_margin), and so must a body
    // wrapped back into D since the cut (its move is measured on its nearest image).
    const sesi::HyperbolicSurface<double> surface(scene.space.genus, scene.space.radius);
    const double reach = halo_width(scene) + wrap_margin(scene, surface.max_cutoff());
    if (!(reach < surface.star_margin())) {
      char line[256];
      std::snprintf(line, sizeof line,
                    "a compact hyperbolic surface this small for its cutoff (the ranks' halo and the wrap's "
                    "margin reach %.4g from the polygon, past its neighbouring tiles, which end %.4g from it)",
                    reach, surface.star_margin());
      return line;
    }
  }
  // Below System::rows_from bodies one process sums pairs in another order (the symmetric loop).
  if (scene.body_count() < parallel::min_parallel_bodies) {
    return "fewer than " + std::to_string(parallel::min_parallel_bodies) + " bodies";
  }
  return {};
}

/// The squared chord of two points in the ambient metric (Euclidean; Minkowski on H^n, whose last
/// coordinate is time), a monotone function of their distance; in a periodic box, of the nearest
/// images (a body wrapped into the box moved by less than its jump).
double chord2(const SpaceSpec& space, const Eigen::VectorXd& x, const Eigen::VectorXd& y) {
  Eigen::VectorXd u = x - y;
  for (std::size_t k = 0; k < space.box.size(); ++k) {
    const double L = space.box[k];
    u[static_cast<Eigen::Index>(k)] -= L * std::nearbyint(u[static_cast<Eigen::Index>(k)] / L);
  }
  if (space.kind != SpaceKind::hyperbolic) return u.squaredNorm();
  const Eigen::Index t = u.size() - 1;
  return u.head(t).squaredNorm() - u[t] * u[t];
}

/// The slabs of one cut: every body's rank, each rank's slab [lo, hi] of the cut coordinate, and
/// the halo's width about it.
struct Slabs {
  // A compact surface: the cut coordinate of each body's other images within the halo's width of
  // the polygon D (HyperbolicSurface::images_near), body b's at [image_from[b], image_from[b + 1]).
  std::vector<std::size_t> image_from;
  std::vector<double> image_keys;
  int axis = 0;
  std::vector<double> key;  // by body: the cut coordinate of its world point
  std::vector<int> owner;   // by body
  std::vector<double> lo, hi;
  double halo = 0.0;
  double period = 0.0;  // a periodic box's edge along the axis (0: none)
  /// Whether rank r holds body b (as its own or in its halo): within the halo of its slab, or in a
  /// box of one of the slab's images a period away.
  bool holds(int r, int b) const {
    if (owner[static_cast<std::size_t>(b)] == r) return true;
    const double k = key[static_cast<std::size_t>(b)];
    const double l = lo[static_cast<std::size_t>(r)] - halo, h = hi[static_cast<std::size_t>(r)] + halo;
    if (k >= l && k <= h) return true;
    if (period > 0.0 && ((k + period >= l && k + period <= h) || (k - period >= l && k - period <= h))) return true;
    if (image_from.empty()) return false;
    for (std::size_t i = image_from[static_cast<std::size_t>(b)]; i < image_from[static_cast<std::size_t>(b) + 1]; ++i) {
      if (image_keys[i] >= l && image_keys[i] <= h) return true;
    }
    return false;
  }
};

/// Cut world points X (ambient x bodies) into `ranks` slabs of equal count along the coordinate
/// of widest extent (ties: the body order), with a halo of width `halo`. A function of X alone:
/// every rank cuts alike.
///
/// The coordinate differs between two bodies by at most their distance, as the halo needs: on
/// S^n and E^n a Cartesian coordinate of the points (bounded by their chord); on H^n, of the
/// points in the cluster frame, the signed distance R asinh(x_k / R) from the hyperplane x_k = 0
/// (a totally geodesic one: a distance from it is 1-Lipschitz), k a space coordinate.
/// On a compact surface (`surface`) the same of each point reduced into D, and of its images
/// within the halo's width of D: bodies at a distance d on the surface have points y_a, y_b in
/// D and an element gamma with d(y_a, gamma y_b) = d, so gamma y_b is within d of D, one of the
/// star's images (d < star_margin: unsupported()), and its coordinate within d of y_a's.
Slabs cut(const SpaceSpec& space, const sesi::HyperbolicSurface<double>* surface, const Eigen::MatrixXd& X,
          int ranks, double halo) {
  Slabs s;
  s.halo = halo;
  const int n = static_cast<int>(X.cols());
  const bool hyperbolic = space.kind == SpaceKind::hyperbolic;
  const int axes = static_cast<int>(X.rows()) - (hyperbolic ? 1 : 0);
  double widest = -1.0;
  for (int r = 0; r < axes; ++r) {
    // (A periodic box: its longest edge, the first of equals.)
    const double extent = space.box.empty() ? X.row(r).maxCoeff() - X.row(r).minCoeff()
                                            : space.box[static_cast<std::size_t>(r)];
    if (extent > widest) {  // (NaN: not taken)
      widest = extent;
      s.axis = r;
    }
  }
  if (!space.box.empty()) s.period = space.box[static_cast<std::size_t>(s.axis)];
  s.key.resize(static_cast<std::size_t>(n));
  const auto key = [&](double x) {
    const double k = hyperbolic ? space.radius * std::asinh(x / space.radius) : x;
    return std::isnan(k) ? std::numeric_limits<double>::infinity() : k;
  };
  Eigen::Vector3d y;
  Word applied;
  std::vector<int> near;
  // A point y of D within inradius - halo of the centre o has no other image within the halo of D:
  // gamma y (gamma not 1) lies in the tile gamma D, as far from D as y is from D's sides, at least
  // inradius - d(o, y). Its time coordinate R cosh(d(o, y) / R) tells (a few eps of room).
  double interior = -std::numeric_limits<double>::infinity();
  if (surface && surface->inradius() > halo) {
    interior = space.radius * std::cosh((surface->inradius() - halo) / space.radius) *
               (1.0 - 64.0 * std::numeric_limits<double>::epsilon());
  }
  if (surface) s.image_from.assign(1, 0);
  for (int b = 0; b < n; ++b) {
    if (surface) {
      // (A body may be out of D until the bodies are wrapped.)
      y = X.col(b);
      surface->reduce(y, applied);
      s.key[static_cast<std::size_t>(b)] = key(y[s.axis]);
      near.clear();
      if (!(y[2] < interior)) surface->images_near(y, halo, near);
      for (const int k : near) {
        if (k != 0) s.image_keys.push_back(key((surface->images()[static_cast<std::size_t>(k)] * y)[s.axis]));
      }
      s.image_from.push_back(s.image_keys.size());
      continue;
    }
    double k = X(s.axis, b);
    // A box: the coordinate in [0, L) (a body may be out of the box until the bodies are wrapped).
    if (s.period > 0.0) k -= s.period * std::floor(k / s.period);
    s.key[static_cast<std::size_t>(b)] = key(k);
  }
  std::vector<int> order(static_cast<std::size_t>(n));
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](int a, int b) {
    const double ka = s.key[static_cast<std::size_t>(a)], kb = s.key[static_cast<std::size_t>(b)];
    return ka < kb || (ka == kb && a < b);
  });
  s.owner.resize(static_cast<std::size_t>(n));
  s.lo.assign(static_cast<std::size_t>(ranks), std::numeric_limits<double>::infinity());
  s.hi.assign(static_cast<std::size_t>(ranks), -std::numeric_limits<double>::infinity());
  for (int k = 0; k < n; ++k) {
    const int r = static_cast<int>(static_cast<long long>(k) * ranks / n);
    const int b = order[static_cast<std::size_t>(k)];
    s.owner[static_cast<std::size_t>(b)] = r;
    s.lo[static_cast<std::size_t>(r)] = std::min(s.lo[static_cast<std::size_t>(r)], s.key[static_cast<std::size_t>(b)]);
    s.hi[static_cast<std::size_t>(r)] = std::max(s.hi[static_cast<std::size_t>(r)], s.key[static_cast<std::size_t>(b)]);
  }
  return s;
}

/// A run's snapshots across ranks (Snapshot::gather): rank 0 asks for a block of bodies (a
/// request broadcast: fields, first, count; none: done), each rank sends its own bodies in it
/// ([index, fields] a body), and rank 0 puts them in body order.
class RankGather final : public BodyGather {
 public:
  RankGather(const Ranks& ranks, int bodies) : ranks_(ranks), n_(bodies) {}
  void fetch(const Snapshot& s, unsigned fields, Eigen::Index first, Eigen::Index count,
             std::vector<double>& out) const override {
    std::vector<double> request{static_cast<double>(fields), static_cast<double>(first), static_cast<double>(count)};
    ranks_.from_root(request);
    answer(s, fields, first, count, &out);
  }
  void done() const override {
    std::vector<double> none;
    ranks_.from_root(none);
  }
  void serve(const Snapshot& s) const override {
    std::vector<double> request;
    for (;;) {
      request.clear();
      ranks_.from_root(request);
      if (request.size() != 3) return;
      answer(s, static_cast<unsigned>(request[0]), static_cast<Eigen::Index>(request[1]),
             static_cast<Eigen::Index>(request[2]), nullptr);
    }
  }
  Eigen::Index bodies() const override { return n_; }
  bool root() const override { return ranks_.root(); }
  double shared(double value) const override { return ranks_.from_root(value); }

 private:
  void answer(const Snapshot& s, unsigned fields, Eigen::Index first, Eigen::Index count, std::vector<double>* out) const {
    std::vector<std::pair<const double*, Eigen::Index>> parts;  // each field's data and rows
    for (const auto& [field, m] : {std::pair{field_q, &s.q}, std::pair{field_p, &s.p}, std::pair{field_x, &s.x},
                                   std::pair{field_v, &s.v}}) {
      if ((fields & field) != 0) parts.emplace_back(m->data(), m->rows());
    }
    const Eigen::Index rn = (fields & field_n) != 0 ? s.image_counts.rows() : 0;
    Eigen::Index stride = rn;
    for (const auto& part : parts) stride += part.second;
    mine_.clear();
    const auto lo = std::lower_bound(s.ids.begin(), s.ids.end(), first);
    const auto hi = std::lower_bound(lo, s.ids.end(), first + count);
    for (auto at = lo; at != hi; ++at) {
      const Eigen::Index k = at - s.ids.begin();
      mine_.push_back(*at);
      for (const auto& [data, rows] : parts) mine_.insert(mine_.end(), data + rows * k, data + rows * (k + 1));
      for (Eigen::Index i = 0; i < rn; ++i) mine_.push_back(static_cast<double>(s.image_counts(i, k)));
    }
    ranks_.gather(mine_, all_, counts_);
    if (!out) return;
    out->assign(static_cast<std::size_t>(stride * count), 0.0);
    std::size_t placed = 0;
    for (std::size_t at = 0; at + static_cast<std::size_t>(stride) < all_.size() + 1; at += static_cast<std::size_t>(stride + 1)) {
      const auto b = static_cast<Eigen::Index>(all_[at]) - first;
      if (b < 0 || b >= count) break;
      std::copy_n(all_.data() + at + 1, stride, out->data() + b * stride);
      ++placed;
    }
    if (placed != static_cast<std::size_t>(count) || all_.size() != placed * static_cast<std::size_t>(stride + 1)) {
      std::fprintf(stderr, "sesi: rank 0: a block of bodies gathered from the ranks is not whole\n");
      ranks_.abort(3);
    }
  }

  const Ranks& ranks_;
  int n_;
  mutable std::vector<double> mine_, all_;  // one block's, reused
  mutable std::vector<int> counts_;
};

class DomainIntegrator final : public Integrator {
 public:
  DomainIntegrator(const Scene& scene, const Ranks& ranks)
      : scene_(scene), ranks_(ranks), geometry_(scene.space), n_(scene.body_count()), gather_(ranks, n_) {
    // (Member by member: a copy of the whole scene would copy its bodies once more.)
    shape_.name = scene.name;
    shape_.source = scene.source;
    shape_.space = scene.space;
    shape_.potentials = scene.potentials;
    shape_.integrator = scene.integrator;
    shape_.exact = scene.exact;
    shape_.thermostat = scene.thermostat;
    for (const PotentialSpec& spec : scene.potentials) {
      long_range_ = long_range_ || std::holds_alternative<CotangentGravitySpec>(spec) ||
                    std::holds_alternative<HarmonicPairSpec>(spec) || std::holds_alternative<ChordWellSpec>(spec);
    }
    const double cutoff = short_range_cutoff(scene), skin = domain_skin(scene);
    halo_width_ = halo_width(scene);
    const double half = geometry_.chord_of_distance(0.5 * skin), whole = geometry_.chord_of_distance(skin);
    recut2_ = cutoff > 0.0 ? half * half : std::numeric_limits<double>::infinity();
    broken2_ = cutoff > 0.0 ? whole * whole : std::numeric_limits<double>::infinity();
    skin_ = skin;
    if (scene.space.kind == SpaceKind::hyperbolic) {
      // H^n: one process's start puts the bodies in a cluster frame at their centre (or at a
      // force centre), a function of all of them: each rank starts the whole scene once and
      // takes its bodies from that state.
      const FramedState start = make_integrator(scene)->framed_state();
      take(start);
      return;
    }
    // The scene's bodies, as one process starts them (each rank its own and its halo's).
    Eigen::MatrixXd X(geometry_.ambient_dim(), n_);
    for (int b = 0; b < n_; ++b) X.col(b) = geometry_.embed(scene.bodies[static_cast<std::size_t>(b)].q);
    begin(cut(scene_.space, geometry_.surface(), X, ranks_.size(), halo_width_), X, nullptr);
  }

  void step(double t, double h) override {
    try {
      local_->step(t, h);
    } catch (const std::exception& e) {
      // The other ranks wait in this step's exchanges: end them all.
      std::fprintf(stderr, "sesi: rank %d: %s\n", ranks_.rank(), e.what());
      ranks_.abort(3);
    }
    refresh_halo();
    if (!same(local_->cluster(), cluster_)) {
      // H^n: the cluster frame was re-centred (alike on every rank), and with it every body's
      // point in it: cut again where the bodies are in the new frame.
      const Eigen::MatrixXd all = local_->local_points();
      moved_.resize(all.rows(), static_cast<Eigen::Index>(own_.size()));
      for (std::size_t k = 0; k < own_.size(); ++k) moved_.col(static_cast<Eigen::Index>(k)) = all.col(own_[k]);
      recut();
      return;
    }
    // How far the bodies moved since the cut, at the step's last force evaluation.
    local_->kicked_points(own_, moved_);
    double most = 0.0;
    for (Eigen::Index k = 0; k < moved_.cols(); ++k) {
      const double d2 = moved2(moved_.col(k), start_.col(k));
      if (d2 > most) most = d2;  // (NaN: the run's finiteness check stops it)
    }
    most = ranks_.max(most);
    if (most > broken2_) {
      throw InvariantFailure("a body moved more than the domain skin (" + std::to_string(skin_) +
                             ") since the bodies last changed rank: a step may have missed a pair; take a "
                             "smaller dt or a larger neighbour_skin");
    }
    if (most > recut2_) recut();
  }

  void read(Eigen::MatrixXd& q, Eigen::MatrixXd& p) const override {
    Eigen::MatrixXd lq, lp;
    local_->read(lq, lp);
    q = gathered(lq);
    p = gathered(lp);
  }
  int first_non_finite_body() const override {
    const int b = local_->first_non_finite_body();
    return first_body(b);
  }
  double energy() override { return local_->energy(); }
  Eigen::VectorXd momentum_map() override {
    // As sesi::momentum_map, in the frame the bodies are held in (a cluster frame's on H^n), then
    // taken to the world. Each component is a sum over bodies in body order of one term a body
    // (sesi::momentum_map_of): each rank forms its own bodies' terms, and the sums go through the
    // domain's sum (rank 0, body order: one process's bits), so no rank holds every body's point.
    Eigen::MatrixXd lx, lv;
    local_->frame_points(lx, lv);
    const bool translations = scene_.space.kind == SpaceKind::euclidean;
    // Each own body's term formed as its block of bodies is summed (sum_own), never all at once.
    Eigen::MatrixXd x(lx.rows(), 1), v(lv.rows(), 1);
    const auto term = [&](std::size_t k, double* out) {
      const int l = own_[k];
      x = lx.col(l);
      v = lv.col(l);
      const double m = scene_.bodies[static_cast<std::size_t>(ids_[static_cast<std::size_t>(l)])].mass;
      // (One body's map: 0 + its term, the term itself; a sum from +0 never meets -0.)
      const Eigen::VectorXd t = sesi::momentum_map_of(x, v, [m](int) { return m; }, translations);
      std::copy_n(t.data(), t.size(), out);
    };
    // (sesi::momentum_map_of's count: every rank knows it, whatever it owns.)
    const auto a = static_cast<int>(lx.rows());
    const std::vector<double> sums = sum_own(a * (a - 1) / 2 + (translations ? a : 0), term);
    Eigen::VectorXd out = Eigen::Map<const Eigen::VectorXd>(sums.data(), static_cast<Eigen::Index>(sums.size()));
    return local_->momentum_in_world(out);
  }
  Eigen::MatrixXd points() override { return gathered(local_->points()); }
  Eigen::MatrixXd points_of(const std::vector<int>& bodies, bool local) override {
    std::vector<double> wanted(bodies.begin(), bodies.end());  // rank 0's, to every rank
    ranks_.from_root(wanted);
    if (wanted.empty()) return {};
    const Eigen::MatrixXd all = local ? local_->local_points() : local_->points();
    std::vector<double> mine, got;
    std::vector<int> counts;
    for (std::size_t k = 0; k < wanted.size(); ++k) {
      const auto at = std::lower_bound(ids_.begin(), ids_.end(), static_cast<int>(wanted[k]));
      if (at == ids_.end() || *at != static_cast<int>(wanted[k]) || !owned_[static_cast<std::size_t>(at - ids_.begin())]) continue;
      mine.push_back(static_cast<double>(k));
      const Eigen::Index l = at - ids_.begin();
      mine.insert(mine.end(), all.col(l).data(), all.col(l).data() + all.rows());
    }
    ranks_.gather(mine, got, counts);
    if (!ranks_.root()) return {};
    Eigen::MatrixXd out(all.rows(), static_cast<Eigen::Index>(wanted.size()));
    for (std::size_t at = 0; at < got.size(); at += static_cast<std::size_t>(all.rows() + 1)) {
      out.col(static_cast<Eigen::Index>(got[at])) = Eigen::Map<const Eigen::VectorXd>(got.data() + at + 1, all.rows());
    }
    return out;
  }
  bool own_state(Snapshot& s) override {
    // The own bodies' columns of what the outputs see (one process's read, points, velocities
    // and image counts of the same bodies, bit for bit: the same functions of the same state).
    Eigen::MatrixXd q, p;
    local_->read(q, p);
    s.q = q(Eigen::all, own_);
    s.p = p(Eigen::all, own_);
    q.resize(0, 0);
    p.resize(0, 0);
    s.x = local_->points()(Eigen::all, own_);
    s.v = local_->velocities()(Eigen::all, own_);
    const auto counts = local_->image_counts();
    s.image_counts.resize(0, 0);
    if (counts.size() != 0) s.image_counts = counts(Eigen::all, own_);
    if (geometry_.surface()) {
      // A surface's words and unwrapped points whole on rank 0 (the outputs read them by body):
      // 3 numbers and a word a body, beside the blocks of the other fields.
      s.words = gathered_words(local_->words());
      s.unwrapped = gathered(local_->unwrapped_points());
    }
    s.ids.clear();
    for (const int l : own_) s.ids.push_back(ids_[static_cast<std::size_t>(l)]);
    s.gather = &gather_;
    return true;
  }
  Eigen::Matrix<std::int64_t, Eigen::Dynamic, Eigen::Dynamic> image_counts() const override {
    const auto local = local_->image_counts();
    if (local.size() == 0) return {};
    return gathered(local.cast<double>()).cast<std::int64_t>();  // (exact below 2^53)
  }
  Eigen::MatrixXd unwrapped_points() override { return gathered(local_->unwrapped_points()); }
  Eigen::MatrixXd velocities() override { return gathered(local_->velocities()); }
  // (The cluster frame is the same on every rank: each re-centres alike, from the same sums.)
  bool clustered() const override { return local_->clustered(); }
  Eigen::MatrixXd local_points() override { return gathered(local_->local_points()); }
  Eigen::VectorXd to_local(const Eigen::VectorXd& world) const override { return local_->to_local(world); }
  bool listed_close_pairs(double reach, std::vector<std::pair<int, int>>& out) override {
    std::vector<std::pair<int, int>> local;
    const bool listed = local_->listed_close_pairs(reach, local);
    if (ranks_.any(!listed)) return false;  // every rank then leaves it to the caller's search
    // Each pair once: by the rank that owns its first body (whose halo holds the second).
    std::vector<double> mine, all;
    std::vector<int> counts;
    for (const auto& pair : local) {
      if (!owned_[static_cast<std::size_t>(pair.first)]) continue;
      mine.push_back(ids_[static_cast<std::size_t>(pair.first)]);
      mine.push_back(ids_[static_cast<std::size_t>(pair.second)]);
    }
    ranks_.gather(mine, all, counts);
    out.clear();
    for (std::size_t k = 0; k + 1 < all.size(); k += 2) {
      out.emplace_back(static_cast<int>(all[k]), static_cast<int>(all[k + 1]));
    }
    std::sort(out.begin(), out.end());  // one process's order: rows, then partners, ascending
    return true;
  }
  FramedState framed_state() const override {
    // Each piece of this rank's state, its own bodies' columns gathered by rank 0 in body order.
    const FramedState mine = local_->framed_state();
    FramedState out;
    out.q = gathered(mine.q);
    out.p = gathered(mine.p);
    const int a = geometry_.ambient_dim();
    if (framed_) {
      // (A state without frames: each at the identity, as ChartIntegrator::pack writes them.)
      const Eigen::MatrixXd identity = Eigen::MatrixXd::Identity(a, a);
      Eigen::MatrixXd frames(a * a, static_cast<Eigen::Index>(ids_.size()));
      for (std::size_t b = 0; b < ids_.size(); ++b) {
        frames.col(static_cast<Eigen::Index>(b)) = (mine.frames.empty() ? identity : mine.frames[b]).reshaped();
      }
      frames = gathered(frames);
      for (Eigen::Index b = 0; b < frames.cols(); ++b) out.frames.push_back(frames.col(b).reshaped(a, a));
    }
    if (mine.image_counts.size() != 0) {
      out.image_counts = gathered(mine.image_counts.cast<double>()).cast<std::int64_t>();  // (exact below 2^53)
    }
    if (geometry_.surface()) out.words = gathered_words(mine.words);
    out.clustered = mine.clustered;
    if (mine.clustered) out.cluster = mine.cluster;
    out.thermostat = mine.thermostat;  // (the same on every rank)
    if (!ranks_.root()) return FramedState{};
    return out;
  }
  void restore(const FramedState& state) override { take(state); }
  // A thermostat: each rank's is the same (it sees the whole simulation's sums, and its bodies'
  // noise is keyed by their indices in it: ChartIntegrator::set_domain).
  bool thermostatted() const override { return local_->thermostatted(); }
  void set_temperature(double kT) override { local_->set_temperature(kT); }
  std::vector<double> thermostat_state() const override { return local_->thermostat_state(); }
  void set_thermostat_state(const std::vector<double>& saved) override { local_->set_thermostat_state(saved); }
  std::uint64_t thermostat_step() const override { return local_->thermostat_step(); }
  void set_thermostat_step(std::uint64_t k) override { local_->set_thermostat_step(k); }
  double heat() const override { return local_->heat(); }
  double conserved_offset() const override { return local_->conserved_offset(); }
  double kinetic_temperature() override { return local_->kinetic_temperature(); }
  std::array<double, 2> configurational_sums() override { return local_->configurational_sums(); }
  FramedState shown_state() const override { return framed_state(); }
  void start_from(const FramedState& state) override { take(state); }
  int body_with_non_finite_energy() override { return first_body(local_->body_with_non_finite_energy()); }

 private:
  static bool same(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
    return a.rows() == b.rows() && a.cols() == b.cols() && a == b;
  }

  /// The squared chord of a body's move from `then` to `now` (chord2); on a compact surface, where
  /// a wrap since then took the body back into D by an element of the group, of its nearest image
  /// (HyperbolicSurface::nearest_image: in the star of D, unsupported()), looked for only when the
  /// plain chord would end the cut.
  double moved2(const Eigen::VectorXd& now, const Eigen::VectorXd& then) const {
    const double d2 = chord2(scene_.space, now, then);
    const sesi::HyperbolicSurface<double>* surface = geometry_.surface();
    if (!surface || d2 <= recut2_) return d2;
    Eigen::Vector3d y = now;
    surface->nearest_image(then, y);
    return std::min(d2, chord2(scene_.space, y, then));
  }

  /// A compact surface's words of this rank's own bodies (words: one a local body), gathered by
  /// rank 0 into body order (the whole run's, as Snapshot::words and FramedState::words hold them
  /// there); none on the other ranks.
  std::vector<Word> gathered_words(const std::vector<Word>& words) const {
    std::vector<double> mine, all;  // [index, letters, letter...] a body
    std::vector<int> counts;
    for (const int l : own_) {
      const Word& word = words[static_cast<std::size_t>(l)];
      mine.push_back(ids_[static_cast<std::size_t>(l)]);
      mine.push_back(static_cast<double>(word.size()));
      mine.insert(mine.end(), word.begin(), word.end());
    }
    ranks_.gather(mine, all, counts);
    if (!ranks_.root()) return {};
    std::vector<Word> out(static_cast<std::size_t>(n_));
    std::size_t at = 0, placed = 0;
    while (at + 2 <= all.size()) {
      const auto b = static_cast<std::size_t>(all[at]), letters = static_cast<std::size_t>(all[at + 1]);
      at += 2;
      if (b >= out.size() || at + letters > all.size()) break;
      out[b] = word_of(all.data() + at, letters);
      at += letters;
      ++placed;
    }
    if (at != all.size() || placed != out.size()) {
      std::fprintf(stderr, "sesi: rank 0: the words gathered from the ranks are not whole\n");
      ranks_.abort(3);
    }
    return out;
  }

  /// The whole run's body (1-based) of the first bad local body b (1-based; 0: none) over all
  /// ranks: a halo body is its owner's body, bad there too (the halo is its owner's copy).
  int first_body(int b) const {
    const long id = ranks_.min(b > 0 ? static_cast<long>(ids_[static_cast<std::size_t>(b - 1)]) : static_cast<long>(n_));
    return id < n_ ? static_cast<int>(id) + 1 : 0;
  }

  /// The columns of local (one per local body) of this rank's own bodies, gathered by rank 0 into
  /// one matrix in body order; 0 columns on the other ranks.
  Eigen::MatrixXd gathered(const Eigen::MatrixXd& local) const {
    // (Each column after its body's index: rank 0 keeps no list of every rank's bodies.)
    std::vector<double> mine, all;
    std::vector<int> counts;
    const Eigen::Index rows = local.rows();
    mine.reserve(own_.size() * static_cast<std::size_t>(rows + 1));
    for (const int b : own_) {
      mine.push_back(ids_[static_cast<std::size_t>(b)]);
      mine.insert(mine.end(), local.col(b).data(), local.col(b).data() + rows);
    }
    ranks_.gather(mine, all, counts);
    if (!ranks_.root()) return Eigen::MatrixXd(rows, 0);
    Eigen::MatrixXd out(rows, n_);
    for (std::size_t at = 0; at < all.size(); at += static_cast<std::size_t>(rows + 1)) {
      out.col(static_cast<Eigen::Index>(all[at])) = Eigen::Map<const Eigen::VectorXd>(all.data() + at + 1, rows);
    }
    return out;
  }

  /// A sum over bodies (System::sum_rows): this rank's own rows to rank 0, summed there over all
  /// bodies in body order (one process's bits), the total on every rank.
  double sum(const std::vector<double>& rows) const {
    return sum_own(1, [&](std::size_t k, double* out) { *out = rows[static_cast<std::size_t>(own_[k])]; })[0];
  }
  /// The same of `width` values a body at once, each summed apart: value(k, out) puts the k-th
  /// own body's (own_'s order) into out[0 .. width). In blocks of bodies, so that rank 0 holds a
  /// block's values at a time, not every body's (issue #27's memory at 10^6 bodies): term by
  /// term in body order, the same sums as sum_in_order over all of them.
  template <class Value>
  std::vector<double> sum_own(int width, const Value& value) const {
    constexpr int block = 1 << 16;
    const bool root = ranks_.root();
    const auto w = static_cast<std::size_t>(width);
    std::vector<double> mine, all, part;
    std::vector<int> counts;
    std::size_t own = 0;
    std::vector<double> totals(w, 0.0);
    for (int first = 0; first < n_; first += block) {
      const int end = std::min(n_, first + block);
      mine.clear();
      // (Each body's values after its index: rank 0 keeps no list of every rank's bodies.)
      for (; own < own_.size() && ids_[static_cast<std::size_t>(own_[own])] < end; ++own) {
        mine.push_back(ids_[static_cast<std::size_t>(own_[own])]);
        mine.resize(mine.size() + w);
        value(own, mine.data() + mine.size() - w);
      }
      ranks_.gather(mine, all, counts);
      if (!root) continue;
      part.assign(static_cast<std::size_t>(end - first) * w, 0.0);
      for (std::size_t at = 0; at < all.size(); at += w + 1) {
        std::copy_n(all.data() + at + 1, w, part.data() + (static_cast<std::size_t>(all[at]) - static_cast<std::size_t>(first)) * w);
      }
      for (std::size_t b = 0; b < part.size(); b += w) {
        for (std::size_t c = 0; c < w; ++c) totals[c] += part[b + c];
      }
    }
    for (double& total : totals) total = ranks_.from_root(total);
    return totals;
  }

  /// The own bodies' columns of local (rows x this rank's bodies) from every rank into whole
  /// (rows x the run's bodies, in body order), on every rank: the points of every body that pair
  /// terms without a cutoff need at each evaluation (System::set_whole_run). One MPI_Allgatherv,
  /// not a ring of K - 1 MPI_Sendrecv: a body's sum runs over its partners in the whole run's
  /// body order, which interleaves the ranks' bodies, so no rank can start its rows before it
  /// holds every point, and both end with the same copy.
  void gather_whole(const double* local, int rows, double* whole) {
    whole_mine_.clear();
    whole_mine_.reserve(own_.size() * static_cast<std::size_t>(rows));
    for (const int l : own_) whole_mine_.insert(whole_mine_.end(), local + rows * l, local + rows * (l + 1));
    ranks_.all_gather(whole_mine_, whole_all_, whole_counts_);
    if (whole_all_.size() != static_cast<std::size_t>(n_) * static_cast<std::size_t>(rows)) {
      std::fprintf(stderr, "sesi: rank %d: a gather of the whole run of the wrong size\n", ranks_.rank());
      ranks_.abort(3);
    }
    std::size_t at = 0;
    for (const std::vector<int>& ids : owned_ids_) {
      for (const int b : ids) {
        std::copy_n(whole_all_.data() + at, rows, whole + static_cast<std::ptrdiff_t>(rows) * b);
        at += static_cast<std::size_t>(rows);
      }
    }
  }

  /// After a drift: the halo's q from the owners.
  void refresh_positions(double* q, int dim) {
    for (int r = 0; r < ranks_.size(); ++r) {
      std::vector<double>& out = send_[static_cast<std::size_t>(r)];
      out.clear();
      for (const int b : send_to_[static_cast<std::size_t>(r)]) out.insert(out.end(), q + dim * b, q + dim * (b + 1));
    }
    ranks_.exchange(send_, received_);
    for (int r = 0; r < ranks_.size(); ++r) {
      const std::vector<double>& in = received_[static_cast<std::size_t>(r)];
      const std::vector<int>& to = receive_from_[static_cast<std::size_t>(r)];
      check_size(in, to, dim);
      for (std::size_t k = 0; k < to.size(); ++k) std::copy_n(in.data() + k * static_cast<std::size_t>(dim), dim, q + dim * to[k]);
    }
  }
  /// After a step (and its re-chartings): the halo's whole state from the owners.
  void refresh_halo() {
    for (int r = 0; r < ranks_.size(); ++r) {
      send_[static_cast<std::size_t>(r)].clear();
      local_->pack(send_to_[static_cast<std::size_t>(r)], send_[static_cast<std::size_t>(r)]);
    }
    ranks_.exchange(send_, received_);
    for (int r = 0; r < ranks_.size(); ++r) {
      const std::vector<int>& to = receive_from_[static_cast<std::size_t>(r)];
      check_size(received_[static_cast<std::size_t>(r)], to, local_->packed_size());
      local_->unpack(to, received_[static_cast<std::size_t>(r)].data());
    }
  }
  void check_size(const std::vector<double>& in, const std::vector<int>& to, int stride) const {
    if (in.size() != to.size() * static_cast<std::size_t>(stride)) {
      std::fprintf(stderr, "sesi: rank %d: a halo message of the wrong size\n", ranks_.rank());
      ranks_.abort(3);
    }
  }

  /// Cut the slabs again where the bodies are now and move each body's state to the ranks that
  /// hold it next.
  void recut() {
    const int a = geometry_.ambient_dim(), stride = local_->packed_size();
    cluster_ = local_->cluster();  // (the next integrator's bodies stay in it)
    const std::vector<double> thermostat = local_->thermostat_state();
    // Every rank's bodies' points (at the last force evaluation) with their indices, to all.
    Eigen::MatrixXd X(a, n_);
    {
      std::vector<double> mine, all;
      std::vector<int> counts;
      mine.reserve(own_.size() * static_cast<std::size_t>(a + 1));
      for (std::size_t k = 0; k < own_.size(); ++k) {
        mine.push_back(ids_[static_cast<std::size_t>(own_[k])]);
        mine.insert(mine.end(), moved_.col(static_cast<Eigen::Index>(k)).data(),
                    moved_.col(static_cast<Eigen::Index>(k)).data() + a);
      }
      ranks_.all_gather(mine, all, counts);
      for (std::size_t at = 0; at < all.size(); at += static_cast<std::size_t>(a + 1)) {
        X.col(static_cast<Eigen::Index>(all[at])) = Eigen::Map<const Eigen::VectorXd>(all.data() + at + 1, a);
      }
    }
    Slabs next = cut(scene_.space, geometry_.surface(), X, ranks_.size(), halo_width_);
    // Each body's state from its owner now to every rank that holds it next: [index, packed],
    // and on a compact surface its word after it: [letters, letter...].
    const bool surface = geometry_.surface() != nullptr;
    for (int r = 0; r < ranks_.size(); ++r) send_[static_cast<std::size_t>(r)].clear();
    {
      std::vector<double> packed;
      local_->pack(own_, packed);
      const std::vector<Word> words = surface ? local_->words() : std::vector<Word>{};
      for (std::size_t k = 0; k < own_.size(); ++k) {
        const int b = ids_[static_cast<std::size_t>(own_[k])];
        const double* state = packed.data() + k * static_cast<std::size_t>(stride);
        for (int r = 0; r < ranks_.size(); ++r) {
          if (!next.holds(r, b)) continue;
          std::vector<double>& out = send_[static_cast<std::size_t>(r)];
          out.push_back(b);
          out.insert(out.end(), state, state + stride);
          if (!surface) continue;
          const Word& word = words[static_cast<std::size_t>(own_[k])];
          out.push_back(static_cast<double>(word.size()));
          out.insert(out.end(), word.begin(), word.end());
        }
      }
    }
    // The old integrator is done with (its bodies' states are in send_): freed before the new
    // one is built, so that a rank never holds both (memory: issue #27's 10^6 bodies).
    local_.reset();
    ranks_.exchange(send_, received_);
    release(send_);
    // (In body order: the new local order.)
    struct Arrived {
      int body;
      const double* state;
      const double* word;  // a surface's letters
      std::size_t letters;
    };
    std::vector<Arrived> arrived;
    for (const std::vector<double>& in : received_) {
      for (std::size_t at = 0; at < in.size();) {
        Arrived entry{static_cast<int>(in[at]), in.data() + at + 1, nullptr, 0};
        at += static_cast<std::size_t>(stride + 1);
        if (surface && at < in.size()) {
          entry.letters = static_cast<std::size_t>(in[at]);
          entry.word = in.data() + at + 1;
          at += entry.letters + 1;
        } else if (surface) {
          at = in.size() + 1;  // (no word)
        }
        if (at > in.size()) {
          std::fprintf(stderr, "sesi: rank %d: a message of bodies that change ranks is not whole\n", ranks_.rank());
          ranks_.abort(3);
        }
        arrived.push_back(entry);
      }
    }
    std::sort(arrived.begin(), arrived.end(), [](const Arrived& x, const Arrived& y) { return x.body < y.body; });
    std::vector<double> state;
    state.reserve(arrived.size() * static_cast<std::size_t>(stride));
    std::vector<Word> words;
    for (const Arrived& entry : arrived) {
      state.insert(state.end(), entry.state, entry.state + stride);
      if (surface) words.push_back(word_of(entry.word, entry.letters));
    }
    arrived = {};
    release(received_);
    begin(std::move(next), X, &state);
    if (surface) local_->set_words(std::move(words));
    local_->set_thermostat_state(thermostat);
  }
  /// Empty the blocks and give their memory back (a cut's blocks hold every body's state; a
  /// step's halo blocks, which reuse them, a small part).
  static void release(std::vector<std::vector<double>>& blocks) {
    for (std::vector<double>& block : blocks) std::vector<double>().swap(block);
  }

  /// Every rank passes the same whole state (a checkpoint's): each takes its bodies from it.
  void take(const FramedState& state) {
    const bool surface = geometry_.surface() != nullptr;
    if (state.embedded || (!state.words.empty() && (!surface || state.words.size() != static_cast<std::size_t>(n_))) ||
        state.q.cols() != n_ || state.p.cols() != n_ ||
        (state.image_counts.size() != 0 && state.image_counts.cols() != n_) ||
        (!state.frames.empty() && state.frames.size() != static_cast<std::size_t>(n_))) {
      throw std::logic_error("the state to restore across ranks is not of this run");
    }
    const int a = geometry_.ambient_dim();
    Eigen::MatrixXd X(a, n_);
    for (int b = 0; b < n_; ++b) {
      const Eigen::VectorXd x = geometry_.embed(state.q.col(b));
      X.col(b) = state.frames.empty() ? x : Eigen::VectorXd(state.frames[static_cast<std::size_t>(b)] * x);
    }
    Slabs slabs = cut(scene_.space, geometry_.surface(), X, ranks_.size(), halo_width_);
    // The columns of the bodies this rank holds, in body order: its integrator restores them.
    std::vector<Eigen::Index> held;
    for (int b = 0; b < n_; ++b) {
      if (slabs.holds(ranks_.rank(), b)) held.push_back(b);
    }
    FramedState mine;
    mine.q = state.q(Eigen::all, held);
    mine.p = state.p(Eigen::all, held);
    for (const Eigen::Index b : held) {
      if (!state.frames.empty()) mine.frames.push_back(state.frames[static_cast<std::size_t>(b)]);
      if (!state.words.empty()) mine.words.push_back(state.words[static_cast<std::size_t>(b)]);
    }
    if (state.image_counts.size() != 0) mine.image_counts = state.image_counts(Eigen::all, held);
    mine.clustered = state.clustered;
    if (state.clustered) mine.cluster = state.cluster;
    mine.thermostat = state.thermostat;
    cluster_ = state.clustered ? state.cluster : Eigen::MatrixXd();
    begin(std::move(slabs), X, nullptr, &mine);
  }

  /// Start a cut: this rank's bodies (its own and its halo, in body order), the exchange plans,
  /// the integrator of its bodies (from the scene's initial state, the packed states given in
  /// body order, or the state of those bodies held), the points the next moves are measured from.
  void begin(Slabs slabs, const Eigen::MatrixXd& X, const std::vector<double>* packed,
             const FramedState* held = nullptr) {
    const int me = ranks_.rank(), K = ranks_.size();
    ids_.clear();
    own_.clear();
    halo_.clear();
    owned_.clear();
    for (int b = 0; b < n_; ++b) {
      if (!slabs.holds(me, b)) continue;
      const bool own = slabs.owner[static_cast<std::size_t>(b)] == me;
      (own ? own_ : halo_).push_back(static_cast<int>(ids_.size()));
      owned_.push_back(own ? 1 : 0);
      ids_.push_back(b);
    }
    send_to_.assign(static_cast<std::size_t>(K), {});
    receive_from_.assign(static_cast<std::size_t>(K), {});
    for (const int l : own_) {
      for (int r = 0; r < K; ++r) {
        if (r != me && slabs.holds(r, ids_[static_cast<std::size_t>(l)])) send_to_[static_cast<std::size_t>(r)].push_back(l);
      }
    }
    for (const int l : halo_) {
      receive_from_[static_cast<std::size_t>(slabs.owner[static_cast<std::size_t>(ids_[static_cast<std::size_t>(l)])])].push_back(l);
    }
    send_.assign(static_cast<std::size_t>(K), {});
    received_.assign(static_cast<std::size_t>(K), {});
    owned_ids_.assign(static_cast<std::size_t>(K), {});
    // (For the whole run's points of pair terms without a cutoff: gather_whole.)
    if (long_range_) {
      for (int b = 0; b < n_; ++b) owned_ids_[static_cast<std::size_t>(slabs.owner[static_cast<std::size_t>(b)])].push_back(b);
    }
    start_.resize(X.rows(), static_cast<Eigen::Index>(own_.size()));
    for (std::size_t k = 0; k < own_.size(); ++k) {
      start_.col(static_cast<Eigen::Index>(k)) = X.col(ids_[static_cast<std::size_t>(own_[k])]);
    }
    moved_ = start_;

    // Its bodies: the scene's initial conditions at the start, the held state's (restored with
    // its frames below), or the packed states' (q and p first: ChartIntegrator::pack), which
    // unpack() then puts in place with their frames. (After the start the scene's q and p are
    // released: run_command.cpp.)
    Scene local = shape_;
    local.bodies.resize(ids_.size());
    const int d = scene_.dim(), stride = packed ? static_cast<int>(packed->size() / std::max<std::size_t>(ids_.size(), 1)) : 0;
    for (std::size_t k = 0; k < ids_.size(); ++k) {
      Body& body = local.bodies[k];
      const Body& given = scene_.bodies[static_cast<std::size_t>(ids_[k])];
      body.mass = given.mass;
      if (held) {
        body.q = held->q.col(static_cast<Eigen::Index>(k));
        body.p = held->p.col(static_cast<Eigen::Index>(k));
        continue;
      }
      if (!packed) {
        body.q = given.q;
        body.p = given.p;
        continue;
      }
      const double* state = packed->data() + k * static_cast<std::size_t>(stride);
      body.q = Eigen::Map<const Eigen::VectorXd>(state, d);
      body.p = Eigen::Map<const Eigen::VectorXd>(state + d, d);
    }
    local_.reset();
    local_ = make_integrator(local);
    DomainHooks hooks;
    hooks.halo = halo_;
    hooks.drifted = [this](double* q, int dim, int) { refresh_positions(q, dim); };
    hooks.sum = [this](const std::vector<double>& rows) { return sum(rows); };
    hooks.ids = ids_;
    hooks.bodies = n_;
    hooks.any = [this](bool value) { return ranks_.any(value); };
    hooks.gather = [this](const double* local, int rows, double* whole) { gather_whole(local, rows, whole); };
    local_->set_domain(std::move(hooks));
    if (held) local_->restore(*held);
    if (packed) {
      std::vector<int> all(ids_.size());
      std::iota(all.begin(), all.end(), 0);
      local_->set_cluster(cluster_);
      local_->unpack(all, packed->data());
    }
    // (Frames or none is the chart's: S^n and H^n are re-charted from the start, E^n never.)
    if (!framed_known_) framed_ = !local_->framed_state().frames.empty();
    framed_known_ = true;
  }

  const Scene& scene_;
  const Ranks& ranks_;
  Geometry geometry_;
  int n_;
  RankGather gather_;  // the snapshots of own_state
  Scene shape_;  // the scene without its bodies
  double halo_width_ = 0.0, skin_ = 0.0;
  double recut2_ = 0.0, broken2_ = 0.0;  // squared chords of half the skin and of the skin

  // This cut: the bodies this rank holds (whole-run indices, ascending), which of them it owns
  // (local indices of its own and of its halo), and the halo's exchange plans per rank.
  std::vector<int> ids_, own_, halo_;
  std::vector<char> owned_;
  std::vector<std::vector<int>> send_to_, receive_from_;
  // Each rank's own bodies, ascending: on every rank with long_range_.
  std::vector<std::vector<int>> owned_ids_;
  bool long_range_ = false;  // a pair term without a cutoff (gather_whole)
  std::vector<double> whole_mine_, whole_all_;  // gather_whole's buffers
  std::vector<int> whole_counts_;
  std::vector<std::vector<double>> send_, received_;
  Eigen::MatrixXd start_, moved_;  // own bodies' world points at the cut, and at the last step
  bool framed_ = false, framed_known_ = false;
  Eigen::MatrixXd cluster_;  // H^n: the cluster frame the bodies were last taken in (empty: none)
  std::unique_ptr<Integrator> local_;
};

}  // namespace

std::unique_ptr<Integrator> make_domain_integrator(const Scene& scene, const Ranks& ranks) {
  std::string why = unsupported(scene);
  if (why.empty() && ranks.size() > scene.body_count()) why = "more ranks than bodies";
  if (!why.empty()) {
    throw InputError(Origin{scene.source}, "",
                     "a run across " + std::to_string(ranks.size()) + " ranks (mpirun) does not support " + why +
                         " yet: run it as one process (docs/parallel.md)");
  }
  try {
    return std::make_unique<DomainIntegrator>(scene, ranks);
  } catch (const std::logic_error&) {
    // (The method may come from the scene file or from --method: named, not located.)
    throw InputError(Origin{scene.source}, "",
                     "method '" + scene.integrator.method + "' cannot run across ranks (mpirun) yet: a plain "
                     "sesi method (sesi2, sesi4, ...) can; or run it as one process (docs/parallel.md)");
  }
}

}  // namespace sesi::program
