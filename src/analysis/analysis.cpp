#include "analysis.hpp"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <limits>
#include <mutex>
#include <numbers>
#include <stdexcept>
#include <variant>

#include <sesi/neighbours.hpp>
#include <sesi/parallel.hpp>
#include <sesi/spaces/euclidean.hpp>
#include <sesi/spaces/hyperbolic.hpp>
#include <sesi/spaces/sphere.hpp>
#include <sesi/topologies/hyperbolic_surface.hpp>
#include <sesi/topologies/periodic_box.hpp>

#include "errors.hpp"

namespace sesi::analysis {

namespace {

constexpr double nan = std::numeric_limits<double>::quiet_NaN();
constexpr double pi = std::numbers::pi;

/// The 8-point Gauss-Legendre rule on [-1, 1] (Abramowitz and Stegun, table 25.4): exact for
/// polynomials of degree <= 15.
constexpr std::array<double, 4> gl_node = {0.18343464249564980494, 0.52553240991632898582, 0.79666647741362673959,
                                           0.96028985649753623168};
constexpr std::array<double, 4> gl_weight = {0.36268378337836198297, 0.31370664587788728734, 0.22238103445337447054,
                                             0.10122853629037625915};

/// The shell's radial density s_R(s)^{n-1} (without Omega_{n-1}).
double radial_density(const SpaceSpec& space, double s) {
  const int m = space.dim - 1;
  if (m == 0) return 1.0;
  const double r = space.radius;
  switch (space.kind) {
    case SpaceKind::sphere:
      return std::pow(r * std::sin(s / r), m);
    case SpaceKind::hyperbolic:
      return std::pow(r * std::sinh(s / r), m);
    case SpaceKind::euclidean:
      break;
  }
  return std::pow(s, m);
}

/// int_a^b weight(s) radial_density(s) ds by the 8-point rule on pieces of width at most
/// R / (4 max(1, n - 1)). The rule's remainder on a piece of width h is
/// h^17 (8!)^4 / (17 (16!)^3) |f^(16)| (Abramowitz and Stegun 25.4.30), and sin^m, sinh^m are
/// sums of exponentials e^{+-k s/R}, k <= m, so |f^(16)| <= (m/R)^16 max|f| (times weight's
/// growth): with h = R / 4m the remainder is below 1e-33 h max|f| on each piece, far below
/// the rounding of the sum.
template <class Weight>
double radial_integral(const SpaceSpec& space, double a, double b, Weight&& weight) {
  if (!(b > a)) return 0.0;
  const double scale = space.kind == SpaceKind::euclidean ? std::max(b, 1.0) : space.radius;
  const double width = scale / (4.0 * std::max(1, space.dim - 1));
  const long pieces = std::max(1L, static_cast<long>(std::ceil((b - a) / width)));
  const double h = (b - a) / static_cast<double>(pieces);
  double total = 0.0;
  for (long k = 0; k < pieces; ++k) {
    const double mid = a + (static_cast<double>(k) + 0.5) * h, half = h / 2;
    double piece = 0.0;
    for (std::size_t j = 0; j < gl_node.size(); ++j) {
      for (const double sign : {-1.0, 1.0}) {
        const double s = mid + sign * half * gl_node[j];
        piece += gl_weight[j] * weight(s) * radial_density(space, s);
      }
    }
    total += piece * half;
  }
  return total;
}

using Charts = std::variant<sesi::Sphere<Eigen::Dynamic>, sesi::Hyperbolic<Eigen::Dynamic>,
                            sesi::Euclidean<Eigen::Dynamic>>;

Charts chart_of(const SpaceSpec& space) {
  switch (space.kind) {
    case SpaceKind::sphere:
      return sesi::Sphere<Eigen::Dynamic>(space.radius, space.dim);
    case SpaceKind::hyperbolic:
      return sesi::Hyperbolic<Eigen::Dynamic>(space.radius, space.dim);
    case SpaceKind::euclidean:
      break;
  }
  return sesi::Euclidean<Eigen::Dynamic>(space.dim);
}

/// Minkowski product (time-like coordinate last) or Euclidean dot product of two columns.
double inner(const SpaceSpec& space, const double* u, const double* w, int a) {
  double s = 0.0;
  for (int k = 0; k < a; ++k) s += u[k] * w[k];
  if (space.kind == SpaceKind::hyperbolic) s -= 2.0 * u[a - 1] * w[a - 1];
  return s;
}

/// The distance of two embedding points given as arrays of a coordinates.
double distance_of(const SpaceSpec& space, const double* x, const double* y, int a) {
  const double r = space.radius;
  switch (space.kind) {
    case SpaceKind::sphere: {
      // 2R atan2(|x - y|, |x + y|): accurate at all angles (sphere.hpp).
      double minus = 0.0, plus = 0.0;
      for (int k = 0; k < a; ++k) {
        minus += (x[k] - y[k]) * (x[k] - y[k]);
        plus += (x[k] + y[k]) * (x[k] + y[k]);
      }
      return 2.0 * r * std::atan2(std::sqrt(minus), std::sqrt(plus));
    }
    case SpaceKind::hyperbolic: {
      // By radii and directions (Hyperbolic::polar_distance): eps sinh(rho) far out, where the
      // chord would lose eps e^{2 rho}.
      const int n = a - 1;
      double sx = 0.0, sy = 0.0;
      for (int k = 0; k < n; ++k) {
        sx += x[k] * x[k];
        sy += y[k] * y[k];
      }
      sx = std::sqrt(sx) / r;
      sy = std::sqrt(sy) / r;
      double h = 0.0;
      if (sx > 0.0 && sy > 0.0) {
        for (int k = 0; k < n; ++k) {
          const double u = x[k] / (r * sx) - y[k] / (r * sy);
          h += u * u;
        }
        h /= 2.0;
      }
      const double half = std::sinh((std::asinh(sx) - std::asinh(sy)) / 2.0);
      return 2.0 * r * std::asinh(std::sqrt(half * half + sx * sy * h / 2.0));
    }
    case SpaceKind::euclidean:
      break;
  }
  double s = 0.0;
  for (int k = 0; k < a; ++k) s += (x[k] - y[k]) * (x[k] - y[k]);
  return std::sqrt(s);
}

double transported_dot_of(const SpaceSpec& space, const double* x, const double* v, const double* y, const double* w,
                          int a) {
  const double vw = inner(space, v, w, a);
  if (space.kind == SpaceKind::euclidean) return vw;
  const double r = space.radius;
  // With unit points x^ = x/R, y^ = y/R the transport along the geodesic from x to y is
  //   S^n: P v = v - (y^.v) / (1 + x^.y^) (x^ + y^),   H^n: P v = v + <y^,v> / (1 - <x^,y^>) (x^ + y^)
  // (it keeps <P v, y> = 0 and |P v| = |v|, and is the rotation or boost in the plane of x and
  // y that takes x to y: Levi-Civita transport along their geodesic); as w is tangent at y,
  // <P v, w> = <v, w> -+ (y^.v)(x^.w) / (1 +- x^.y^). The denominators without cancellation:
  // S^n: 1 + x^.y^ = |x^ + y^|^2 / 2, zero only at antipodes; H^n: 1 - <x^,y^> = 2 + |x^ - y^|_L^2 / 2 >= 2.
  const double yv = inner(space, y, v, a) / r, xw = inner(space, x, w, a) / r;
  double chord = 0.0;
  if (space.kind == SpaceKind::sphere) {
    for (int k = 0; k < a; ++k) chord += (x[k] + y[k]) * (x[k] + y[k]);
    const double denominator = chord / (2.0 * r * r);
    if (!(denominator > 0.0)) return nan;  // antipodes: no unique geodesic
    return vw - yv * xw / denominator;
  }
  for (int k = 0; k < a; ++k) chord += (x[k] - y[k]) * (x[k] - y[k]);
  chord -= 2.0 * (x[a - 1] - y[a - 1]) * (x[a - 1] - y[a - 1]);
  return vw + yv * xw / (2.0 + chord / (2.0 * r * r));
}

std::string number(double v) { return program::format_number(v); }

}  // namespace

// ---- the space's topology ----------------------------------------------------------------------

/// The library's topology of a quotient space (include/sesi/topologies/): the minimum image, the
/// reduction into the domain, the ghost images near the domain and the domain's volume. One
/// place here that asks the library; the observables below go through it.
class Topology {
 public:
  using Box = sesi::PeriodicBox<double, Eigen::Dynamic>;
  using Surface = sesi::HyperbolicSurface<double>;

  explicit Topology(const SpaceSpec& space) : space_(space) {
    try {
      if (!space.box.empty()) {
        if (space.kind != SpaceKind::euclidean || static_cast<int>(space.box.size()) != space.dim) {
          throw program::InputError("space.box: expected " + std::to_string(space.dim) +
                                    " edges of a euclidean space's box");
        }
        box_.emplace(Eigen::Map<const Eigen::VectorXd>(space.box.data(), static_cast<Eigen::Index>(space.box.size())));
      } else if (space.genus != 0) {
        if (space.kind != SpaceKind::hyperbolic || space.dim != 2) {
          throw program::InputError("space.genus: a compact surface needs a hyperbolic space of dim 2");
        }
        surface_.emplace(space.genus, space.radius);
      }
    } catch (const std::invalid_argument& e) {
      throw program::InputError(std::string("space: ") + e.what());
    }
  }

  bool is_box() const { return box_.has_value(); }
  const Box& box() const { return *box_; }
  const Surface& surface() const { return *surface_; }
  double max_cutoff() const { return box_ ? box_->max_cutoff() : surface_->max_cutoff(); }

  /// The domain's volume: L_1 ... L_n; the surface's area 4 pi (g - 1) R^2 (Gauss-Bonnet;
  /// Sausset and Tarjus, J. Phys. A 40, 12873 (2007)).
  double volume() const { return box_ ? box_->edges().prod() : surface_->area(); }

  /// x <- its image in the domain (PeriodicBox::reduce, HyperbolicSurface::reduce).
  void reduce(double* x) const {
    if (box_) {
      Eigen::Map<Eigen::VectorXd> y(x, box_->edges().size());
      Eigen::Matrix<std::int64_t, Eigen::Dynamic, 1> counts = Eigen::Matrix<std::int64_t, Eigen::Dynamic, 1>::Zero(y.size());
      box_->reduce(y, counts);
      return;
    }
    Surface::Vector y(x[0], x[1], x[2]);
    Surface::Word applied;
    surface_->reduce(y, applied);
    for (int k = 0; k < 3; ++k) x[k] = y(k);
  }

  /// y <- the image of y nearest to x (the library's minimum image).
  void nearest(const double* x, double* y) const {
    if (box_) {
      const Eigen::Map<const Eigen::VectorXd> xm(x, box_->edges().size());
      Eigen::VectorXd ym = Eigen::Map<const Eigen::VectorXd>(y, box_->edges().size());
      box_->nearest_image(xm, ym);
      for (Eigen::Index k = 0; k < ym.size(); ++k) y[k] = ym(k);
      return;
    }
    const Surface::Vector xv(x[0], x[1], x[2]);
    Surface::Vector yv(y[0], y[1], y[2]);
    surface_->nearest_image(xv, yv);
    for (int k = 0; k < 3; ++k) y[k] = yv(k);
  }

  /// Appends to `ghosts` (and the body's index to `origin`) every image of the domain point y,
  /// other than y itself, that lies within reach of the domain: every image that can be within
  /// reach of a body in the domain. Box: per axis the shifts 0, +L (y_k < reach) and -L
  /// (y_k > L - reach), all their combinations but none; surface: images_near.
  void add_ghosts(const Eigen::Ref<const Eigen::VectorXd>& y, int body, double reach,
                  std::vector<Eigen::VectorXd>& ghosts, std::vector<int>& origin, std::vector<int>& near) const {
    if (box_) {
      const Eigen::Index n = y.size();
      std::vector<std::array<double, 3>> shifts(static_cast<std::size_t>(n));
      std::vector<int> options(static_cast<std::size_t>(n)), at(static_cast<std::size_t>(n), 0);
      for (Eigen::Index k = 0; k < n; ++k) {
        const double l = box_->edges()(k);
        auto& s = shifts[static_cast<std::size_t>(k)];
        int m = 0;
        s[m++] = 0.0;
        if (y(k) < reach) s[m++] = 1.0;
        if (y(k) > l - reach) s[m++] = -1.0;
        options[static_cast<std::size_t>(k)] = m;
      }
      while (true) {
        // The next combination (an odometer over the axes); the first, all zero, is y itself.
        Eigen::Index k = 0;
        while (k < n && ++at[static_cast<std::size_t>(k)] == options[static_cast<std::size_t>(k)]) {
          at[static_cast<std::size_t>(k)] = 0;
          ++k;
        }
        if (k == n) break;
        Eigen::VectorXd g = y;
        // y + L n, as PeriodicBox::nearest_image writes it, so that the ghost is the same point
        // to the bit as the minimum image of the all-pairs reference.
        for (Eigen::Index a = 0; a < n; ++a) {
          g(a) = y(a) + box_->edges()(a) * shifts[static_cast<std::size_t>(a)][static_cast<std::size_t>(at[static_cast<std::size_t>(a)])];
        }
        ghosts.push_back(std::move(g));
        origin.push_back(body);
      }
      return;
    }
    const Surface::Vector v(y(0), y(1), y(2));
    near.clear();
    surface_->images_near(v, reach, near);
    for (const int k : near) {
      if (k == 0) continue;  // images()[0] is the identity: y itself
      Surface::Vector g = v;
      surface_->apply(k, g);
      ghosts.emplace_back(Eigen::VectorXd(g));
      origin.push_back(body);
    }
  }

  /// The squared distance in the covering space of the unwrapped points of a body at frames o
  /// and p (msd): box |(x_p - x_o) + L .* (n_p - n_o)|^2; surface d(x_o, W_o^{-1} W_p x_p)^2.
  double unwrapped_distance2(const Frames& f, std::size_t o, std::size_t p, int b) const {
    if (box_) {
      double s = 0.0;
      for (Eigen::Index k = 0; k < box_->edges().size(); ++k) {
        const auto jumps = static_cast<double>(f.images[p](k, b) - f.images[o](k, b));
        const double d = (f.x[p](k, b) - f.x[o](k, b)) + box_->edges()(k) * jumps;
        s += d * d;
      }
      return s;
    }
    Surface::Vector y;
    carry(f, o, p, b, y, nullptr);
    const double d = distance_of(space_, f.x[o].col(b).data(), y.data(), 3);
    return d * d;
  }

  /// Surface: y <- W_o^{-1} W_p x_p, the body's point at frame p seen from the tile of its point
  /// at frame o (and w <- the same isometry applied to its velocity at p, when w is given).
  /// The common prefix of the two reduced words cancels; the rest is applied letter by letter
  /// from the right: W_p's tail right to left, then the inverses of W_o's tail in order.
  void carry(const Frames& f, std::size_t o, std::size_t p, int b, Surface::Vector& y, Surface::Vector* w) const {
    const Word& wo = f.words[o][static_cast<std::size_t>(b)];
    const Word& wp = f.words[p][static_cast<std::size_t>(b)];
    std::size_t common = 0;
    while (common < wo.size() && common < wp.size() && wo[common] == wp[common]) ++common;
    y = Surface::Vector(f.x[p](0, b), f.x[p](1, b), f.x[p](2, b));
    if (w) *w = Surface::Vector(f.v[p](0, b), f.v[p](1, b), f.v[p](2, b));
    const int sides = surface_->sides(), half = sides / 2;
    const auto apply = [&](int letter) {
      y = (surface_->generator(letter) * y).eval();
      if (w) *w = (surface_->generator(letter) * *w).eval();
    };
    for (std::size_t k = wp.size(); k > common; --k) apply(wp[k - 1]);
    for (std::size_t k = common; k < wo.size(); ++k) apply((wo[k] + half) % sides);
  }

 private:
  SpaceSpec space_;
  std::optional<Box> box_;
  std::optional<Surface> surface_;
};

namespace {

/// The topology of a space (null without one), built once per space: a surface's images are a
/// walk around every vertex of its polygon, not to be repeated per distance.
std::shared_ptr<const Topology> topology_of(const SpaceSpec& space) {
  if (!space.has_topology()) return nullptr;
  static std::mutex mutex;
  static SpaceSpec key;
  static std::shared_ptr<const Topology> cached;
  const std::lock_guard<std::mutex> lock(mutex);
  if (!cached || key.kind != space.kind || key.dim != space.dim || key.radius != space.radius ||
      key.box != space.box || key.genus != space.genus) {
    cached = std::make_shared<const Topology>(space);
    key = space;
  }
  return cached;
}

}  // namespace

double max_cutoff(const SpaceSpec& space) {
  const auto topology = topology_of(space);
  return topology ? topology->max_cutoff() : std::numeric_limits<double>::infinity();
}

Word parse_word(std::string_view text, int genus) {
  Word word;
  if (text == "e") return word;
  const int sides = 4 * genus;
  const auto bad = [&]() {
    return program::InputError("word '" + program::cut_input(std::string(text)) +
                               "': expected \"e\" or side numbers 1.." + std::to_string(sides) + " joined by '.'");
  };
  std::size_t at = 0;
  while (true) {
    int side = 0;
    const auto [end, ec] = std::from_chars(text.data() + at, text.data() + text.size(), side);
    if (ec != std::errc() || side < 1 || side > sides) throw bad();
    word.push_back(static_cast<std::int16_t>(side - 1));
    at = static_cast<std::size_t>(end - text.data());
    if (at == text.size()) break;
    if (text[at] != '.') throw bad();
    ++at;
  }
  return word;
}

std::string word_text(const Word& word) {
  if (word.empty()) return "e";
  std::string out;
  for (std::size_t k = 0; k < word.size(); ++k) {
    if (k > 0) out += '.';
    out += std::to_string(word[k] + 1);
  }
  return out;
}

void reduce_into_domain(const SpaceSpec& space, Eigen::MatrixXd& X) {
  const auto topology = topology_of(space);
  if (!topology) return;
  for (Eigen::Index b = 0; b < X.cols(); ++b) topology->reduce(X.col(b).data());
}

// ---- the space's measure ---------------------------------------------------------------------

double unit_sphere_area(int k) {
  const double half = (k + 1) / 2.0;
  return 2.0 * std::pow(pi, half) / std::tgamma(half);
}

double shell_volume(const SpaceSpec& space, double a, double b) {
  a = std::max(a, 0.0);
  if (space.kind == SpaceKind::sphere) b = std::min(b, pi * space.radius);
  if (!(b > a)) return 0.0;
  const double omega = unit_sphere_area(space.dim - 1);
  if (space.kind == SpaceKind::euclidean) {
    const int n = space.dim;
    return omega * (std::pow(b, n) - std::pow(a, n)) / n;
  }
  return omega * radial_integral(space, a, b, [](double) { return 1.0; });
}

double total_volume(const SpaceSpec& space, double ball_radius) {
  if (const auto topology = topology_of(space)) return topology->volume();
  if (space.kind == SpaceKind::sphere) return unit_sphere_area(space.dim) * std::pow(space.radius, space.dim);
  return shell_volume(space, 0.0, ball_radius);
}

double msd_saturation(const SpaceSpec& space) {
  if (space.kind != SpaceKind::sphere) return nan;
  const double end = pi * space.radius;
  return radial_integral(space, 0.0, end, [](double s) { return s * s; }) /
         radial_integral(space, 0.0, end, [](double) { return 1.0; });
}

double distance(const SpaceSpec& space, const Eigen::Ref<const Eigen::VectorXd>& x,
                const Eigen::Ref<const Eigen::VectorXd>& y) {
  const Eigen::VectorXd xc = x;
  Eigen::VectorXd yc = y;
  if (const auto topology = topology_of(space)) topology->nearest(xc.data(), yc.data());
  return distance_of(space, xc.data(), yc.data(), static_cast<int>(xc.size()));
}

double transported_dot(const SpaceSpec& space, const Eigen::Ref<const Eigen::VectorXd>& x,
                       const Eigen::Ref<const Eigen::VectorXd>& v, const Eigen::Ref<const Eigen::VectorXd>& y,
                       const Eigen::Ref<const Eigen::VectorXd>& w) {
  const Eigen::VectorXd xc = x, vc = v, yc = y, wc = w;
  return transported_dot_of(space, xc.data(), vc.data(), yc.data(), wc.data(), static_cast<int>(xc.size()));
}

// ---- g(r) ----------------------------------------------------------------------------------------

Region bounding_region(const SpaceSpec& space, const Eigen::MatrixXd& X) {
  Region region;
  const int a = static_cast<int>(X.rows());
  const int n = static_cast<int>(X.cols());
  if (n == 0) return region;
  Eigen::VectorXd sum = X.rowwise().sum();
  if (space.kind == SpaceKind::hyperbolic) {
    // The Minkowski sum of points on the upper sheet is time-like; scaled onto the hyperboloid
    // it is the centre of mass of the bodies seen from the space's symmetries.
    const double norm2 = -inner(space, sum.data(), sum.data(), a);
    region.center = sum * (space.radius / std::sqrt(norm2));
  } else {
    region.center = sum / static_cast<double>(n);
  }
  for (int b = 0; b < n; ++b) {
    region.radius = std::max(region.radius, distance_of(space, region.center.data(), X.col(b).data(), a));
  }
  return region;
}

double default_rdf_max(const SpaceSpec& space, const Eigen::MatrixXd& first_frame) {
  double top = pi * space.radius, volume = total_volume(space);
  if (space.has_topology()) {
    top = max_cutoff(space);
  } else if (space.kind != SpaceKind::sphere) {
    const double extent = bounding_region(space, first_frame).radius;
    top = extent / 4;
    volume = total_volume(space, extent);
  }
  if (!(top > 0.0)) {
    throw program::InputError(program::Origin{}, "--rdf-max", "the bodies have no extent to take a default from: give a distance");
  }
  // Ten mean spacings (V/N)^{1/n} at most: the shells hold O(1) bodies each, so a frame costs
  // O(N) through the cells however many bodies there are.
  const double n = static_cast<double>(std::max<Eigen::Index>(first_frame.cols(), 1));
  return std::min(top, 10.0 * std::pow(volume / n, 1.0 / space.dim));
}

struct Rdf::Frame {
  Eigen::MatrixXd points;    ///< the bodies (on H^n far out: in a frame at the first body)
  std::vector<char> centre;  ///< body i's shell lies in the region
  int centres = 0;
  double volume = 0.0;       ///< the region's volume
};

Rdf::Rdf(SpaceSpec space, double r_max, int bins)
    : space_(space), topology_(topology_of(space)), r_max_(r_max), bins_(bins) {
  if (topology_) {
    // Beyond the largest cutoff a pair may have two images within r, and a shell about a body
    // overlaps itself: the covering space's shell is no longer the quotient's.
    const double top = topology_->max_cutoff();
    if (!(r_max > 0.0 && r_max <= top)) {
      throw program::InputError(program::Origin{}, "--rdf-max",
                                "expected a distance in (0, " + number(top) + "] on this " +
                                    (topology_->is_box() ? std::string("periodic box") : "genus-" + std::to_string(space.genus) + " surface") +
                                    " (the largest allowed cutoff is " + number(top) + "), got " + number(r_max));
    }
  }
  const double top = space.kind == SpaceKind::sphere ? pi * space.radius : std::numeric_limits<double>::infinity();
  if (!(r_max > 0.0 && r_max <= top)) {
    throw program::InputError(program::Origin{}, "--rdf-max",
                              "expected a distance in (0, " +
                                  (space.kind == SpaceKind::sphere ? "pi R = " + number(top) : std::string("inf")) +
                                  "], got " + number(r_max));
  }
  if (bins < 1 || bins > 1000000) {
    throw program::InputError(program::Origin{}, "--bins", "expected 1 to 1000000 bins, got " + std::to_string(bins));
  }
  const std::vector<double> e = edges();
  for (int k = 0; k < bins; ++k) shell_.push_back(shell_volume(space, e[static_cast<std::size_t>(k)], e[static_cast<std::size_t>(k) + 1]));
  counts_.assign(static_cast<std::size_t>(bins), 0);
  expected_.assign(static_cast<std::size_t>(bins), 0.0);
}

std::vector<double> Rdf::edges() const {
  std::vector<double> e(static_cast<std::size_t>(bins_) + 1);
  for (int k = 0; k <= bins_; ++k) e[static_cast<std::size_t>(k)] = r_max_ * k / bins_;
  return e;
}

std::vector<double> Rdf::centers() const {
  const std::vector<double> e = edges();
  std::vector<double> c(static_cast<std::size_t>(bins_));
  for (std::size_t k = 0; k < c.size(); ++k) c[k] = (e[k] + e[k + 1]) / 2;
  return c;
}

std::vector<double> Rdf::g() const {
  std::vector<double> out(static_cast<std::size_t>(bins_));
  for (std::size_t k = 0; k < out.size(); ++k) {
    out[k] = expected_[k] > 0.0 ? static_cast<double>(counts_[k]) / expected_[k] : nan;
  }
  return out;
}

Rdf::Frame Rdf::prepare(const Eigen::MatrixXd& X, const std::optional<Region>& given) const {
  Frame f;
  const int n = static_cast<int>(X.cols());
  f.centre.assign(static_cast<std::size_t>(n), 1);
  if (topology_) {
    // A quotient has no edge: every body is a centre, at density (N - 1) / the domain's volume.
    f.points = X;
    for (int b = 0; b < n; ++b) topology_->reduce(f.points.col(b).data());
    f.centres = n;
    f.volume = topology_->volume();
    return f;
  }
  if (space_.kind == SpaceKind::sphere) {
    f.points = X;
    f.centres = n;
    f.volume = total_volume(space_);
    return f;
  }
  std::optional<Region> region = given;
  if (space_.kind == SpaceKind::hyperbolic && n > 0 && X(X.rows() - 1, 0) / space_.radius > std::cosh(2.0)) {
    // Far out: the bodies (and a given centre) read into a frame at the first body (to_frame,
    // no cancellation), so that distances and the index see a cluster near the origin.
    const sesi::Hyperbolic<Eigen::Dynamic> chart(space_.radius, space_.dim);
    Eigen::MatrixXd frame;
    Eigen::VectorXd point;
    chart.boost_to(Eigen::VectorXd(X.col(0)), frame);
    f.points.resize(X.rows(), n);
    for (int b = 0; b < n; ++b) {
      chart.to_frame(frame, Eigen::VectorXd(X.col(b)), point);
      f.points.col(b) = point;
    }
    if (region) {
      chart.to_frame(frame, Eigen::VectorXd(region->center), point);
      region->center = point;
    }
  } else {
    f.points = X;
  }
  if (!region) region = bounding_region(space_, f.points);
  const int a = static_cast<int>(X.rows());
  f.volume = total_volume(space_, region->radius);
  f.centres = 0;
  for (int b = 0; b < n; ++b) {
    const double d = distance_of(space_, region->center.data(), f.points.col(b).data(), a);
    f.centre[static_cast<std::size_t>(b)] = d <= region->radius - r_max_;
    f.centres += f.centre[static_cast<std::size_t>(b)];
  }
  return f;
}

void Rdf::add(double d) {
  if (!(d < r_max_)) return;
  const auto k = std::min(static_cast<std::size_t>(d / r_max_ * bins_), static_cast<std::size_t>(bins_) - 1);
  ++counts_[k];
}

void Rdf::accumulate(const Eigen::MatrixXd& X, const std::optional<Region>& region) {
  const Frame f = prepare(X, region);
  const int n = static_cast<int>(X.cols());
  const int a = static_cast<int>(X.rows());
  if (topology_ && n >= 2) {
    // The bodies and their ghost images within r_max of the domain (every image that can be
    // within r_max of a body), in one neighbour index of the covering space. Below max_cutoff
    // each pair has at most one image within r_max, its minimum image, so each ordered pair
    // (i, j) is counted once, as accumulate_all_pairs counts it.
    const double reach = r_max_ * (1 + 1e-6);
    std::vector<Eigen::VectorXd> ghosts;
    std::vector<int> origin, near;
    for (int b = 0; b < n; ++b) origin.push_back(b);
    for (int b = 0; b < n; ++b) topology_->add_ghosts(f.points.col(b), b, reach, ghosts, origin, near);
    Eigen::MatrixXd all(a, static_cast<Eigen::Index>(origin.size()));
    all.leftCols(n) = f.points;
    for (std::size_t g = 0; g < ghosts.size(); ++g) all.col(n + static_cast<Eigen::Index>(g)) = ghosts[g];
    NeighbourLists lists;
    std::visit([&](const auto& chart) {
      using Chart = std::remove_cvref_t<decltype(chart)>;
      NeighbourIndex<Chart> index;
      index.build(chart, all, reach, lists);
    }, chart_of(space_));
    for (int i = 0; i < n; ++i) {
      for (int k = lists.begin(i); k < lists.end(i); ++k) {
        const int j = lists.index[static_cast<std::size_t>(k)];
        if (origin[static_cast<std::size_t>(j)] == i) continue;
        add(distance_of(space_, f.points.col(i).data(), all.col(j).data(), a));
      }
    }
  } else if (n >= 2 && f.centres > 0) {
    NeighbourLists lists;
    std::visit(
        [&](const auto& chart) {
          using Chart = std::remove_cvref_t<decltype(chart)>;
          NeighbourIndex<Chart> index;
          // Every pair closer than r_max is a candidate: the index's chord test is exact up to
          // rounding, so its reach is widened by 1e-6 relative and the distance decides.
          index.build(chart, f.points, r_max_ * (1 + 1e-6), lists);
        },
        chart_of(space_));
    for (int i = 0; i < n; ++i) {
      if (!f.centre[static_cast<std::size_t>(i)]) continue;
      for (int k = lists.begin(i); k < lists.end(i); ++k) {
        const int j = lists.index[static_cast<std::size_t>(k)];
        add(distance_of(space_, f.points.col(i).data(), f.points.col(j).data(), a));
      }
    }
  }
  for (int k = 0; k < bins_; ++k) {
    if (n >= 2) expected_[static_cast<std::size_t>(k)] += f.centres * (n - 1.0) * shell_[static_cast<std::size_t>(k)] / f.volume;
  }
  ++frames_;
  centres_ += f.centres;
}

void Rdf::accumulate_all_pairs(const Eigen::MatrixXd& X, const std::optional<Region>& region) {
  const Frame f = prepare(X, region);
  const int n = static_cast<int>(X.cols());
  const int a = static_cast<int>(X.rows());
  Eigen::VectorXd y(a);
  for (int i = 0; i < n; ++i) {
    if (!f.centre[static_cast<std::size_t>(i)]) continue;
    for (int j = 0; j < n; ++j) {
      if (j == i) continue;
      y = f.points.col(j);
      if (topology_) topology_->nearest(f.points.col(i).data(), y.data());  // the minimum image
      add(distance_of(space_, f.points.col(i).data(), y.data(), a));
    }
  }
  for (int k = 0; k < bins_; ++k) {
    if (n >= 2) expected_[static_cast<std::size_t>(k)] += f.centres * (n - 1.0) * shell_[static_cast<std::size_t>(k)] / f.volume;
  }
  ++frames_;
  centres_ += f.centres;
}

// ---- dynamics ----------------------------------------------------------------------------------

namespace {

/// <f(frame o, frame o + lag, body b)> over origins o and bodies b, for each lag; each lag's sum
/// runs in one fixed order (origins, then bodies), so the result does not depend on threads.
template <class F>
Correlation correlate(const Frames& frames, long max_lag, F&& f) {
  Correlation out;
  const long count = static_cast<long>(frames.x.size());
  const int n = frames.bodies();
  if (count == 0) return out;
  if (max_lag < 0) max_lag = count / 2;
  max_lag = std::min(max_lag, count - 1);
  const auto lags = static_cast<std::size_t>(max_lag) + 1;
  out.lag_time.resize(lags);
  out.value.assign(lags, 0.0);
  out.samples.assign(lags, 0);
  out.per_body_last.assign(static_cast<std::size_t>(n), 0.0);
  sesi::parallel::for_each(static_cast<int>(lags), [&](int lag) {
    double sum = 0.0;
    long samples = 0;
    for (long o = 0; o + lag < count; ++o) {
      for (int b = 0; b < n; ++b) {
        const double value = f(o, o + lag, b);
        if (std::isnan(value)) continue;  // S^n transport at exact antipodes
        sum += value;
        ++samples;
      }
    }
    out.lag_time[static_cast<std::size_t>(lag)] = frames.t[static_cast<std::size_t>(lag)] - frames.t.front();
    out.value[static_cast<std::size_t>(lag)] = samples > 0 ? sum / static_cast<double>(samples) : nan;
    out.samples[static_cast<std::size_t>(lag)] = samples;
  });
  for (int b = 0; b < n; ++b) {
    double sum = 0.0;
    long samples = 0;
    for (long o = 0; o + max_lag < count; ++o) {
      const double value = f(o, o + max_lag, b);
      if (std::isnan(value)) continue;
      sum += value;
      ++samples;
    }
    out.per_body_last[static_cast<std::size_t>(b)] = samples > 0 ? sum / static_cast<double>(samples) : nan;
  }
  return out;
}

/// On a quotient: the frames must hold the image counts (box) or words (surface) of every body.
void check_unwrapping(const Frames& frames, const Topology& topology, const std::string& what) {
  const bool box = topology.is_box();
  const std::size_t held = box ? frames.images.size() : frames.words.size();
  if (held != frames.x.size()) {
    throw program::InputError(what + " on a " + (box ? "periodic box needs the image counts" : "compact surface needs the words") +
                              " of every frame (the unwrapped positions)");
  }
  for (std::size_t f = 0; f < held; ++f) {
    const bool fits = box ? frames.images[f].rows() == frames.space.dim && frames.images[f].cols() == frames.bodies()
                          : static_cast<int>(frames.words[f].size()) == frames.bodies();
    if (!fits) throw program::InputError(what + ": frame " + std::to_string(f) + "'s image counts or words do not match its bodies");
  }
}

}  // namespace

Correlation msd(const Frames& frames, long max_lag) {
  const int a = frames.x.empty() ? 0 : static_cast<int>(frames.x.front().rows());
  if (const auto topology = topology_of(frames.space)) {
    // On a quotient the wrapped points jump across the domain: the displacement is that of the
    // unwrapped points, from the image counts or the words.
    check_unwrapping(frames, *topology, "the MSD");
    return correlate(frames, max_lag, [&](long o, long p, int b) {
      return topology->unwrapped_distance2(frames, static_cast<std::size_t>(o), static_cast<std::size_t>(p), b);
    });
  }
  return correlate(frames, max_lag, [&](long o, long p, int b) {
    const double d = distance_of(frames.space, frames.x[static_cast<std::size_t>(o)].col(b).data(),
                                 frames.x[static_cast<std::size_t>(p)].col(b).data(), a);
    return d * d;
  });
}

Correlation vacf(const Frames& frames, long max_lag) {
  if (frames.v.size() != frames.x.size()) {
    throw program::InputError("the velocity autocorrelation needs the velocities (the bodies' masses are unknown)");
  }
  const int a = frames.x.empty() ? 0 : static_cast<int>(frames.x.front().rows());
  const auto topology = topology_of(frames.space);
  if (topology && !topology->is_box()) {
    // On a surface both velocities are carried into the covering space by the words: the later
    // one by the isometry W_o^{-1} W_p that takes its point next to the earlier one's, then by
    // parallel transport along the geodesic between them. (On a box the isometries are
    // translations, which leave velocities alone.)
    check_unwrapping(frames, *topology, "the velocity autocorrelation");
    return correlate(frames, max_lag, [&](long o, long p, int b) {
      const auto so = static_cast<std::size_t>(o), sp = static_cast<std::size_t>(p);
      Topology::Surface::Vector y, w;
      topology->carry(frames, so, sp, b, y, &w);
      return transported_dot_of(frames.space, frames.x[so].col(b).data(), frames.v[so].col(b).data(), y.data(),
                                w.data(), a);
    });
  }
  return correlate(frames, max_lag, [&](long o, long p, int b) {
    const auto so = static_cast<std::size_t>(o), sp = static_cast<std::size_t>(p);
    return transported_dot_of(frames.space, frames.x[so].col(b).data(), frames.v[so].col(b).data(),
                              frames.x[sp].col(b).data(), frames.v[sp].col(b).data(), a);
  });
}

}  // namespace sesi::analysis
