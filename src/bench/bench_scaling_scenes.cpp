#include "bench_scaling_scenes.hpp"

#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <stdexcept>
#include <unordered_map>
#include <vector>

#include "geometry.hpp"

namespace sesi::program::bench {

namespace {

constexpr double density = 0.5;
/// The golden angle, pi (3 - sqrt 5): consecutive points of the spiral lattices.
constexpr double golden_angle = std::numbers::pi * (3.0 - 2.2360679774997896964);

/// Uniform and normal deviates from the generator's bits (the standard distributions are not
/// the same on every library; these are).
class Deviates {
 public:
  explicit Deviates(std::uint64_t seed) : bits_(seed) {}
  double uniform() { return static_cast<double>(bits_() >> 11) * 0x1.0p-53; }
  /// Box-Muller, one of the pair.
  double normal() {
    const double u = 1.0 - uniform(), v = uniform();
    return std::sqrt(-2.0 * std::log(u)) * std::cos(2.0 * std::numbers::pi * v);
  }
  Eigen::VectorXd normal_vector(int n) {
    Eigen::VectorXd out(n);
    for (int i = 0; i < n; ++i) out(i) = normal();
    return out;
  }

 private:
  std::mt19937_64 bits_;
};

/// Area of the unit sphere S^{n-1} in R^n: 2 pi^{n/2} / Gamma(n/2).
double unit_sphere_area(int n) {
  return 2.0 * std::pow(std::numbers::pi, 0.5 * n) / std::tgamma(0.5 * n);
}

/// u = rho / R of the geodesic ball of H^n (radius R) holding `bodies` at density 1/2:
/// area(S^{n-1}) R^n int_0^u sinh^{n-1} t dt = bodies / density.
double hyperbolic_ball_radius(int n, double R, int bodies) {
  const double target = bodies / density / (unit_sphere_area(n) * std::pow(R, n));
  const auto volume = [n](double u) {  // Simpson's rule, smooth integrand
    constexpr int m = 400;
    double sum = 0;
    for (int k = 0; k <= m; ++k) {
      const double w = (k == 0 || k == m) ? 1 : (k % 2 ? 4 : 2);
      sum += w * std::pow(std::sinh(u * k / m), n - 1);
    }
    return sum * u / (3.0 * m);
  };
  double lo = 0, hi = 1;
  while (volume(hi) < target) hi *= 2;
  for (int it = 0; it < 100; ++it) {
    const double mid = 0.5 * (lo + hi);
    (volume(mid) < target ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

/// The boost of H^n by `rapidity` in the plane of the first and the last ambient axes.
void boost(Eigen::MatrixXd& X, double rapidity) {
  const Eigen::Index last = X.rows() - 1;
  const double c = std::cosh(rapidity), s = std::sinh(rapidity);
  for (Eigen::Index b = 0; b < X.cols(); ++b) {
    const double x0 = X(0, b), xn = X(last, b);
    X(0, b) = c * x0 + s * xn;
    X(last, b) = s * x0 + c * xn;
  }
}

/// A uniform random point of the region the bodies fill.
Eigen::VectorXd random_point(const SpaceSpec& space, double extent, Deviates& random) {
  const int n = space.dim;
  if (space.kind == SpaceKind::euclidean) {
    Eigen::VectorXd x(n);
    for (int i = 0; i < n; ++i) x(i) = extent * random.uniform();
    return x;
  }
  Eigen::VectorXd direction = random.normal_vector(space.kind == SpaceKind::sphere ? n + 1 : n);
  direction.normalize();
  const double R = space.radius;
  if (space.kind == SpaceKind::sphere) return R * direction;
  // Geodesic ball of radius extent * R: density of the radius ~ sinh^{n-1}(r/R), by rejection.
  double u = 0;
  do {
    u = extent * random.uniform();
  } while (random.uniform() > std::pow(std::sinh(u) / std::sinh(extent), n - 1));
  Eigen::VectorXd x(n + 1);
  x << R * std::sinh(u) * direction, R * std::cosh(u);
  return x;
}

/// Random sequential addition: points drawn one at a time, each kept when no kept point is
/// within `too_close` of it, found through a hash of cells of side `cell` over key(x) (a point's
/// coordinates in which every too-close pair lies in neighbouring cells); with period_cells > 0
/// the cells wrap around (a periodic box of that many cells per side).
template <class Draw, class Key, class TooClose>
std::vector<Eigen::VectorXd> sequential_addition(int bodies, Draw&& draw, Key&& key, TooClose&& too_close, double cell,
                                                 int period_cells = 0) {
  std::vector<Eigen::VectorXd> kept;
  kept.reserve(static_cast<std::size_t>(bodies));
  std::unordered_map<std::uint64_t, std::vector<int>> cells;  // colliding keys only add candidates
  const auto wrap = [&](long c) { return period_cells > 0 ? ((c % period_cells) + period_cells) % period_cells : c; };
  const auto hash = [](const std::vector<long>& c) {
    std::uint64_t h = 0x9e3779b97f4a7c15ull;
    for (long v : c) h = (h ^ static_cast<std::uint64_t>(v)) * 0x100000001b3ull;
    return h;
  };
  for (int b = 0; b < bodies; ++b) {
    for (long trial = 0;; ++trial) {
      if (trial == 1'000'000) throw std::runtime_error("sesi bench --scaling: no room for the bodies");
      Eigen::VectorXd x = draw();
      const Eigen::VectorXd k = key(x);
      const int dims = static_cast<int>(k.size());
      std::vector<long> home(static_cast<std::size_t>(dims)), c(home.size());
      for (int i = 0; i < dims; ++i) home[static_cast<std::size_t>(i)] = static_cast<long>(std::floor(k(i) / cell));
      bool fits = true;
      long offsets = 1;
      for (int i = 0; i < dims; ++i) offsets *= 3;
      for (long o = 0; o < offsets && fits; ++o) {
        long rest = o;
        for (int i = 0; i < dims; ++i, rest /= 3) c[static_cast<std::size_t>(i)] = wrap(home[static_cast<std::size_t>(i)] + rest % 3 - 1);
        const auto found = cells.find(hash(c));
        if (found == cells.end()) continue;
        for (int j : found->second) {
          if (too_close(x, kept[static_cast<std::size_t>(j)])) {
            fits = false;
            break;
          }
        }
      }
      if (!fits) continue;
      for (int i = 0; i < dims; ++i) c[static_cast<std::size_t>(i)] = wrap(home[static_cast<std::size_t>(i)]);
      cells[hash(c)].push_back(b);
      kept.push_back(std::move(x));
      break;
    }
  }
  return kept;
}

/// Points of S^n (n >= 3), of a geodesic ball of H^n of radius extent R, or of a cube of E^n of
/// side extent, every pair at least 1 apart.
Eigen::MatrixXd separated_points(const SpaceSpec& space, int bodies, double extent, Deviates& random) {
  const double R = space.radius;
  const auto draw = [&] { return random_point(space, extent, random); };
  std::vector<Eigen::VectorXd> points;
  if (space.kind == SpaceKind::hyperbolic) {
    // Spatial coordinates s: a Minkowski chord c bounds |ds| by c cosh(extent) in the ball.
    const double chord = 2 * R * std::sinh(0.5 / R);
    const auto key = [](const Eigen::VectorXd& x) -> Eigen::VectorXd { return x.head(x.size() - 1); };
    const auto too_close = [&](const Eigen::VectorXd& x, const Eigen::VectorXd& y) {
      const Eigen::VectorXd d = x - y;
      const Eigen::Index last = d.size() - 1;
      return d.head(last).squaredNorm() - d(last) * d(last) < chord * chord;
    };
    points = sequential_addition(bodies, draw, key, too_close, chord * std::cosh(extent));
  } else {
    // S^n: the chord of geodesic distance 1 (no longer than 1); E^n: the distance.
    const double chord = space.kind == SpaceKind::sphere ? 2 * R * std::sin(0.5 / R) : 1.0;
    const auto key = [](const Eigen::VectorXd& x) -> Eigen::VectorXd { return x; };
    const auto too_close = [&](const Eigen::VectorXd& x, const Eigen::VectorXd& y) {
      return (x - y).squaredNorm() < chord * chord;
    };
    points = sequential_addition(bodies, draw, key, too_close, 1.0);
  }
  Eigen::MatrixXd X(points.front().size(), bodies);
  for (int b = 0; b < bodies; ++b) X.col(b) = points[static_cast<std::size_t>(b)];
  return X;
}

/// The Fibonacci lattice of S^2 (equal areas along z, consecutive points a golden angle apart).
Eigen::MatrixXd fibonacci_sphere(int bodies, double R) {
  Eigen::MatrixXd X(3, bodies);
  for (int k = 0; k < bodies; ++k) {
    const double z = 1.0 - 2.0 * (k + 0.5) / bodies, rho = std::sqrt(1.0 - z * z);
    X.col(k) << R * rho * std::cos(k * golden_angle), R * rho * std::sin(k * golden_angle), R * z;
  }
  return X;
}

/// The same spiral on the geodesic disc of H^2 of radius u R about the origin (equal areas:
/// cosh(r_k / R) - 1 proportional to k + 1/2).
Eigen::MatrixXd spiral_hyperbolic_disc(int bodies, double R, double u) {
  Eigen::MatrixXd X(3, bodies);
  for (int k = 0; k < bodies; ++k) {
    const double c = 1.0 + (k + 0.5) / bodies * (std::cosh(u) - 1.0), s = std::sqrt(c * c - 1.0);
    X.col(k) << R * s * std::cos(k * golden_angle), R * s * std::sin(k * golden_angle), R * c;
  }
  return X;
}

/// A random tangent velocity at x: a normal vector (per-component deviation `speed`) with its
/// normal part removed.
Eigen::VectorXd tangent_velocity(const SpaceSpec& space, const Eigen::VectorXd& x, double speed, Deviates& random) {
  Eigen::VectorXd v = speed * random.normal_vector(static_cast<int>(x.size()));
  const double R2 = space.radius * space.radius;
  if (space.kind == SpaceKind::sphere) {
    v -= (x.dot(v) / R2) * x;
  } else if (space.kind == SpaceKind::hyperbolic) {
    const Eigen::Index last = x.size() - 1;
    const double minkowski = x.head(last).dot(v.head(last)) - x(last) * v(last);  // <x, v>_L
    v += (minkowski / R2) * x;  // <x, x>_L = -R^2
  }
  return v;
}

}  // namespace

double scaling_radius(int dim, int bodies) {
  return std::pow(bodies / density / unit_sphere_area(dim + 1), 1.0 / dim);
}

Scene scaling_scene(const ScalingPoint& point, std::uint64_t seed) {
  Scene scene;
  scene.name = "scaling";
  scene.source = "<sesi bench --scaling>";
  scene.space.kind = point.space;
  scene.space.dim = point.dim;
  scene.space.radius = point.space == SpaceKind::euclidean ? 1.0 : scaling_radius(point.dim, point.bodies);
  const double R = scene.space.radius;
  Deviates random(seed);

  Eigen::MatrixXd X;
  switch (point.space) {
    case SpaceKind::sphere:
      X = point.dim == 2 ? fibonacci_sphere(point.bodies, R) : separated_points(scene.space, point.bodies, 0, random);
      break;
    case SpaceKind::hyperbolic: {
      const double u = hyperbolic_ball_radius(point.dim, R, point.bodies);
      X = point.dim == 2 ? spiral_hyperbolic_disc(point.bodies, R, u)
                         : separated_points(scene.space, point.bodies, u, random);
      break;
    }
    case SpaceKind::euclidean:
      X = separated_points(scene.space, point.bodies, std::pow(point.bodies / density, 1.0 / point.dim), random);
      break;
  }
  const bool gravity = point.potential == "cotangent-gravity";
  Eigen::MatrixXd V(X.rows(), X.cols());
  for (int b = 0; b < point.bodies; ++b) V.col(b) = tangent_velocity(scene.space, X.col(b), gravity ? 0.1 : 1.0, random);
  if (point.space == SpaceKind::hyperbolic && point.center_distance != 0) {
    boost(X, point.center_distance);  // an isometry: the velocities go along
    boost(V, point.center_distance);
  }

  const Geometry geometry(scene.space);
  scene.bodies.resize(static_cast<std::size_t>(point.bodies));
  for (int b = 0; b < point.bodies; ++b) {
    Body& body = scene.bodies[static_cast<std::size_t>(b)];
    geometry.to_chart(X.col(b), V.col(b), body.mass, body.q, body.p);
  }
  if (gravity) {
    scene.potentials.emplace_back(CotangentGravitySpec{1.0 / point.bodies});
  } else {
    scene.potentials.emplace_back(LennardJonesSpec{1.0, 1.0, lj_cutoff});
  }
  scene.integrator.method = point.method;
  scene.integrator.dt = gravity ? gravity_dt : lj_dt;
  scene.integrator.t_end = 0.0;
  scene.integrator.check_every = point.check_every;
  scene.integrator.neighbour_skin = point.neighbour_skin;
  return scene;
}

long pairs_within(const Scene& scene, double cutoff) {
  const long n = scene.body_count();
  if (!std::isfinite(cutoff)) return n * (n - 1) / 2;
  const Geometry geometry(scene.space);
  Eigen::MatrixXd X(geometry.ambient_dim(), n);
  for (long b = 0; b < n; ++b) X.col(b) = geometry.embed(scene.bodies[static_cast<std::size_t>(b)].q);
  return static_cast<long>(geometry.close_pairs(X, cutoff).size());
}

namespace {

/// The plain flat loop's bodies in a periodic cube of side L (unit masses), kept sorted by cell
/// (a counting sort every step, so that a cell's bodies are contiguous in memory, as MD codes
/// do) with cells of side >= the cutoff, at least 3 per side (below that, one cell).
class PeriodicBox {
 public:
  PeriodicBox(std::vector<double> x, std::vector<double> v, double side, double cutoff)
      : n_(static_cast<int>(x.size() / 3)), L_(side), x_(std::move(x)), v_(std::move(v)), a_(x_.size(), 0.0) {
    cells_ = std::max(1, static_cast<int>(side / cutoff));
    if (cells_ < 3) cells_ = 1;
    start_.assign(static_cast<std::size_t>(cells_ * cells_ * cells_) + 1, 0);
  }

  /// Velocity Verlet with dt; returns the pairs within the cutoff.
  long step(double dt, double rc2) {
    for (std::size_t k = 0; k < x_.size(); ++k) {
      v_[k] += 0.5 * dt * a_[k];
      x_[k] += dt * v_[k];
      x_[k] -= L_ * std::floor(x_[k] / L_);
    }
    const long pairs = forces(rc2);
    for (std::size_t k = 0; k < x_.size(); ++k) v_[k] += 0.5 * dt * a_[k];
    return pairs;
  }

  /// Sort by cell, then Lennard-Jones (epsilon = sigma = 1) accelerations, each pair once.
  long forces(double rc2) {
    sort();
    std::fill(a_.begin(), a_.end(), 0.0);
    long pairs = 0;
    const auto pair = [&](int i, int j, const double* shift) {
      const double dx = x_[3 * i] - x_[3 * j] - shift[0], dy = x_[3 * i + 1] - x_[3 * j + 1] - shift[1],
                   dz = x_[3 * i + 2] - x_[3 * j + 2] - shift[2], r2 = dx * dx + dy * dy + dz * dz;
      if (r2 >= rc2) return;
      ++pairs;
      const double inv2 = 1.0 / r2, inv6 = inv2 * inv2 * inv2;
      const double f = 24.0 * inv2 * inv6 * (2.0 * inv6 - 1.0);  // -dV/dr / r, V = 4 (r^-12 - r^-6)
      a_[3 * i] += f * dx, a_[3 * i + 1] += f * dy, a_[3 * i + 2] += f * dz;
      a_[3 * j] -= f * dx, a_[3 * j + 1] -= f * dy, a_[3 * j + 2] -= f * dz;
    };
    if (cells_ == 1) {
      for (int i = 0; i < n_; ++i)
        for (int j = i + 1; j < n_; ++j) {
          double shift[3];  // the nearest image
          for (int a = 0; a < 3; ++a) shift[a] = L_ * std::nearbyint((x_[3 * i + a] - x_[3 * j + a]) / L_);
          pair(i, j, shift);
        }
      return pairs;
    }
    // Half of the 26 neighbours, so each pair of cells once; across a face of the box, the
    // neighbour cell's image shift (no division per pair).
    static constexpr std::array<std::array<int, 3>, 13> half{{{1, 0, 0}, {-1, 1, 0}, {0, 1, 0}, {1, 1, 0},
                                                            {-1, -1, 1}, {0, -1, 1}, {1, -1, 1}, {-1, 0, 1},
                                                            {0, 0, 1}, {1, 0, 1}, {-1, 1, 1}, {0, 1, 1}, {1, 1, 1}}};
    const double none[3] = {0, 0, 0};
    for (int cz = 0; cz < cells_; ++cz)
      for (int cy = 0; cy < cells_; ++cy)
        for (int cx = 0; cx < cells_; ++cx) {
          const int c = cx + cells_ * (cy + cells_ * cz);
          const int begin = start_[static_cast<std::size_t>(c)], end = start_[static_cast<std::size_t>(c) + 1];
          for (int i = begin; i < end; ++i)
            for (int j = i + 1; j < end; ++j) pair(i, j, none);
          for (const auto& o : half) {
            const int at[3] = {cx + o[0], cy + o[1], cz + o[2]};
            double shift[3];
            int wrapped[3];
            for (int a = 0; a < 3; ++a) {
              shift[a] = at[a] < 0 ? -L_ : (at[a] >= cells_ ? L_ : 0.0);
              wrapped[a] = at[a] < 0 ? at[a] + cells_ : (at[a] >= cells_ ? at[a] - cells_ : at[a]);
            }
            const std::size_t d = static_cast<std::size_t>(wrapped[0] + cells_ * (wrapped[1] + cells_ * wrapped[2]));
            for (int i = begin; i < end; ++i)
              for (int j = start_[d]; j < start_[d + 1]; ++j) pair(i, j, shift);
          }
        }
    return pairs;
  }

 private:
  int cell_of(double coordinate) const { return std::min(cells_ - 1, static_cast<int>(coordinate / L_ * cells_)); }

  void sort() {
    std::fill(start_.begin(), start_.end(), 0);
    cell_.resize(static_cast<std::size_t>(n_));
    for (int i = 0; i < n_; ++i) {
      const std::size_t k = 3 * static_cast<std::size_t>(i);
      cell_[static_cast<std::size_t>(i)] = cell_of(x_[k]) + cells_ * (cell_of(x_[k + 1]) + cells_ * cell_of(x_[k + 2]));
      ++start_[static_cast<std::size_t>(cell_[static_cast<std::size_t>(i)]) + 1];
    }
    for (std::size_t c = 1; c < start_.size(); ++c) start_[c] += start_[c - 1];
    std::vector<int> fill(start_.begin(), start_.end() - 1);
    sorted_x_.resize(x_.size());
    sorted_v_.resize(v_.size());
    sorted_a_.resize(a_.size());
    for (int i = 0; i < n_; ++i) {
      const std::size_t to = 3 * static_cast<std::size_t>(fill[static_cast<std::size_t>(cell_[static_cast<std::size_t>(i)])]++);
      for (std::size_t a = 0; a < 3; ++a) {
        sorted_x_[to + a] = x_[3 * static_cast<std::size_t>(i) + a];
        sorted_v_[to + a] = v_[3 * static_cast<std::size_t>(i) + a];
        sorted_a_[to + a] = a_[3 * static_cast<std::size_t>(i) + a];
      }
    }
    x_.swap(sorted_x_);
    v_.swap(sorted_v_);
    a_.swap(sorted_a_);
  }

  int n_;
  double L_;
  int cells_ = 1;
  std::vector<double> x_, v_, a_, sorted_x_, sorted_v_, sorted_a_;
  std::vector<int> start_, cell_;
};

}  // namespace

double flat_cell_list_seconds_per_step(int bodies, long steps, long& pairs) {
  const double L = std::cbrt(bodies / density), rc2 = lj_cutoff * lj_cutoff, dt = lj_dt;
  Deviates random(1);
  // Random sequential addition in the periodic box, as the curved scenes' bodies.
  const int period = std::max(1, static_cast<int>(L));  // cells of side L / period >= 1
  const auto draw = [&]() -> Eigen::VectorXd {
    return Eigen::Vector3d(L * random.uniform(), L * random.uniform(), L * random.uniform());
  };
  const auto key = [](const Eigen::VectorXd& p) -> Eigen::VectorXd { return p; };
  const auto too_close = [L](const Eigen::VectorXd& p, const Eigen::VectorXd& q) {
    Eigen::VectorXd d = p - q;
    for (Eigen::Index a = 0; a < 3; ++a) d(a) -= L * std::nearbyint(d(a) / L);
    return d.squaredNorm() < 1.0;
  };
  const auto points = sequential_addition(bodies, draw, key, too_close, L / period, period);
  std::vector<double> x(3 * static_cast<std::size_t>(bodies)), v(x.size());
  for (int b = 0; b < bodies; ++b)
    for (int k = 0; k < 3; ++k) x[3 * static_cast<std::size_t>(b) + k] = points[static_cast<std::size_t>(b)](k);
  for (double& c : v) c = random.normal();
  PeriodicBox box(std::move(x), std::move(v), L, lj_cutoff);
  box.forces(rc2);
  box.step(dt, rc2);  // warm caches
  const auto start = std::chrono::steady_clock::now();
  for (long s = 0; s < steps; ++s) pairs = box.step(dt, rc2);
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() / static_cast<double>(steps);
}

}  // namespace sesi::program::bench
