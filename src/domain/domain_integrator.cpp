#include "domain_integrator.hpp"

#include <algorithm>
#include <cmath>
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

namespace sesi::program {

namespace {

/// What of scene a run across ranks cannot hold yet, or empty.
std::string unsupported(const Scene& scene) {
  if (scene.space.has_topology()) return "a space with a topology (a periodic box or a compact surface)";
  if (scene.thermostat) return "a thermostat";
  for (const PotentialSpec& spec : scene.potentials) {
    if (std::holds_alternative<CotangentGravitySpec>(spec) || std::holds_alternative<HarmonicPairSpec>(spec) ||
        std::holds_alternative<ChordWellSpec>(spec)) {
      return "pair potentials without a cutoff ('" + std::string(potential_kind(spec)) + "')";
    }
  }
  // Below System::rows_from bodies one process sums pairs in another order (the symmetric loop).
  if (scene.body_count() < parallel::min_parallel_bodies) {
    return "fewer than " + std::to_string(parallel::min_parallel_bodies) + " bodies";
  }
  return {};
}

/// The chord of a geodesic distance d in the ambient metric: 2 R sin(d / 2R) on S^n (d <= pi R),
/// the Minkowski chord 2 R sinh(d / 2R) on H^n, d on E^n.
double chord_of(const SpaceSpec& space, double d) {
  const double R = space.radius;
  switch (space.kind) {
    case SpaceKind::sphere:
      return 2.0 * R * std::sin(std::min(d, M_PI * R) / (2.0 * R));
    case SpaceKind::hyperbolic:
      return 2.0 * R * std::sinh(d / (2.0 * R));
    case SpaceKind::euclidean:
      break;
  }
  return d;
}

/// The squared chord of two points in the ambient metric (Euclidean; Minkowski on H^n, whose last
/// coordinate is time), a monotone function of their distance.
double chord2(const SpaceSpec& space, const Eigen::VectorXd& x, const Eigen::VectorXd& y) {
  const Eigen::VectorXd u = x - y;
  if (space.kind != SpaceKind::hyperbolic) return u.squaredNorm();
  const Eigen::Index t = u.size() - 1;
  return u.head(t).squaredNorm() - u[t] * u[t];
}

/// The slabs of one cut: every body's rank, each rank's slab [lo, hi] of the cut coordinate, and
/// the halo's width about it.
struct Slabs {
  int axis = 0;
  std::vector<double> key;  // by body: the cut coordinate of its world point
  std::vector<int> owner;   // by body
  std::vector<double> lo, hi;
  double halo = 0.0;
  /// Whether rank r holds body b (as its own or in its halo).
  bool holds(int r, int b) const {
    const double k = key[static_cast<std::size_t>(b)];
    return owner[static_cast<std::size_t>(b)] == r ||
           (k >= lo[static_cast<std::size_t>(r)] - halo && k <= hi[static_cast<std::size_t>(r)] + halo);
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
Slabs cut(const SpaceSpec& space, const Eigen::MatrixXd& X, int ranks, double halo) {
  Slabs s;
  s.halo = halo;
  const int n = static_cast<int>(X.cols());
  const bool hyperbolic = space.kind == SpaceKind::hyperbolic;
  const int axes = static_cast<int>(X.rows()) - (hyperbolic ? 1 : 0);
  double widest = -1.0;
  for (int r = 0; r < axes; ++r) {
    const double extent = X.row(r).maxCoeff() - X.row(r).minCoeff();
    if (extent > widest) {  // (NaN: not taken)
      widest = extent;
      s.axis = r;
    }
  }
  s.key.resize(static_cast<std::size_t>(n));
  for (int b = 0; b < n; ++b) {
    double k = X(s.axis, b);
    if (hyperbolic) k = space.radius * std::asinh(k / space.radius);
    s.key[static_cast<std::size_t>(b)] = std::isnan(k) ? std::numeric_limits<double>::infinity() : k;
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

class DomainIntegrator final : public Integrator {
 public:
  DomainIntegrator(const Scene& scene, const Ranks& ranks)
      : scene_(scene), ranks_(ranks), geometry_(scene.space), n_(scene.body_count()) {
    shape_ = scene;
    shape_.bodies.clear();
    double cutoff = 0.0;
    for (const PotentialSpec& spec : scene.potentials) {
      if (const auto* lj = std::get_if<LennardJonesSpec>(&spec)) cutoff = std::max(cutoff, lj->cutoff);
    }
    // The domain's skin: twice the Verlet lists' (at least twice their default), a fraction of
    // the cutoff. A cut costs more than a list rebuild (the bodies change ranks, each rank's
    // integrator starts again), so the slabs are cut half as often, for a halo 2 skins wider.
    const double skin = 2.0 * std::max(scene.integrator.neighbour_skin, sesi::default_skin_fraction) * cutoff;
    halo_width_ = cutoff > 0.0 ? cutoff + 2.0 * skin : 0.0;
    const double half = chord_of(scene.space, 0.5 * skin), whole = chord_of(scene.space, skin);
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
    begin(cut(scene_.space, X, ranks_.size(), halo_width_), X, nullptr);
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
      const double d2 = chord2(scene_.space, moved_.col(k), start_.col(k));
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
    // As sesi::momentum_map: summed by rank 0 over all bodies in body order, in the frame the
    // bodies are held in (a cluster frame's on H^n), then taken to the world.
    Eigen::MatrixXd lx, lv;
    local_->frame_points(lx, lv);
    const Eigen::MatrixXd X = gathered(lx), V = gathered(lv);
    std::vector<double> m;
    if (ranks_.root()) {
      const Eigen::VectorXd out = local_->momentum_in_world(sesi::momentum_map_of(
          X, V, [&](int b) { return scene_.bodies[static_cast<std::size_t>(b)].mass; },
          scene_.space.kind == SpaceKind::euclidean));
      m.assign(out.data(), out.data() + out.size());
    }
    ranks_.from_root(m);
    return Eigen::Map<const Eigen::VectorXd>(m.data(), static_cast<Eigen::Index>(m.size()));
  }
  Eigen::MatrixXd points() override { return gathered(local_->points()); }
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
    std::vector<double> mine, all;
    std::vector<int> counts;
    local_->pack(own_, mine);
    ranks_.gather(mine, all, counts);
    FramedState out;
    if (!ranks_.root()) return out;
    const int d = scene_.dim(), a = geometry_.ambient_dim(), stride = local_->packed_size();
    out.q.resize(d, n_);
    out.p.resize(d, n_);
    if (framed_) out.frames.resize(static_cast<std::size_t>(n_));
    const Eigen::MatrixXd c = local_->cluster();
    out.clustered = c.size() != 0;
    if (out.clustered) out.cluster = c;
    std::size_t at = 0;
    for (const std::vector<int>& ids : owned_ids_) {
      for (const int b : ids) {
        const double* in = all.data() + at;
        for (int i = 0; i < d; ++i) out.q(i, b) = in[i];
        for (int i = 0; i < d; ++i) out.p(i, b) = in[d + i];
        if (framed_) out.frames[static_cast<std::size_t>(b)] = Eigen::Map<const Eigen::MatrixXd>(in + 2 * d, a, a);
        at += static_cast<std::size_t>(stride);
      }
    }
    return out;
  }
  void restore(const FramedState& state) override { take(state); }
  FramedState shown_state() const override { return framed_state(); }
  void start_from(const FramedState& state) override { take(state); }
  int body_with_non_finite_energy() override { return first_body(local_->body_with_non_finite_energy()); }

 private:
  static bool same(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
    return a.rows() == b.rows() && a.cols() == b.cols() && a == b;
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
    std::vector<double> mine, all;
    std::vector<int> counts;
    mine.reserve(own_.size() * static_cast<std::size_t>(local.rows()));
    for (const int b : own_) mine.insert(mine.end(), local.col(b).data(), local.col(b).data() + local.rows());
    ranks_.gather(mine, all, counts);
    if (!ranks_.root()) return Eigen::MatrixXd(local.rows(), 0);
    Eigen::MatrixXd out(local.rows(), n_);
    std::size_t at = 0;
    for (const std::vector<int>& ids : owned_ids_) {
      for (const int b : ids) {
        out.col(b) = Eigen::Map<const Eigen::VectorXd>(all.data() + at, local.rows());
        at += static_cast<std::size_t>(local.rows());
      }
    }
    return out;
  }

  /// A sum over bodies (System::sum_rows): this rank's own rows to rank 0, summed there over all
  /// bodies in body order (one process's bits), the total on every rank.
  double sum(const std::vector<double>& rows) const {
    std::vector<double> mine, all;
    std::vector<int> counts;
    mine.reserve(own_.size());
    for (const int b : own_) mine.push_back(rows[static_cast<std::size_t>(b)]);
    ranks_.gather(mine, all, counts);
    double total = 0.0;
    if (ranks_.root()) {
      std::vector<double> full(static_cast<std::size_t>(n_), 0.0);
      std::size_t at = 0;
      for (const std::vector<int>& ids : owned_ids_) {
        for (const int b : ids) full[static_cast<std::size_t>(b)] = all[at++];
      }
      total = sesi::parallel::sum_in_order(full);
    }
    return ranks_.from_root(total);
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
    // Every rank's bodies' points (at the last force evaluation) with their indices, to all.
    std::vector<double> mine, all;
    std::vector<int> counts;
    mine.reserve(own_.size() * static_cast<std::size_t>(a + 1));
    for (std::size_t k = 0; k < own_.size(); ++k) {
      mine.push_back(ids_[static_cast<std::size_t>(own_[k])]);
      mine.insert(mine.end(), moved_.col(static_cast<Eigen::Index>(k)).data(),
                  moved_.col(static_cast<Eigen::Index>(k)).data() + a);
    }
    ranks_.all_gather(mine, all, counts);
    Eigen::MatrixXd X(a, n_);
    for (std::size_t at = 0; at < all.size(); at += static_cast<std::size_t>(a + 1)) {
      X.col(static_cast<Eigen::Index>(all[at])) = Eigen::Map<const Eigen::VectorXd>(all.data() + at + 1, a);
    }
    Slabs next = cut(scene_.space, X, ranks_.size(), halo_width_);
    // Each body's state from its owner now to every rank that holds it next: [index, packed].
    std::vector<double> packed;
    local_->pack(own_, packed);
    for (int r = 0; r < ranks_.size(); ++r) send_[static_cast<std::size_t>(r)].clear();
    for (std::size_t k = 0; k < own_.size(); ++k) {
      const int b = ids_[static_cast<std::size_t>(own_[k])];
      const double* state = packed.data() + k * static_cast<std::size_t>(stride);
      for (int r = 0; r < ranks_.size(); ++r) {
        if (!next.holds(r, b)) continue;
        std::vector<double>& out = send_[static_cast<std::size_t>(r)];
        out.push_back(b);
        out.insert(out.end(), state, state + stride);
      }
    }
    ranks_.exchange(send_, received_);
    // (In body order: the new local order.)
    std::vector<std::pair<int, const double*>> arrived;
    for (const std::vector<double>& in : received_) {
      for (std::size_t at = 0; at < in.size(); at += static_cast<std::size_t>(stride + 1)) {
        arrived.emplace_back(static_cast<int>(in[at]), in.data() + at + 1);
      }
    }
    std::sort(arrived.begin(), arrived.end(), [](const auto& x, const auto& y) { return x.first < y.first; });
    std::vector<double> state;
    state.reserve(arrived.size() * static_cast<std::size_t>(stride));
    for (const auto& entry : arrived) state.insert(state.end(), entry.second, entry.second + stride);
    begin(std::move(next), X, &state);
  }

  /// Every rank passes the same whole state (a checkpoint's): each takes its bodies from it.
  void take(const FramedState& state) {
    if (state.embedded || !state.thermostat.empty() || state.image_counts.size() != 0 ||
        !state.words.empty() || state.q.cols() != n_ || state.p.cols() != n_ ||
        (!state.frames.empty() && state.frames.size() != static_cast<std::size_t>(n_))) {
      throw std::logic_error("the state to restore across ranks is not of this run");
    }
    const int a = geometry_.ambient_dim();
    Eigen::MatrixXd X(a, n_);
    for (int b = 0; b < n_; ++b) {
      const Eigen::VectorXd x = geometry_.embed(state.q.col(b));
      X.col(b) = state.frames.empty() ? x : Eigen::VectorXd(state.frames[static_cast<std::size_t>(b)] * x);
    }
    Slabs slabs = cut(scene_.space, X, ranks_.size(), halo_width_);
    std::vector<double> packed;
    const int d = scene_.dim();
    for (int b = 0; b < n_; ++b) {
      if (!slabs.holds(ranks_.rank(), b)) continue;
      for (int i = 0; i < d; ++i) packed.push_back(state.q(i, b));
      for (int i = 0; i < d; ++i) packed.push_back(state.p(i, b));
      for (int c = 0; c < a; ++c) {
        for (int r = 0; r < a; ++r) {
          packed.push_back(state.frames.empty() ? (r == c ? 1.0 : 0.0) : state.frames[static_cast<std::size_t>(b)](r, c));
        }
      }
    }
    cluster_ = state.clustered ? state.cluster : Eigen::MatrixXd();
    begin(std::move(slabs), X, &packed);
  }

  /// Start a cut: this rank's bodies (its own and its halo, in body order), the exchange plans,
  /// the integrator of its bodies (from the scene's initial state, or the packed states given in
  /// body order), the points the next moves are measured from.
  void begin(Slabs slabs, const Eigen::MatrixXd& X, const std::vector<double>* packed) {
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
    if (ranks_.root()) {
      for (int b = 0; b < n_; ++b) owned_ids_[static_cast<std::size_t>(slabs.owner[static_cast<std::size_t>(b)])].push_back(b);
    }
    start_.resize(X.rows(), static_cast<Eigen::Index>(own_.size()));
    for (std::size_t k = 0; k < own_.size(); ++k) {
      start_.col(static_cast<Eigen::Index>(k)) = X.col(ids_[static_cast<std::size_t>(own_[k])]);
    }
    moved_ = start_;

    Scene local = shape_;
    local.bodies.reserve(ids_.size());
    for (const int b : ids_) local.bodies.push_back(scene_.bodies[static_cast<std::size_t>(b)]);
    local_.reset();
    local_ = make_integrator(local);
    DomainHooks hooks;
    hooks.halo = halo_;
    hooks.drifted = [this](double* q, int dim, int) { refresh_positions(q, dim); };
    hooks.sum = [this](const std::vector<double>& rows) { return sum(rows); };
    local_->set_domain(std::move(hooks));
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
  Scene shape_;  // the scene without its bodies
  double halo_width_ = 0.0, skin_ = 0.0;
  double recut2_ = 0.0, broken2_ = 0.0;  // squared chords of half the skin and of the skin

  // This cut: the bodies this rank holds (whole-run indices, ascending), which of them it owns
  // (local indices of its own and of its halo), and the halo's exchange plans per rank.
  std::vector<int> ids_, own_, halo_;
  std::vector<char> owned_;
  std::vector<std::vector<int>> send_to_, receive_from_;
  std::vector<std::vector<int>> owned_ids_;  // rank 0: each rank's own bodies, ascending
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
