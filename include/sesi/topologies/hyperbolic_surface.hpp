#pragma once
/// @file hyperbolic_surface.hpp
/// Compact hyperbolic surfaces H^2/Gamma of genus g >= 2 (issue #26), after Sausset & Tarjus,
/// "Periodic boundary conditions on the pseudosphere", J. Phys. A 40, 12873 (2007).
///
/// Ambient vectors are (x1, x2, x0), time-like coordinate last (as sesi::Hyperbolic<2>), on the
/// hyperboloid <x,x>_L = x1^2 + x2^2 - x0^2 = -R^2. The fundamental domain D is the regular
/// 4g-gon centred at the chart origin o = (0, 0, R) with interior angles pi/(2g) (4g of them
/// meet at a vertex: the {4g, 4g} tiling). Side k (k = 0..4g-1) has its midpoint in direction
/// angle 2 pi k / (4g); vertex j lies between sides j and j+1, in direction 2 pi (j + 1/2) / (4g).
/// In the right triangle (centre, midpoint, vertex), with angles pi/(4g) at the centre and at the
/// vertex (Ratcliffe, Foundations of Hyperbolic Manifolds, 3.5; Beardon, The Geometry of
/// Discrete Groups, 7.11), in units of R:
///   cosh(inradius) = cot(pi/4g),  cosh(circumradius) = cot^2(pi/4g),  cosh(side/2) = cot(pi/4g).
/// Side k is paired with side k+2g by generator(k), the hyperbolic translation along the axis
/// through the midpoint of side k by twice the inradius: it maps D onto the tile across side k
/// (the reflection in the side composed with the reflection in the symmetry line perpendicular
/// to the axis) and side k+2g onto side k; generator(k+2g) is its inverse. The 4g vertices form
/// one cycle with angle sum 2 pi, so by Poincare's polygon theorem (Beardon 9.8) the generators
/// generate a Fuchsian group Gamma with D as a fundamental domain and H^2/Gamma a closed surface
/// of genus g (Euler characteristic 1 - 2g + 1 = 2 - 2g), area 4 pi (g - 1) R^2.
/// D is the Dirichlet domain of o (each side bisects o and its image across the side), which
/// is why reduce() terminates (Beardon 9.4).

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "sesi/config.hpp"

namespace sesi {

template <class Scalar_>
class HyperbolicSurface {
 public:
  using Scalar = Scalar_;
  using Matrix = Eigen::Matrix<Scalar, 3, 3>;
  using Vector = Eigen::Matrix<Scalar, 3, 1>;
  using Word = std::vector<std::int16_t>;  ///< letters = side indices 0..4g-1, freely reduced
  /// Per body: the group element W_b (a word) with unwrapped point u_b = element(W_b) x_b.
  using Images = std::vector<Word>;

  /// The largest genus accepted. What limits it: images() holds 1 + 4g (4g - 2) ~ 16 g^2 tiles
  /// (3969 at g = 16), each a candidate of nearest_image and of the ghost search; the generators'
  /// entries grow as cot^2(pi/4g) ~ (4g/pi)^2 (415 at g = 16), and world points in D as
  /// cosh(circumradius) = cot^2(pi/4g) times R, so every coordinate of a body carries absolute
  /// rounding ~ eps R cot^2(pi/4g) (about 2.6 of the 16 digits lost at g = 16).
  static constexpr int max_genus = 16;

  /// @param genus g in [2, max_genus]; @param radius R > 0 (else std::invalid_argument).
  HyperbolicSurface(int genus, Scalar radius) : genus_(genus), radius_(radius) {
    if (genus < 2 || genus > max_genus)
      throw std::invalid_argument("hyperbolic surface: genus must be in [2, " + std::to_string(max_genus) + "]");
    if (!(radius > Scalar(0)) || !std::isfinite(static_cast<double>(radius)))
      throw std::invalid_argument("hyperbolic surface: radius must be finite and > 0");
    build();
  }

  int genus() const { return genus_; }
  Scalar radius() const { return radius_; }
  int sides() const { return 4 * genus_; }
  /// The inverse letter: side k is paired with side k + 2g.
  int inverse(int k) const { return (k + 2 * genus_) % sides(); }

  /// generator(k): the translation along the axis through side k's midpoint by 2 inradius;
  /// maps D onto the tile across side k and side k+2g onto side k.
  const Matrix& generator(int k) const { return generators_[static_cast<std::size_t>(k)]; }
  /// The identity first, then every tile sharing a vertex with D (1 + 4g (4g - 2) in all), in a
  /// fixed order: vertex j = 0..4g-1 of D, the tiles around it in the walk's order (build()).
  const std::vector<Matrix>& images() const { return images_; }
  /// The word of images()[k] (element(image_word(k)) == images()[k] up to rounding).
  const Word& image_word(int k) const { return image_words_[static_cast<std::size_t>(k)]; }
  /// The walk around vertex 0 of D: the letters s_1..s_4g with g_{s_1} ... g_{s_4g} = 1, the
  /// defining relation of Gamma (Sausset & Tarjus eq. (3) up to labelling).
  const Word& relation() const { return relation_; }

  /// Lengths in units of R (as are the arguments and results of every method).
  Scalar inradius() const { return radius_ * inradius_; }
  Scalar circumradius() const { return radius_ * circumradius_; }
  Scalar side_length() const { return Scalar(2) * radius_ * inradius_; }  // cosh(side/2) = cot(pi/4g)
  Scalar area() const { return Scalar(4) * std::numbers::pi_v<Scalar> * Scalar(genus_ - 1) * radius_ * radius_; }
  /// The length of the shortest closed geodesic: the least translation length l over the
  /// non-trivial elements of images() and of their pairwise products (tr = 1 + 2 cosh l in
  /// SO(2,1)). Exact when that least value is <= 2 delta (delta below): an element gamma whose
  /// axis meets D (every class has one) with gamma D outside images()^2 moves every point of D
  /// by at least 2 delta (a path from D to gamma D leaves the star of D, then goes from a star
  /// tile M D to gamma D with M^{-1} gamma D outside the star: delta each). Otherwise 2 delta,
  /// a lower bound. (At every genus up to max_genus the least value is found, see the tests.)
  Scalar systole() const { return radius_ * systole_; }
  /// delta: a lower bound (attained) of the distance from D to any tile not in images(): the
  /// distance from D to the boundary of the union of the images() tiles.
  Scalar star_margin() const { return radius_ * delta_; }
  /// The largest pair cutoff r_c = R min(systole / 2, delta): for x, y in D at most one image of y
  /// lies within r_c of x (two would be >= systole apart), and it is one of images() (a tile
  /// within r_c < delta of D is in the star).
  Scalar max_cutoff() const { return radius_ * std::min(systole_ / Scalar(2), delta_); }

  /// 0 inside D (a point on a side, to rounding, is inside: slack()), else the distance from y to D.
  Scalar outside(const Vector& y) const {
    const Vector p = y / radius_;
    if (p[2] <= cosh_in_) return Scalar(0);  // inside the inscribed disc
    bool in = true;
    const Scalar on_side = slack(p);
    for (int k = 0; k < sides() && in; ++k) in = lorentz(p, normals_[static_cast<std::size_t>(k)]) <= on_side;
    if (in) return Scalar(0);
    if (!(p[2] == p[2])) return std::numeric_limits<Scalar>::infinity();
    Scalar d = std::numeric_limits<Scalar>::infinity();
    for (int k = 0; k < sides(); ++k) d = std::min(d, point_side(p, k));
    return radius_ * d;
  }
  /// y <- into D by generators: while y violates some side's half-plane, apply generator(k+2g)
  /// for the side k it violates most (largest <y, n_k>_L; ties to the lower k). Each step
  /// lowers the distance to o (Dirichlet domain), so it terminates; a step that would not lower
  /// y's time coordinate (a point on a side, up to rounding) is not taken: no flip-flop.
  /// `applied` gets the letters applied, in order: y_out = g_{a_m} ... g_{a_1} y_in.
  void reduce(Vector& y, Word& applied) const {
    applied.clear();
    for (int guard = 0; guard < 1 << 20; ++guard) {
      int worst = -1;
      Scalar most = slack(y);  // a point on a side (to rounding) is inside
      for (int k = 0; k < sides(); ++k) {
        const Scalar v = lorentz(y, normals_[static_cast<std::size_t>(k)]);
        if (v > most) {
          most = v;
          worst = k;
        }
      }
      if (worst < 0) return;  // inside (or NaN: left to the finiteness checks)
      const int letter = inverse(worst);
      const Vector z = generator(letter) * y;
      if (!(z[2] < y[2])) return;
      y = z;
      applied.push_back(static_cast<std::int16_t>(letter));
    }
  }
  /// y <- images()[k] y for the k with the least chord to x (largest <x, images()[k] y>_L; ties
  /// to the lower k). Returns k. The minimum image when d(x, y's nearest image) < max_cutoff().
  int nearest_image(const Vector& x, Vector& y) const {
    const Vector w(x[0], x[1], -x[2]);  // <x, z>_L = w . z
    int best = 0;
    Scalar most = -std::numeric_limits<Scalar>::infinity();
    Vector best_z = y;
    for (std::size_t k = 0; k < images_.size(); ++k) {
      const Vector z = images_[k] * y;
      const Scalar v = w.dot(z);
      if (v > most) {
        most = v;
        best = static_cast<int>(k);
        best_z = z;
      }
    }
    y = best_z;
    return best;
  }
  void apply(int k, Vector& y) const { y = (images_[static_cast<std::size_t>(k)] * y).eval(); }
  /// The product of the word's generators, left to right: g_{w_0} g_{w_1} ... .
  Matrix element(const Word& w) const {
    Matrix m = Matrix::Identity();
    for (const auto l : w) m = (m * generator(l)).eval();
    return m;
  }
  Images identity_images(int bodies) const { return Images(static_cast<std::size_t>(bodies)); }
  /// The word of W gamma^{-1} for gamma = g_{a_m} ... g_{a_1} (`applied` = a_1..a_m, as reduce()
  /// gives it): appends the inverse letters of a_1, ..., a_m in that order, cancelling a letter
  /// next to its inverse, so that W stays freely reduced and W_b x_b is unchanged by a wrap.
  void append_inverse(Word& w, const Word& applied) const {
    for (const auto a : applied) {
      const auto inv = static_cast<std::int16_t>(inverse(a));
      if (!w.empty() && w.back() == a) {
        w.pop_back();  // ... g_a g_a^{-1}: cancels
      } else {
        w.push_back(inv);
      }
    }
  }
  /// Appends to out every k such that images()[k] y lies within `reach` of D (ghost images for
  /// neighbour search). A cheap test first: a point within reach of D is within circumradius +
  /// reach of o, i.e. its time coordinate is at most R cosh(circumradius/R + reach/R).
  void images_near(const Vector& y, Scalar reach, std::vector<int>& out) const {
    using std::cosh;
    const Scalar cap = radius_ * cosh(circumradius_ + reach / radius_);
    for (std::size_t k = 0; k < images_.size(); ++k) {
      const Vector z = images_[k] * y;
      if (z[2] > cap) continue;
      if (outside(z) <= reach) out.push_back(static_cast<int>(k));
    }
  }

  /// Whether some body's world point lies outside D by more than margin: wrap()'s trigger, and
  /// a run across ranks' test of its own bodies (the whole run's wrap is then any rank's call).
  template <class Chart, class StateT>
  bool out_by_more(const Chart& chart, const StateT& s, Scalar margin) const {
    SESI_CHECK(!s.clustered, "a hyperbolic surface never uses a cluster frame");
    Vector y;
    for (int b = 0; b < s.bodies(); ++b) {
      if (within(s, b, margin)) continue;
      world(chart, s, b, y);
      if (outside(y) > margin) return true;
    }
    return false;
  }

  /// wrap() for a surface (topology.hpp): F_b <- gamma F_b for every body outside D once one is
  /// outside by more than margin; the frame is then made Lorentz again (orthonormalise), so
  /// that rounding does not accumulate over many wraps.
  template <class Chart, class StateT>
  int wrap(const Chart& chart, StateT& s, Images& images, Scalar margin) const {
    SESI_CHECK(static_cast<int>(images.size()) == s.bodies(), "wrap: one word per body");
    if (!out_by_more(chart, s, margin)) return 0;
    if (!s.framed()) s.enable_frames(3);
    int moved = 0;
    Vector y;
    Word applied;
    for (int b = 0; b < s.bodies(); ++b) {
      if (within(s, b, Scalar(0))) continue;  // inside the inscribed disc: inside D
      world(chart, s, b, y);
      reduce(y, applied);
      if (applied.empty()) continue;
      Matrix gamma = Matrix::Identity();
      for (const auto a : applied) gamma = (generator(a) * gamma).eval();
      auto& f = s.frames[static_cast<std::size_t>(b)];
      f = (gamma * f).eval();
      orthonormalise(f);
      append_inverse(images[static_cast<std::size_t>(b)], applied);
      ++moved;
    }
    return moved;
  }

  /// Makes a frame exactly Lorentz again (to relative rounding of its entries), keeping its
  /// point F o and its orientation: F = B(y) diag(Q, 1) with y = F o normalised onto the
  /// hyperboloid (y_t = sqrt(1 + |y_s|^2)), B(y) the standard boost to y (as Hyperbolic::home)
  /// and Q the rotation (or reflection) read from F's spatial columns in the rest frame of y,
  /// a = w_s - y_s w_t / (1 + y_t), then normalised. Unlike Gram-Schmidt in the Lorentz metric,
  /// whose normalisations cancel terms of size |F|^2 (errors ~ eps |F|^3), this loses only
  /// ~ eps |F| in Q's angle, and the rebuilt F's defect |F^T eta F - eta| does not accumulate over
  /// wraps (a product gamma F alone adds ~ eps |gamma| |F|^2 to it at every wrap).
  static void orthonormalise(Matrix& f) {
    using std::sqrt;
    using Vec2 = Eigen::Matrix<Scalar, 2, 1>;
    const Vec2 ys = f.template block<2, 1>(0, 2);
    const Scalar yt = sqrt(Scalar(1) + ys.squaredNorm()), k = Scalar(1) / (Scalar(1) + yt);
    auto rest = [&](int c) { return Vec2(f.template block<2, 1>(0, c) - ys * (f(2, c) * k)); };
    Vec2 a = rest(0);
    const Vec2 b = rest(1);
    a /= a.norm();
    Vec2 a_perp(-a[1], a[0]);
    if (a[0] * b[1] - a[1] * b[0] < Scalar(0)) a_perp = -a_perp;  // keep an improper frame improper
    auto lift = [&](const Vec2& c, int col) {  // B(y) (c, 0)
      const Scalar yc = ys.dot(c);
      f.template block<2, 1>(0, col) = c + ys * (yc * k);
      f(2, col) = yc;
    };
    lift(a, 0);
    lift(a_perp, 1);
    f.template block<2, 1>(0, 2) = ys;
    f(2, 2) = yt;
  }
  /// How far <y, n_k>_L may exceed 0 by rounding alone for a point on side k that a generator
  /// put there (a wrap): g y rounds by <= (gamma_3 + 2 * 10 eps) |g|_F |y| (gamma_3 < 4 eps for
  /// the product; the generator's and the normal's entries, built from cot(pi/4g), carry <= 10 eps
  /// relative each), with |g|_F <= 2 sqrt(3) cot^2, |y| <= sqrt(2) y_t and |n_k| <= sqrt(2) cot:
  /// 24 * 2 * 1.74 * 1.42 < 128 eps cot^3 y_t. Within it a point counts as inside (no flip-flop).
  Scalar slack(const Vector& y) const {
    using std::abs;
    return Scalar(128) * std::numeric_limits<Scalar>::epsilon() * cot_ * cot_ * cot_ * abs(y[2]);
  }
  /// <x, y>_L = x1 y1 + x2 y2 - x0 y0.
  static Scalar lorentz(const Vector& x, const Vector& y) { return x[0] * y[0] + x[1] * y[1] - x[2] * y[2]; }

  /// Vertex j of D and the unit outward normal of side k, on the unit hyperboloid.
  const Vector& vertex(int j) const { return vertices_[static_cast<std::size_t>(j)]; }
  const Vector& normal(int k) const { return normals_[static_cast<std::size_t>(k)]; }

 private:
  /// Body b's world point y = F_b embed(q_b) (no frame: embed(q_b)).
  template <class Chart, class StateT>
  static void world(const Chart& chart, const StateT& s, int b, Vector& y) {
    typename Chart::Point q = s.q.col(b);
    Vector x;
    chart.embed(q, x);
    if (s.framed()) {
      y.noalias() = s.frames[static_cast<std::size_t>(b)] * x;
    } else {
      y = x;
    }
  }
  /// Whether body b is surely within m of D: within inradius + m of o (D holds the inscribed
  /// disc). A cheap test on y_t = R cosh q_1 (no frame) or its bound R (|F_20, F_21| sinh q_1 +
  /// F_22 cosh q_1) (y = F embed(q)), with a few eps of room for rounding.
  template <class StateT>
  bool within(const StateT& s, int b, Scalar m) const {
    using std::abs;
    using std::cosh;
    using std::exp;
    using std::hypot;
    const Scalar q1 = abs(s.q(0, b)), reach = inradius_ + m / radius_;
    if (!s.framed()) return q1 <= reach;
    const auto& f = s.frames[static_cast<std::size_t>(b)];
    const Scalar e = exp(q1), ch = (e + Scalar(1) / e) / Scalar(2), sh = (e - Scalar(1) / e) / Scalar(2);
    return hypot(f(2, 0), f(2, 1)) * sh + f(2, 2) * ch <=
           cosh(reach) * (Scalar(1) - Scalar(64) * std::numeric_limits<Scalar>::epsilon());
  }
  int genus_;
  Scalar radius_;
  Scalar cot_{}, cosh_in_{}, inradius_{}, circumradius_{}, systole_{}, delta_{};
  std::vector<Matrix> generators_;
  std::vector<Vector> normals_, vertices_, midpoints_;
  std::vector<Matrix> images_;
  std::vector<Word> image_words_;
  Word relation_;

  static Scalar acosh1(Scalar c) {
    using std::acosh;
    return acosh(std::max(c, Scalar(1)));
  }
  /// eta (u x v): Lorentz-orthogonal to u and v.
  static Vector cross(const Vector& u, const Vector& v) {
    return Vector(u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], -(u[0] * v[1] - u[1] * v[0]));
  }
  /// Whether f (on the line through a and b, in the future cone) is on the segment [a, b]:
  /// f = alpha a + beta b with alpha, beta >= 0 (Gram system of <., a> and <., b>).
  static bool on_segment(const Vector& f, const Vector& a, const Vector& b) {
    const Scalar c = lorentz(a, b), fa = lorentz(f, a), fb = lorentz(f, b);
    return fa + c * fb >= Scalar(0) && fb + c * fa >= Scalar(0);
  }
  /// Unit-hyperboloid distance from p to the segment [a, b] (unit normal n of its line).
  static Scalar point_segment(const Vector& p, const Vector& a, const Vector& b, const Vector& n) {
    using std::abs;
    using std::asinh;
    const Scalar s = lorentz(p, n);
    const Vector f = p - s * n;  // the foot, up to normalisation
    if (on_segment(f, a, b)) return asinh(abs(s));
    return std::min(chord_distance(p, a), chord_distance(p, b));
  }
  /// d(p, a) from the chord, <p - a, p - a>_L = 4 sinh^2(d/2): accurate near 0, where acosh of
  /// -<p, a>_L = cosh d loses half the digits.
  static Scalar chord_distance(const Vector& p, const Vector& a) {
    using std::asinh;
    using std::sqrt;
    const Vector d = p - a;
    return Scalar(2) * asinh(sqrt(std::max(Scalar(0), lorentz(d, d))) / Scalar(2));
  }
  Scalar point_side(const Vector& p, int k) const {
    const int prev = (k + sides() - 1) % sides();
    return point_segment(p, vertices_[static_cast<std::size_t>(prev)], vertices_[static_cast<std::size_t>(k)],
                         normals_[static_cast<std::size_t>(k)]);
  }
  static Vector unit_normal(const Vector& a, const Vector& b) {
    using std::sqrt;
    Vector n = cross(a, b);
    return n / sqrt(lorentz(n, n));
  }
  /// Distance between the segments [a0, a1] and [b0, b1] that do not meet (unit hyperboloid):
  /// the distance is jointly convex along the two segments (H^2 is CAT(-1)), so its least
  /// value is at an endpoint of one of them or at a common perpendicular with both feet inside.
  static Scalar segment_segment(const Vector& a0, const Vector& a1, const Vector& b0, const Vector& b1) {
    using std::abs;
    using std::sqrt;
    const Vector na = unit_normal(a0, a1), nb = unit_normal(b0, b1);
    Scalar d = std::min({point_segment(a0, b0, b1, nb), point_segment(a1, b0, b1, nb),
                         point_segment(b0, a0, a1, na), point_segment(b1, a0, a1, na)});
    if (abs(lorentz(na, nb)) > Scalar(1)) {  // ultraparallel lines: a common perpendicular
      const Vector m = cross(na, nb);
      Vector fa = cross(na, m), fb = cross(nb, m);
      if (fa[2] < Scalar(0)) fa = -fa;
      if (fb[2] < Scalar(0)) fb = -fb;
      fa /= sqrt(-lorentz(fa, fa));
      fb /= sqrt(-lorentz(fb, fb));
      if (on_segment(fa, a0, a1) && on_segment(fb, b0, b1)) d = std::min(d, acosh1(-lorentz(fa, fb)));
    }
    return d;
  }

  void build() {
    using std::cos;
    using std::sin;
    using std::sqrt;
    using std::tan;
    const int n = sides(), half = 2 * genus_;
    const Scalar pi = std::numbers::pi_v<Scalar>;
    cot_ = Scalar(1) / tan(pi / Scalar(n));
    cosh_in_ = cot_;
    const Scalar sinh_in = sqrt((cot_ - Scalar(1)) * (cot_ + Scalar(1)));
    const Scalar cosh_circ = cot_ * cot_, sinh_circ = sqrt((cosh_circ - Scalar(1)) * (cosh_circ + Scalar(1)));
    inradius_ = acosh1(cosh_in_);
    circumradius_ = acosh1(cosh_circ);
    // cosh 2 rho = 2 cot^2 - 1, sinh 2 rho = 2 cot sinh rho.
    const Scalar ch2 = Scalar(2) * cosh_circ - Scalar(1), sh2 = Scalar(2) * cot_ * sinh_in;
    generators_.assign(static_cast<std::size_t>(n), Matrix::Identity());
    normals_.assign(static_cast<std::size_t>(n), Vector::Zero());
    midpoints_.assign(static_cast<std::size_t>(n), Vector::Zero());
    vertices_.assign(static_cast<std::size_t>(n), Vector::Zero());
    // Directions of sides k < 2g; side k + 2g has exactly the opposite one, so that
    // generator(k + 2g) is exactly generator(k)'s Lorentz inverse.
    for (int k = 0; k < half; ++k) {
      const Scalar th = Scalar(2) * pi * Scalar(k) / Scalar(n);
      const Scalar ph = Scalar(2) * pi * (Scalar(k) + Scalar(0.5)) / Scalar(n);
      for (int sgn = 0; sgn < 2; ++sgn) {
        const Scalar e0 = sgn ? -cos(th) : cos(th), e1 = sgn ? -sin(th) : sin(th);
        const Scalar v0 = sgn ? -cos(ph) : cos(ph), v1 = sgn ? -sin(ph) : sin(ph);
        const auto idx = static_cast<std::size_t>(k + sgn * half);
        Matrix& g = generators_[idx];
        g(0, 0) = Scalar(1) + (ch2 - Scalar(1)) * e0 * e0;
        g(0, 1) = (ch2 - Scalar(1)) * e0 * e1;
        g(1, 0) = g(0, 1);
        g(1, 1) = Scalar(1) + (ch2 - Scalar(1)) * e1 * e1;
        g(0, 2) = g(2, 0) = sh2 * e0;
        g(1, 2) = g(2, 1) = sh2 * e1;
        g(2, 2) = ch2;
        normals_[idx] = Vector(cosh_in_ * e0, cosh_in_ * e1, sinh_in);
        midpoints_[idx] = Vector(sinh_in * e0, sinh_in * e1, cosh_in_);
        vertices_[idx] = Vector(sinh_circ * v0, sinh_circ * v1, cosh_circ);
      }
    }
    build_images();
    build_margin();
    build_systole();
  }

  /// Walks around each vertex of D through the 4g tiles that meet there. At tile M D with the
  /// vertex at M v_i, crossing side s leads to M g_s D, entered through its side s + 2g; g_s maps
  /// v_{s+2g-1} to v_s and v_{s+2g} to v_{s-1} (a translation keeps the side of its axis), so the
  /// walk that always crosses side i+1 enters at vertex s + 2g and crosses s + 2g + 1 next.
  /// The element after m steps, gamma_m = g_{s_1} ... g_{s_m}, maps vertex i_m of D to v_j, so
  /// gamma_m Rot_o(beta_m), beta_m = 2 pi (i_m - j) / 4g, fixes v_j: it is the rotation about v_j
  /// by m steps of 2 pi / 4g (the tiles' angle there). gamma_m is computed in that closed form,
  /// two products of O(cot^4) entries, not as the product of m generators, whose rounding grows
  /// with m (1e-5 at g = 8); the direction of the rotation is the one that gives g_{s_1} at m = 1.
  /// Each tile's word is the walk's first m letters, or for m > 2g the relation run backwards.
  void build_images() {
    using std::cos;
    using std::sin;
    const int n = sides(), half = 2 * genus_;
    const Scalar step = Scalar(2) * std::numbers::pi_v<Scalar> / Scalar(n);
    images_.assign(1, Matrix::Identity());
    image_words_.assign(1, Word{});
    std::vector<Vector> centres(1, Vector(0, 0, 1));
    auto rotation = [](Scalar a) {
      Matrix r = Matrix::Identity();
      r(0, 0) = r(1, 1) = cos(a);
      r(1, 0) = sin(a);
      r(0, 1) = -r(1, 0);
      return r;
    };
    for (int j = 0; j < n; ++j) {
      // B: the boost o -> v_j; rotations about v_j are B Rot_o(alpha) B^{-1}, B^{-1} = eta B^T eta.
      const Vector& v = vertices_[static_cast<std::size_t>(j)];
      Matrix boost = Matrix::Identity();
      const Eigen::Matrix<Scalar, 2, 1> vs = v.template head<2>();
      boost.template topLeftCorner<2, 2>() += vs * vs.transpose() / (Scalar(1) + v[2]);
      boost.template topRightCorner<2, 1>() = v.template head<2>();
      boost.template bottomLeftCorner<1, 2>() = v.template head<2>().transpose();
      boost(2, 2) = v[2];
      Matrix unboost = boost;
      unboost.template topRightCorner<2, 1>() *= Scalar(-1);
      unboost.template bottomLeftCorner<1, 2>() *= Scalar(-1);
      Word walk;
      std::vector<int> vertex_index(1, j);
      int i = j;
      for (int m = 0; m < n; ++m) {
        const int s = (i + 1) % n;
        walk.push_back(static_cast<std::int16_t>(s));
        i = (s + half) % n;
        vertex_index.push_back(i);
      }
      if (j == 0) relation_ = walk;
      auto tile = [&](int m, Scalar sense) {
        const int turn = ((vertex_index[static_cast<std::size_t>(m)] - j) % n + n) % n;
        return Matrix(boost * rotation(sense * step * Scalar(m)) * unboost * rotation(-step * Scalar(turn)));
      };
      const Matrix& first = generator(walk[0]);
      const Scalar sense = (tile(1, Scalar(1)) - first).cwiseAbs().maxCoeff() <=
                                   (tile(1, Scalar(-1)) - first).cwiseAbs().maxCoeff()
                               ? Scalar(1)
                               : Scalar(-1);
      SESI_CHECK((tile(1, sense) - first).cwiseAbs().maxCoeff() <= Scalar(1e-6) * first.cwiseAbs().maxCoeff(),
                 "hyperbolic surface: the walk around a vertex does not start with its generator");
      for (int m = 1; m < n; ++m) {
        Word w;
        if (m <= n / 2) {
          w.assign(walk.begin(), walk.begin() + m);
        } else {
          for (int r = n - 1; r >= m; --r)
            w.push_back(static_cast<std::int16_t>(inverse(walk[static_cast<std::size_t>(r)])));
        }
        const Matrix e = tile(m, sense);
        const Vector c = e.col(2);
        bool seen = false;
        // Distinct tiles have centres >= 2 inradius apart (cosh >= 2 cot^2 - 1 >= 10.6): 2 separates them.
        for (const auto& o : centres) seen = seen || -lorentz(c, o) < Scalar(2);
        if (seen) continue;
        images_.push_back(e);
        image_words_.push_back(w);
        centres.push_back(c);
      }
    }
  }

  /// delta = the distance from D to the boundary of the union U of the images() tiles: the
  /// sides of U's tiles whose neighbour across the side is not in U. A tile is found by its
  /// centre, among U's sorted by time coordinate.
  void build_margin() {
    const int n = sides();
    std::vector<std::pair<Scalar, int>> by_time;
    for (std::size_t k = 0; k < images_.size(); ++k) by_time.emplace_back(images_[k](2, 2), static_cast<int>(k));
    std::sort(by_time.begin(), by_time.end());
    auto in_star = [&](const Vector& c) {
      // centres of distinct tiles: cosh of their distance >= 10.6; the same tile: ~1. Time
      // coordinates of the same tile agree to rounding: search a window of relative 1e-6.
      const Scalar lo = c[2] * (Scalar(1) - Scalar(1e-6)), hi = c[2] * (Scalar(1) + Scalar(1e-6));
      auto it = std::lower_bound(by_time.begin(), by_time.end(), std::make_pair(lo, -1));
      for (; it != by_time.end() && it->first <= hi; ++it) {
        if (-lorentz(c, images_[static_cast<std::size_t>(it->second)].col(2)) < Scalar(2)) return true;
      }
      return false;
    };
    Scalar best = std::numeric_limits<Scalar>::infinity();
    const Vector origin(0, 0, 1);
    for (const auto& m : images_) {
      for (int s = 0; s < n; ++s) {
        const Matrix neighbour = m * generator(s);
        if (in_star(neighbour.col(2))) continue;
        const int prev = (s + n - 1) % n;
        const Vector a = m * vertices_[static_cast<std::size_t>(prev)], b = m * vertices_[static_cast<std::size_t>(s)];
        // d(D, edge) >= d(o, edge) - circumradius: skip edges that cannot beat the best.
        if (point_segment(origin, a, b, m * normals_[static_cast<std::size_t>(s)]) - circumradius_ >= best) continue;
        for (int k = 0; k < n; ++k) {
          const Vector& c0 = vertices_[static_cast<std::size_t>((k + n - 1) % n)];
          best = std::min(best, segment_segment(c0, vertices_[static_cast<std::size_t>(k)], a, b));
        }
      }
    }
    delta_ = best;
  }

  /// The least translation length over images() and their pairwise products (see systole()).
  void build_systole() {
    // tr = 1 + 2 cosh l for a hyperbolic element of SO(2,1).
    Scalar least = std::numeric_limits<Scalar>::infinity();
    // An element is the identity iff it maps o to o (Gamma acts freely); other elements move o
    // by >= 2 inradius (cosh >= 10.6), so -<gamma o, o>_L < 2 tells the identity at any rounding.
    for (std::size_t a = 1; a < images_.size(); ++a) {
      least = std::min(least, (images_[a].trace() - Scalar(1)) / Scalar(2));
      for (std::size_t b = 1; b < images_.size(); ++b) {
        const Matrix& ma = images_[a];
        const Matrix& mb = images_[b];
        if (ma.row(2).dot(mb.col(2)) < Scalar(2)) continue;  // (M_a M_b o)_time = cosh d(o, M_a M_b o)
        Scalar tr(0);
        for (int r = 0; r < 3; ++r) tr += ma.row(r).dot(mb.col(r));
        least = std::min(least, (tr - Scalar(1)) / Scalar(2));
      }
    }
    systole_ = std::min(acosh1(least), Scalar(2) * delta_);
  }
};

}  // namespace sesi
