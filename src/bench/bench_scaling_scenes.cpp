#include "bench_scaling_scenes.hpp"

#include <unistd.h>

#include <array>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
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

/// Random sequential addition in the periodic box [0, L)^n: uniform points, each kept when no
/// kept point's minimum image is within 1 sigma (cells of side L / floor(L) >= 1, wrapping).
Eigen::MatrixXd box_points(int dim, int bodies, double L, Deviates& random) {
  const int period = std::max(1, static_cast<int>(L));
  const auto draw = [&]() -> Eigen::VectorXd {
    Eigen::VectorXd x(dim);
    for (int k = 0; k < dim; ++k) x(k) = L * random.uniform();
    return x;
  };
  const auto key = [](const Eigen::VectorXd& x) -> Eigen::VectorXd { return x; };
  const auto too_close = [L](const Eigen::VectorXd& x, const Eigen::VectorXd& y) {
    Eigen::VectorXd d = x - y;
    for (Eigen::Index k = 0; k < d.size(); ++k) d(k) -= L * std::nearbyint(d(k) / L);
    return d.squaredNorm() < 1.0;
  };
  const auto points = sequential_addition(bodies, draw, key, too_close, L / period, period);
  Eigen::MatrixXd X(dim, bodies);
  for (int b = 0; b < bodies; ++b) X.col(b) = points[static_cast<std::size_t>(b)];
  return X;
}

/// Random sequential addition in the fundamental polygon D of a compact surface: uniform points of
/// the geodesic disc of D's circumradius, kept when inside D and when no kept point lies within
/// 1 sigma of the point or of its images within 1 sigma of D (images_near), found through a hash
/// of cells over the spatial coordinates (x1, x2): a Minkowski chord c moves them by at most
/// c cosh(u) within u radii of the origin, and every point looked at lies within circumradius +
/// 1 sigma of it.
Eigen::MatrixXd surface_points(const SpaceSpec& space, int bodies, Deviates& random) {
  const sesi::HyperbolicSurface<double> surface(space.genus, space.radius);
  const double R = space.radius, reach = 1.0;
  const double extent = surface.circumradius() / R;
  const double chord = 2 * R * std::sinh(0.5 / R);  // Minkowski chord of geodesic distance 1
  const double cell = chord * std::cosh(extent + reach / R);
  std::unordered_map<std::uint64_t, std::vector<int>> cells;
  const auto cell_of = [cell](const Eigen::Vector3d& y) {
    return std::array<long, 2>{static_cast<long>(std::floor(y(0) / cell)), static_cast<long>(std::floor(y(1) / cell))};
  };
  const auto hash = [](long a, long b) {
    return (0x9e3779b97f4a7c15ull ^ static_cast<std::uint64_t>(a)) * 0x100000001b3ull ^ static_cast<std::uint64_t>(b);
  };
  std::vector<Eigen::Vector3d> kept;
  kept.reserve(static_cast<std::size_t>(bodies));
  std::vector<int> near;
  for (int b = 0; b < bodies; ++b) {
    for (long trial = 0;; ++trial) {
      if (trial == 10'000'000) throw std::runtime_error("sesi bench --scaling: no room for the bodies");
      const Eigen::Vector3d x = random_point(space, extent, random);
      if (surface.outside(x) > 0) continue;
      near.assign(1, 0);
      surface.images_near(x, reach, near);
      bool fits = true;
      for (std::size_t m = 0; m < near.size() && fits; ++m) {
        if (m > 0 && near[m] == 0) continue;  // the identity, looked at first
        Eigen::Vector3d y = x;
        if (near[m] != 0) surface.apply(near[m], y);
        const auto home = cell_of(y);
        for (long dx = -1; dx <= 1 && fits; ++dx)
          for (long dy = -1; dy <= 1 && fits; ++dy) {
            const auto found = cells.find(hash(home[0] + dx, home[1] + dy));
            if (found == cells.end()) continue;
            for (const int j : found->second) {
              const Eigen::Vector3d d = y - kept[static_cast<std::size_t>(j)];
              if (d.head<2>().squaredNorm() - d(2) * d(2) < chord * chord) {
                fits = false;
                break;
              }
            }
          }
      }
      if (!fits) continue;
      const auto home = cell_of(x);
      cells[hash(home[0], home[1])].push_back(b);
      kept.push_back(x);
      break;
    }
  }
  Eigen::MatrixXd X(3, bodies);
  for (int b = 0; b < bodies; ++b) X.col(b) = kept[static_cast<std::size_t>(b)];
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

/// A unit-temperature velocity at x on H^2 (radius R) for bodies far from the origin: normal
/// components along the Lorentz-orthonormal tangent frame e_r = (cosh u cos phi, cosh u sin phi,
/// sinh u), e_phi = (-sin phi, cos phi, 0) at x = R (sinh u cos phi, sinh u sin phi, cosh u).
/// (tangent_velocity projects an ambient normal vector, whose speed grows as cosh u there.)
Eigen::VectorXd surface_velocity(const Eigen::VectorXd& x, double R, Deviates& random) {
  const double a = random.normal(), b = random.normal();
  const double rho = std::hypot(x(0), x(1));  // R sinh u
  const double c = rho > 0 ? x(0) / rho : 1.0, s = rho > 0 ? x(1) / rho : 0.0;
  Eigen::VectorXd v(3);
  v << a * (x(2) / R) * c - b * s, a * (x(2) / R) * s + b * c, a * rho / R;
  return v;
}

}  // namespace

double scaling_radius(int dim, int bodies) {
  return std::pow(bodies / density / unit_sphere_area(dim + 1), 1.0 / dim);
}

double box_edge(int dim, int bodies) { return std::pow(bodies / density, 1.0 / dim); }

double surface_radius(int genus, int bodies) {
  return std::sqrt(bodies / density / (4.0 * std::numbers::pi * (genus - 1)));
}

Scene scaling_scene(const ScalingPoint& point, std::uint64_t seed) {
  Scene scene;
  scene.name = "scaling";
  scene.source = "<sesi bench --scaling>";
  scene.space.kind = point.space;
  scene.space.dim = point.dim;
  scene.space.radius = point.space == SpaceKind::euclidean ? 1.0 : scaling_radius(point.dim, point.bodies);
  if (point.box) scene.space.box.assign(static_cast<std::size_t>(point.dim), box_edge(point.dim, point.bodies));
  if (point.genus != 0) {
    scene.space.genus = point.genus;
    scene.space.radius = surface_radius(point.genus, point.bodies);
  }
  const double R = scene.space.radius;
  Deviates random(seed);

  Eigen::MatrixXd X;
  if (point.box) {
    X = box_points(point.dim, point.bodies, scene.space.box[0], random);
  } else if (point.genus != 0) {
    X = surface_points(scene.space, point.bodies, random);
  } else switch (point.space) {
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
  for (int b = 0; b < point.bodies; ++b) {
    V.col(b) = point.genus != 0 ? surface_velocity(X.col(b), R, random)
                                : tangent_velocity(scene.space, X.col(b), gravity ? 0.1 : 1.0, random);
  }
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
  // The placement by minimum image in the domain, checked by the program's own search.
  if (point.box || point.genus != 0) {
    if (pairs_within(scene, 0.999) != 0) throw std::logic_error("sesi bench --scaling: bodies placed too close");
  }
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
class PlainBox {
 public:
  PlainBox(std::vector<double> x, std::vector<double> v, double side, double cutoff)
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
  PlainBox box(std::move(x), std::move(v), L, lj_cutoff);
  box.forces(rc2);
  box.step(dt, rc2);  // warm caches
  const auto start = std::chrono::steady_clock::now();
  for (long s = 0; s < steps; ++s) pairs = box.step(dt, rc2);
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() / static_cast<double>(steps);
}

std::string on_path(const std::string& name) {
  const char* path = std::getenv("PATH");
  std::stringstream dirs(path ? path : "");
  std::string dir;
  while (std::getline(dirs, dir, ':')) {
    if (dir.empty()) continue;
    const std::string candidate = dir + "/" + name;
    if (access(candidate.c_str(), X_OK) == 0) return candidate;
  }
  return {};
}

std::string lammps_unavailable(int ranks) {
  if (on_path("lmp").empty()) return "no LAMMPS program lmp on PATH (Debian: lammps)";
  if (ranks > 1 && on_path("mpirun").empty()) return "no mpirun on PATH (Debian: openmpi-bin)";
  return {};
}

std::optional<double> lammps_seconds_per_step(const Scene& scene, int ranks, long warm, long steps, std::string& why) {
  const int dim = scene.space.dim;
  if (scene.space.kind != SpaceKind::euclidean || scene.space.box.empty() || (dim != 2 && dim != 3)) {
    why = "LAMMPS rows need a periodic box of E^2 or E^3";
    return std::nullopt;
  }
  why = lammps_unavailable(ranks);
  if (!why.empty()) return std::nullopt;
  const std::string lmp = on_path("lmp"), mpirun = ranks > 1 ? on_path("mpirun") : std::string();
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("sesi-scaling-lammps-" + std::to_string(getpid()));
  std::filesystem::create_directories(dir);
  {
    std::ofstream data(dir / "system.data");
    data.precision(17);
    data << "sesi bench --scaling\n\n" << scene.body_count() << " atoms\n1 atom types\n\n";
    for (int k = 0; k < 3; ++k) {
      const char axis = "xyz"[k];
      if (k < dim) data << "0 " << scene.space.box[static_cast<std::size_t>(k)];
      else data << "-0.5 0.5";
      data << ' ' << axis << "lo " << axis << "hi\n";
    }
    data << "\nMasses\n\n1 1\n\nAtoms # atomic\n\n";
    for (std::size_t b = 0; b < scene.bodies.size(); ++b) {
      const Body& body = scene.bodies[b];
      data << b + 1 << " 1";
      for (int k = 0; k < 3; ++k) data << ' ' << (k < dim ? body.q(k) : 0.0);
      data << '\n';
    }
    data << "\nVelocities\n\n";
    for (std::size_t b = 0; b < scene.bodies.size(); ++b) {
      const Body& body = scene.bodies[b];
      data << b + 1;
      for (int k = 0; k < 3; ++k) data << ' ' << (k < dim ? body.p(k) / body.mass : 0.0);
      data << '\n';
    }
    std::ofstream in(dir / "in.lammps");
    in.precision(17);
    in << "units lj\ndimension " << dim << "\nboundary p p p\natom_style atomic\nread_data "
       << (dir / "system.data").string() << "\npair_style lj/cut " << lj_cutoff << "\npair_coeff * * 1 1 " << lj_cutoff
       << "\npair_modify shift yes\nneighbor " << lj_cutoff * scene.integrator.neighbour_skin
       << " bin\nneigh_modify every 1 delay 0 check yes\nfix integrate all nve\n"
       << (dim == 2 ? "fix plane all enforce2d\n" : "") << "timestep " << *scene.integrator.dt
       << "\nthermo_style custom step pe ke\nthermo_modify norm no\nthermo 1000000000\nrun " << warm << "\nrun "
       << steps << "\n";
  }
  std::string command = "OMP_NUM_THREADS=1 ";
  if (ranks > 1) {
    command += mpirun + " -np " + std::to_string(ranks) + (geteuid() == 0 ? " --allow-run-as-root" : "") + " ";
  }
  command += lmp + " -nocite -screen none -in " + (dir / "in.lammps").string() + " -log " + (dir / "log.lammps").string() +
             " > " + (dir / "out.txt").string() + " 2>&1";
  const int status = std::system(command.c_str());
  std::optional<double> out;
  std::ifstream log(dir / "log.lammps");
  std::string line;
  double loop = -1;
  long loop_steps = 0;
  while (std::getline(log, line)) {
    // "Loop time of 1.234 on 2 procs for 40 steps with 100000 atoms": the last run's.
    if (line.rfind("Loop time of ", 0) != 0) continue;
    std::istringstream words(line.substr(13));
    std::string on, procs, for_, steps_word;
    int p = 0;
    words >> loop >> on >> p >> procs >> for_ >> loop_steps;
  }
  if (status != 0 || loop < 0 || loop_steps != steps) {
    why = "LAMMPS failed (" + command + ", exit status " + std::to_string(status) + ")";
  } else {
    out = loop / static_cast<double>(steps);
  }
  std::filesystem::remove_all(dir);
  return out;
}

}  // namespace sesi::program::bench
