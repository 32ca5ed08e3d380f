#pragma once
/// @file neighbours.hpp
/// Which bodies are near which: the neighbour index behind short-range pair terms (a term with
/// a range, potentials.hpp), so that a force evaluation costs O(N) instead of O(N^2).
///
/// The exact test is always the chord in the ambient metric, which is monotone in the geodesic
/// distance on S^n (2R sin(d/2R)), H^n (the Minkowski chord 2R sinh(d/2R)) and E^n, so a
/// distance cutoff is a chord cutoff with no approximation. Cells only propose candidates:
///  - S^n and E^n: cubic cells of the ambient space, of side the chord reach (a chord is the
///    Euclidean distance of the embedding points there), searched in the 3^a cells around;
///  - H^n: a binary-tiling-like grid in upper half-space coordinates (w, y) (Beardon, "The
///    Geometry of Discrete Groups", sec. 7.1; the metric R |d(w,y)| / y): bands of hyperbolic
///    height h in log y, each cut into boxes of hyperbolic width <= h. Every cell has a bounded
///    hyperbolic size wherever it is, so a cluster of fixed density costs O(N) at any distance
///    from the chart's origin. The half-space's boundary point is put opposite the bodies'
///    centroid, so that the coordinates of the bodies are computed without cancellation.
///
/// A build sorts the bodies by cell (a radix sort of the cells' numbers in the keys' bounding box),
/// copies the points in that order, coordinate by coordinate, and finds rows cell by cell: a
/// body's candidates are then a few contiguous runs of that copy (one per row of cells of its
/// query box, shared by the bodies of a cell off H^n), whose chords are formed in short loops of
/// fixed length that the compiler vectorises (Allen & Tildesley, 2nd ed., sec. 5.3.2, and LAMMPS'
/// binned lists, which sort atoms by bin likewise). The order is exposed (visit_order) for loops
/// that want to visit rows in it. Buffers keep their capacity between builds, so a rebuild of a
/// list whose size changes little allocates nothing.
///
/// Lists are full (i sees j and j sees i) and sorted by body index, so a row's sum over its
/// neighbours does not depend on how the index was built or when it was last rebuilt: forces
/// from the index equal those of the all-pairs loop with the same kernel to the bit.
///
/// VerletList keeps a list with a skin (Verlet 1967; Allen & Tildesley, 2nd ed., sec. 5.3):
/// pairs within range + skin, rebuilt only when some body has moved more than skin / 2 since the
/// last build (two bodies then moved at most skin together, so no pair entered the range unseen).
///
/// On a quotient (a chart with a topology, topology.hpp) the partners are images (Allen &
/// Tildesley, 2nd ed., secs. 1.6.2 and 5.3.2; Sausset & Tarjus, J. Phys. A 40, 12873 (2007)):
///  - a periodic box (a topology with edges()): periodic cells, floor(L_k / reach) per axis (so a
///    cell's side is at least the reach), keys taken modulo that count, the chord measured on the
///    minimum image. An axis with fewer than 3 cells is searched whole. The lists hold partner
///    indices only (System takes the minimum image again), and the Verlet test measures each
///    body's minimum-image displacement, so bringing a body back into the box rebuilds nothing.
///  - a compact hyperbolic surface (a topology with images()): ghost images. Every body j close
///    enough to a side of the domain D gets ghosts images()[k] x_j (k != 0) that lie within
///    reach + s of D (and a few more), s the farthest any body lies outside D at the build (a
///    partner within reach of a body i is within reach + s of D; it lies in a tile of images()
///    while reach + s stays below HyperbolicSurface::star_margin()); the H^n index runs over the
///    bodies and their ghosts, and the lists of the real bodies hold pairs (j, k), sorted by
///    (j, k), in `index` and `image`. A body's own images are left out: a pair cutoff is below half the systole
///    (HyperbolicSurface::max_cutoff), so they are never within range. A body brought back into D
///    moves its world point, and the list rebuilds.

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <limits>
#include <type_traits>
#include <utility>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "sesi/config.hpp"
#include "sesi/parallel.hpp"
#include "sesi/profile.hpp"

namespace sesi {

/// Charts whose ambient chord the neighbour index understands (Sphere, Hyperbolic, Euclidean).
template <class C>
concept HasChordMetric = requires(const C& c, typename C::Scalar d) {
  { c.chord_of_distance(d) } -> std::convertible_to<typename C::Scalar>;
  { c.curvature() } -> std::convertible_to<typename C::Scalar>;
};

namespace detail {
/// A chart with a topology (topology.hpp's HasTopology, stated here so that this header does not
/// need that one).
template <class C>
concept QuotientChart = requires(const C& c) { c.topology(); };
/// A quotient by a periodic box: the neighbour index uses periodic cells (PeriodicBox).
template <class C>
concept PeriodicCells = requires(const C& c) { c.topology().edges(); };
/// A quotient whose images are found near the domain: the neighbour index adds ghost images
/// (HyperbolicSurface).
template <class C>
concept GhostImages = requires(const C& c, const typename C::Topology::Vector& x, typename C::Topology::Vector& y) {
  c.topology().images();
  c.topology().apply(0, y);
  c.topology().normal(0);
  c.topology().outside(x);
};
/// A vector the topology's minimum image writes (unused elsewhere).
template <class C>
struct ImageVector {
  using type = Eigen::Matrix<typename C::Scalar, Eigen::Dynamic, 1>;
};
template <PeriodicCells C>
struct ImageVector<C> {
  using type = typename C::Topology::Vector;
};
}  // namespace detail

/// Full neighbour lists in compressed rows: the neighbours of body i are
/// index[offset[i] .. offset[i+1]), ascending. On a compact hyperbolic surface, image[k] is the
/// image (HyperbolicSurface::images() index) of partner index[k] that is near body i, and the
/// row is ascending in (index, image); elsewhere image is empty.
struct NeighbourLists {
  std::vector<int> offset;
  std::vector<int> index;
  std::vector<int> image;
  /// The bodies sorted by the cell of the index that holds them (a permutation of 0 .. bodies()-1,
  /// ties by index): a loop over rows in this order visits neighbours in nearby memory.
  std::vector<int> visit_order;

  int bodies() const { return offset.empty() ? 0 : static_cast<int>(offset.size()) - 1; }
  int begin(int i) const { return offset[static_cast<std::size_t>(i)]; }
  int end(int i) const { return offset[static_cast<std::size_t>(i) + 1]; }
  /// Unordered pairs held (each is listed twice).
  long pairs() const { return static_cast<long>(index.size()) / 2; }
};

/// The neighbour index of one chart type.
template <class Chart>
class NeighbourIndex {
 public:
  using Scalar = typename Chart::Scalar;
  using Points = Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic>;

  /// Lists of all pairs with geodesic distance < reach among the columns of X (world points,
  /// ambient x bodies); on a quotient, of all pairs of images within reach (the file's notes).
  template <class Matrix>
  void build(const Chart& chart, const Matrix& X, Scalar reach, NeighbourLists& out) {
    if constexpr (detail::GhostImages<Chart>) {
      build_with_ghosts(chart, X, reach, out);
    } else {
      build_rows(chart, X, static_cast<int>(X.cols()), reach, out);
      out.image.clear();
    }
  }

  /// The squared chord of bodies i and j in the ambient metric (on a periodic box, of the
  /// minimum image: y is scratch for it).
  template <class Matrix>
  static Scalar chord2_of(const Chart& chart, const Matrix& X, int i, int j,
                          typename detail::ImageVector<Chart>::type& y) {
    if constexpr (detail::PeriodicCells<Chart>) {
      y = X.col(j);
      chart.topology().nearest_image(X.col(i), y);
      return (X.col(i) - y).squaredNorm();
    } else {
      static_cast<void>(y);
      return chord2_of(chart, X, i, j);
    }
  }
  /// The squared chord of columns i and j in the ambient metric (no image taken).
  template <class Matrix>
  static Scalar chord2_of(const Chart& chart, const Matrix& X, int i, int j) {
    Scalar c2(0);
    const int a = static_cast<int>(X.rows());
    for (int k = 0; k < a; ++k) {
      const Scalar u = X(k, i) - X(k, j);
      c2 += u * u;
    }
    if (chart.curvature() < Scalar(0)) {  // Minkowski: the last coordinate is time-like
      const Scalar u = X(a - 1, i) - X(a - 1, j);
      c2 -= Scalar(2) * u * u;
    }
    return c2;
  }

 private:
  /// A box of cells: key coordinate k runs over [lo[k], hi[k]].
  struct Box {
    std::vector<std::int64_t> lo, hi;
  };

  /// The lists of the first `rows` columns of X against all its columns (build; the ghosts'
  /// rows are not needed).
  ///
  /// Rows are found in cell order (order_, the bodies sorted by cell), against a copy of the
  /// points in that order (packed_), so that a body's candidates are a few contiguous runs of
  /// memory (one per row of cells in its query box), shared by all the bodies of its cell off
  /// H^n (where the query box is the cell's). The chord is computed from the same numbers in the
  /// same order as chord2_of, so the lists are those of a body-by-body scan, bit for bit.
  template <class Matrix>
  void build_rows(const Chart& chart, const Matrix& X, int rows, Scalar reach, NeighbourLists& out) {
    const int total = static_cast<int>(X.cols());
    const int a = static_cast<int>(X.rows());
    const Scalar chord = chart.chord_of_distance(reach);
    const Scalar chord2 = chord * chord;
    bin(chart, X, reach, chord);
    if constexpr (!detail::PeriodicCells<Chart>) {
      const std::size_t stride = static_cast<std::size_t>(total) + static_cast<std::size_t>(pad);
      packed_.resize(stride * static_cast<std::size_t>(a));
      parallel::for_each(total, [&](int s) {
        const int j = order_[static_cast<std::size_t>(s)];
        for (int k = 0; k < a; ++k) packed_[static_cast<std::size_t>(k) * stride + static_cast<std::size_t>(s)] = X(k, j);
      });
      for (int k = 0; k < a; ++k) {  // the padding: chords formed there are never kept
        std::fill_n(packed_.begin() + static_cast<std::ptrdiff_t>(static_cast<std::size_t>(k) * stride + static_cast<std::size_t>(total)), pad, Scalar(0));
      }
    }
    const int chunks = parallel::chunks_for(total);
    if (scratch_.size() < static_cast<std::size_t>(chunks)) scratch_.resize(static_cast<std::size_t>(chunks));
    slot_start_.resize(static_cast<std::size_t>(total));
    out.offset.resize(static_cast<std::size_t>(rows) + 1);  // each row's count is written below
    out.offset[0] = 0;
    const bool minkowski = chart.curvature() < Scalar(0);
    parallel::for_chunks(total, chunks, [&](int begin, int end, int c) {
      Scratch& w = scratch_[static_cast<std::size_t>(c)];
      // Capacity for a quarter more than the last build found, grown to twice that when short,
      // so that a build allocates only when a chunk's rows grow by half (not per rebuild).
      const std::size_t want = w.buf.size() + w.buf.size() / 4;
      w.buf.clear();
      if (w.buf.capacity() < want) w.buf.reserve(2 * want);
      w.key.resize(static_cast<std::size_t>(keys_));
      // The minimum image's scratch, on a periodic box only (elsewhere a dynamic-size vector
      // would be an allocation per build).
      using Image = std::conditional_t<detail::PeriodicCells<Chart>, typename detail::ImageVector<Chart>::type, int>;
      Image y(a);
      static_cast<void>(y);
      // The cell of slot `begin`: the last cell starting at or before it.
      int cell = static_cast<int>(std::upper_bound(cell_start_.begin(), cell_start_.end(), begin) - cell_start_.begin()) - 1;
      int spans_of = -1;  // the cell whose query box w.spans holds (off H^n)
      for (int s = begin; s < end; ++s) {
        while (cell_start_[static_cast<std::size_t>(cell) + 1] <= s) ++cell;
        const int i = order_[static_cast<std::size_t>(s)];
        if (i >= rows) continue;  // a ghost: no row of its own
        if (chart.curvature() < Scalar(0) || spans_of != cell) {
          query_boxes(chart, X, i, reach, w.boxes);
          w.spans.clear();
          int row = 0;
          for (const Box& box : w.boxes) {
            for_rows_in(box, w.key, w.hints, row, [&](int s0, int s1) { w.spans.emplace_back(s0, s1); });
          }
          spans_of = cell;
        }
        const std::size_t first = w.buf.size();
        slot_start_[static_cast<std::size_t>(s)] = static_cast<int>(first);
        if constexpr (detail::PeriodicCells<Chart>) {
          for (const auto& span : w.spans) {
            for (int t = span.first; t < span.second; ++t) {
              const int j = order_[static_cast<std::size_t>(t)];
              if (j == i) continue;
              if (chord2_of(chart, X, i, j, y) < chord2) w.buf.push_back(j);
            }
          }
        } else if (minkowski) {
          scan_dispatch<true>(a, s, chord2, w);
        } else {
          scan_dispatch<false>(a, s, chord2, w);
        }
        sort_row(w.buf.data() + first, w.buf.data() + w.buf.size());
        out.offset[static_cast<std::size_t>(i) + 1] = static_cast<int>(w.buf.size() - first);
      }
    });
    // Counts to offsets, and the rows' bodies in cell order, on threads (passes over every body:
    // serial, they were Amdahl's share of a rebuild in `sesi run --profile`).
    parallel::prefix_sums(out.offset.data() + 1, rows, scan_);
    const std::size_t pairs = static_cast<std::size_t>(out.offset.back());
    if (out.index.capacity() < pairs) out.index.reserve(pairs + pairs / 4);  // slack: later builds do not allocate
    out.index.resize(pairs);
    if (out.visit_order.capacity() < static_cast<std::size_t>(rows)) out.visit_order.reserve(static_cast<std::size_t>(rows));
    parallel::select_in_order(
        total, scan_, [&](int s) { return order_[static_cast<std::size_t>(s)] < rows; },
        [&](int kept) { out.visit_order.resize(static_cast<std::size_t>(kept)); },
        [&](int k, int s) { out.visit_order[static_cast<std::size_t>(k)] = order_[static_cast<std::size_t>(s)]; });
    parallel::for_chunks(total, chunks, [&](int begin, int end, int c) {
      const std::vector<int>& buf = scratch_[static_cast<std::size_t>(c)].buf;
      for (int s = begin; s < end; ++s) {
        const int i = order_[static_cast<std::size_t>(s)];
        if (i >= rows) continue;
        const int from = slot_start_[static_cast<std::size_t>(s)];
        const int count = out.end(i) - out.begin(i);
        std::copy(buf.begin() + from, buf.begin() + from + count, out.index.begin() + out.begin(i));
      }
    });
  }

  /// A row in ascending order: an insertion sort for the short rows of a pair cutoff (no call to
  /// memmove for every element, as std::sort's has), std::sort for long ones.
  static void sort_row(int* first, int* last) {
    if (last - first < 2) return;  // (an empty row of an empty buffer: first may be null)
    if (last - first > 48) {
      std::sort(first, last);
      return;
    }
    for (int* p = first + 1; p < last; ++p) {
      const int v = *p;
      int* q = p;
      while (q > first && q[-1] > v) {
        *q = q[-1];
        --q;
      }
      *q = v;
    }
  }

  /// Per chunk of build_rows: query boxes, a key, the candidate runs of slots, the rows found.
  struct Scratch {
    std::vector<Box> boxes;
    std::vector<std::int64_t> key;
    std::vector<std::pair<int, int>> spans;
    std::vector<int> hints;  // for_rows_in's
    std::vector<int> buf;
  };

  /// The candidates of slot s (packed_) within chord2, appended to w.buf: the chord as chord2_of
  /// forms it (coordinates in ascending order, then the time-like correction on H^n), A the
  /// ambient dimension when known at compile time (0: a).
  template <bool Minkowski>
  void scan_dispatch(int a, int s, Scalar chord2, Scratch& w) const {
    std::size_t candidates = 0;
    for (const auto& span : w.spans) candidates += static_cast<std::size_t>(span.second - span.first);
    const std::size_t at = w.buf.size();
    w.buf.resize(at + candidates);
    int* dst = w.buf.data() + at;
    int kept = 0;
    switch (a) {
      case 2: kept = scan<2, Minkowski>(a, s, chord2, w, dst); break;
      case 3: kept = scan<3, Minkowski>(a, s, chord2, w, dst); break;
      case 4: kept = scan<4, Minkowski>(a, s, chord2, w, dst); break;
      default: kept = scan<0, Minkowski>(a, s, chord2, w, dst); break;
    }
    w.buf.resize(at + static_cast<std::size_t>(kept));
  }
  /// Chords a block of `pad` slots at a time (a loop of fixed length, which the compiler
  /// vectorises; packed_ has pad slots of padding at the end of each coordinate), then the
  /// partners kept without a branch.
  static constexpr int pad = 4;
  template <int A, bool Minkowski>
  int scan(int a_run, int s, Scalar chord2, const Scratch& w, int* dst) const {
    const int a = A > 0 ? A : a_run;
    const std::size_t stride = order_.size() + static_cast<std::size_t>(pad);
    const Scalar* p = packed_.data();
    alignas(64) Scalar c2[pad];
    int kept = 0;
    for (const auto& span : w.spans) {
      for (int t0 = span.first; t0 < span.second; t0 += pad) {
        const int m = std::min(pad, span.second - t0);
        for (int q = 0; q < pad; ++q) c2[q] = Scalar(0);
        for (int k = 0; k < a; ++k) {
          const Scalar* pk = p + static_cast<std::size_t>(k) * stride;
          const Scalar x = pk[s];
          const Scalar* pt = pk + t0;
          for (int q = 0; q < pad; ++q) {
            const Scalar u = x - pt[q];
            c2[q] += u * u;
          }
        }
        if constexpr (Minkowski) {
          const Scalar* pk = p + static_cast<std::size_t>(a - 1) * stride;
          const Scalar x = pk[s];
          const Scalar* pt = pk + t0;
          for (int q = 0; q < pad; ++q) {
            const Scalar u = x - pt[q];
            c2[q] -= Scalar(2) * u * u;
          }
        }
        const int* id = order_.data() + t0;
        for (int q = 0; q < m; ++q) {
          dst[kept] = id[q];
          kept += (c2[q] < chord2) & (t0 + q != s);
        }
      }
    }
    return kept;
  }

  // ---- compact hyperbolic surfaces: ghost images ----------------------------------------------

  /// Lists of pairs (j, k) on a surface (the file's notes): the bodies and their ghosts in one
  /// H^n index, the real bodies' rows mapped to (body, image) and sorted.
  template <class Matrix>
  void build_with_ghosts(const Chart& chart, const Matrix& X, Scalar reach, NeighbourLists& out) {
    using std::cosh;
    const auto& topology = chart.topology();
    const int n = static_cast<int>(X.cols());
    const int a = static_cast<int>(X.rows());
    const int chunks = parallel::chunks_for(n);
    // s: the farthest a body lies outside D (a NaN body is skipped: it finds no partner).
    outside_.assign(static_cast<std::size_t>(n), Scalar(0));
    parallel::for_chunks(n, chunks, [&](int begin, int end, int) {
      typename Chart::Topology::Vector x;
      for (int j = begin; j < end; ++j) {
        x = X.col(j);
        outside_[static_cast<std::size_t>(j)] = topology.outside(x);
      }
    });
    Scalar slack(0);
    for (Scalar o : outside_) {
      if (o > slack) slack = o;
    }
    // Widened by a relative 1e-6 for the round-off of the points and of the tests below.
    const Scalar radius = topology.radius();
    const Scalar ghost_reach = (reach + slack) * Scalar(1 + 1e-6) + radius * Scalar(1e-12);
    // A body at distance r from D's centre is at least inradius - r from every other tile (the
    // inscribed disc of a tile lies in it), so its images are farther than ghost_reach from D
    // when r < inradius - ghost_reach: x_0 < R cosh((inradius - ghost_reach) / R).
    const Scalar deep = topology.inradius() - ghost_reach;
    const Scalar deep_time = deep > Scalar(0) ? radius * cosh(deep / radius) : Scalar(0);
    // Which images of a body to keep as ghosts: those within ghost_reach of D, or a few more
    // (extra ghosts are images all the same: any of them within reach of a body is a true pair).
    // Two necessary conditions, cheaper than the exact distance (images_near): the image's time
    // coordinate at most R cosh(circumradius/R + ghost_reach/R) (a dot product with the matrix's
    // last row), and its signed distance to the line of every side of D at most ghost_reach
    // (<z, n_k>_L <= R sinh(ghost_reach / R), n_k the sides' unit normals: D lies in each
    // half-plane). At genus 8 this takes a build from 7 ms to 2 ms (1099 bodies).
    const auto& images = topology.images();
    const int count = static_cast<int>(images.size());
    const Scalar cap = radius * cosh((topology.circumradius() + ghost_reach) / radius);
    const Scalar side_cap = radius * std::sinh(ghost_reach / radius);
    const int sides = topology.sides();
    ghost_lists_.resize(static_cast<std::size_t>(chunks));
    for (auto& ghosts : ghost_lists_) ghosts.clear();
    parallel::for_chunks(n, chunks, [&](int begin, int end, int c) {
      std::vector<std::pair<int, int>>& ghosts = ghost_lists_[static_cast<std::size_t>(c)];
      ghosts.clear();
      typename Chart::Topology::Vector x, z;
      for (int j = begin; j < end; ++j) {
        if (X(a - 1, j) < deep_time) continue;  // (NaN: not deep, and found nowhere)
        x = X.col(j);
        for (int k = 1; k < count; ++k) {
          const auto& m = images[static_cast<std::size_t>(k)];
          if (!(m(2, 0) * x[0] + m(2, 1) * x[1] + m(2, 2) * x[2] <= cap)) continue;
          z = x;
          topology.apply(k, z);
          bool near = true;
          for (int side = 0; side < sides && near; ++side) {
            const auto& nk = topology.normal(side);
            near = nk[0] * z[0] + nk[1] * z[1] - nk[2] * z[2] <= side_cap;
          }
          if (near) ghosts.emplace_back(j, k);
        }
      }
    });
    ghost_body_.clear();
    ghost_image_.clear();
    for (const auto& ghosts : ghost_lists_) {
      for (const auto& g : ghosts) {
        ghost_body_.push_back(g.first);
        ghost_image_.push_back(g.second);
      }
    }
    const int ghosts = static_cast<int>(ghost_body_.size());
    points_.resize(a, n + ghosts);
    points_.leftCols(n) = X;
    parallel::for_chunks(ghosts, parallel::chunks_for(ghosts), [&](int begin, int end, int) {
      typename Chart::Topology::Vector y;
      for (int g = begin; g < end; ++g) {
        y = X.col(ghost_body_[static_cast<std::size_t>(g)]);
        topology.apply(ghost_image_[static_cast<std::size_t>(g)], y);
        points_.col(n + g) = y;
      }
    });
    build_rows(chart, points_, n, reach, raw_);
    // Rows of (body, image), a body's own images left out, sorted by (body, image).
    out.offset.assign(static_cast<std::size_t>(n) + 1, 0);
    pair_lists_.resize(static_cast<std::size_t>(chunks));
    parallel::for_chunks(n, chunks, [&](int begin, int end, int c) {
      std::vector<std::pair<int, int>>& buf = pair_lists_[static_cast<std::size_t>(c)];
      buf.clear();
      for (int i = begin; i < end; ++i) {
        const std::size_t first = buf.size();
        for (int e = raw_.begin(i); e < raw_.end(i); ++e) {
          const int p = raw_.index[static_cast<std::size_t>(e)];
          const int j = p < n ? p : ghost_body_[static_cast<std::size_t>(p - n)];
          const int k = p < n ? 0 : ghost_image_[static_cast<std::size_t>(p - n)];
          if (j != i) buf.emplace_back(j, k);
        }
        std::sort(buf.begin() + static_cast<std::ptrdiff_t>(first), buf.end());
        out.offset[static_cast<std::size_t>(i) + 1] = static_cast<int>(buf.size() - first);
      }
    });
    for (int i = 0; i < n; ++i) out.offset[static_cast<std::size_t>(i) + 1] += out.offset[static_cast<std::size_t>(i)];
    out.index.resize(static_cast<std::size_t>(out.offset.back()));
    out.image.resize(static_cast<std::size_t>(out.offset.back()));
    parallel::for_chunks(n, chunks, [&](int begin, int, int c) {
      const std::vector<std::pair<int, int>>& buf = pair_lists_[static_cast<std::size_t>(c)];
      std::size_t at = static_cast<std::size_t>(out.offset[static_cast<std::size_t>(begin)]);
      for (const auto& e : buf) {
        out.index[at] = e.first;
        out.image[at] = e.second;
        ++at;
      }
    });
  }

  static std::int64_t cell_of(Scalar v) {
    using std::floor;
    constexpr Scalar limit = Scalar(std::int64_t(1) << 60);
    const Scalar f = floor(v);
    if (!(f > -limit)) return -(std::int64_t(1) << 60);  // also NaN: one far cell
    if (!(f < limit)) return std::int64_t(1) << 60;
    return static_cast<std::int64_t>(f);
  }

  /// Cell keys of every body, the bodies sorted by key, and the runs of equal keys.
  template <class Matrix>
  void bin(const Chart& chart, const Matrix& X, Scalar reach, Scalar chord) {
    const int n = static_cast<int>(X.cols());
    const int a = static_cast<int>(X.rows());
    if constexpr (detail::PeriodicCells<Chart>) {
      // floor(L_k / reach) cells per axis (at least 1), of side L_k / cells >= reach; the reach
      // widened by a relative 1e-9 so that a cell's side stays above it after the division's
      // rounding. A body outside [0, L_k) between wraps still finds its cell: the key is taken
      // modulo the count.
      static_cast<void>(chord);
      const auto& edges = chart.topology().edges();
      keys_ = a;
      cells_.assign(static_cast<std::size_t>(a), 1);
      cell_side_.assign(static_cast<std::size_t>(a), Scalar(1));
      for (int d = 0; d < a; ++d) {
        const Scalar L = edges[d];
        const Scalar count = reach > Scalar(0) ? std::floor(L / (reach * Scalar(1 + 1e-9))) : Scalar(1);
        // (at most 2^30 cells per axis: more would only be empty ones)
        cells_[static_cast<std::size_t>(d)] =
            count >= Scalar(1) ? static_cast<std::int64_t>(std::min(count, Scalar(std::int64_t(1) << 30))) : 1;
        cell_side_[static_cast<std::size_t>(d)] = L / static_cast<Scalar>(cells_[static_cast<std::size_t>(d)]);
      }
      key_.resize(static_cast<std::size_t>(n) * static_cast<std::size_t>(keys_));  // all written below
      parallel::for_each(n, [&](int i) {
        std::int64_t* k = &key_[static_cast<std::size_t>(i) * static_cast<std::size_t>(keys_)];
        for (int d = 0; d < a; ++d) {
          const std::int64_t m = cells_[static_cast<std::size_t>(d)];
          const std::int64_t c = cell_of(X(d, i) / cell_side_[static_cast<std::size_t>(d)]) % m;
          k[d] = c < 0 ? c + m : c;
        }
      });
    } else if (chart.curvature() < Scalar(0)) {
      keys_ = a - 1;  // the band, then the n - 1 horizontal coordinates
      key_.resize(static_cast<std::size_t>(n) * static_cast<std::size_t>(keys_));  // all written below
      set_half_space(chart, X, reach);
      parallel::for_each(n, [&](int i) {
        const Scalar u = half_space(X, i);
        std::int64_t* k = &key_[static_cast<std::size_t>(i) * static_cast<std::size_t>(keys_)];
        k[0] = cell_of(u / band_);
        const Scalar width = box_width(k[0]);
        for (int d = 1; d < keys_; ++d) k[d] = cell_of(w_(d - 1, i) / width);
      });
    } else {
      keys_ = a;  // the ambient coordinates
      key_.resize(static_cast<std::size_t>(n) * static_cast<std::size_t>(keys_));  // all written below
      side_ = chord > Scalar(0) ? chord : Scalar(1);
      parallel::for_each(n, [&](int i) {
        std::int64_t* k = &key_[static_cast<std::size_t>(i) * static_cast<std::size_t>(keys_)];
        for (int d = 0; d < a; ++d) k[d] = cell_of(X(d, i) / side_);
      });
    }
    sort_by_key(n);
    // The runs of equal keys, on threads (capacities kept: no allocation after the first build).
    const auto starts_run = [&](int s) {
      return s == 0 || compare(key_ptr(order_[static_cast<std::size_t>(s)]), key_ptr(order_[static_cast<std::size_t>(s) - 1])) != 0;
    };
    const int cells = parallel::select_in_order(
        n, scan_, starts_run,
        [&](int runs) {
          cell_key_.resize(static_cast<std::size_t>(runs) * static_cast<std::size_t>(keys_));
          cell_start_.resize(static_cast<std::size_t>(runs) + 1);
        },
        [&](int c, int s) {
          const std::int64_t* k = key_ptr(order_[static_cast<std::size_t>(s)]);
          std::copy(k, k + keys_, cell_key_.begin() + static_cast<std::ptrdiff_t>(static_cast<std::size_t>(c) * static_cast<std::size_t>(keys_)));
          cell_start_[static_cast<std::size_t>(c)] = s;
        });
    cell_start_[static_cast<std::size_t>(cells)] = n;
  }

  /// order_: the bodies sorted by (key, index). Where the keys' bounding box has fewer than
  /// 2^62 cells, by a stable radix sort of the cells' row-major numbers in it (the same order
  /// as the keys', lexicographic); else, and for fewer bodies than radix_min_bodies, by
  /// comparisons.
  void sort_by_key(int n) {
    order_.resize(static_cast<std::size_t>(n));
    parallel::for_each(n, [&](int i) { order_[static_cast<std::size_t>(i)] = i; });
    if (n == 0) return;
    const auto by_key = [&](int i, int j) {
      const int c = compare(key_ptr(i), key_ptr(j));
      return c != 0 ? c < 0 : i < j;
    };
    // A radix pass clears and scans 2^11 buckets a chunk, whatever n: for a few bodies that
    // was most of a step (2 bodies on H^2: 52 % of `sesi run` in sort_by_key).
    if (n < radix_min_bodies) {
      std::sort(order_.begin(), order_.end(), by_key);
      return;
    }
    // The keys' bounding box: each chunk's on threads, then joined (min and max: any order).
    const int chunks = parallel::chunks_for(n);
    const std::size_t K = static_cast<std::size_t>(keys_);
    chunk_low_.assign(static_cast<std::size_t>(chunks) * K, std::numeric_limits<std::int64_t>::max());
    chunk_high_.assign(static_cast<std::size_t>(chunks) * K, std::numeric_limits<std::int64_t>::min());
    parallel::for_chunks(n, chunks, [&](int begin, int end, int c) {
      std::int64_t* low = chunk_low_.data() + static_cast<std::size_t>(c) * K;
      std::int64_t* up = chunk_high_.data() + static_cast<std::size_t>(c) * K;
      for (int i = begin; i < end; ++i) {
        const std::int64_t* k = key_ptr(i);
        for (std::size_t d = 0; d < K; ++d) {
          low[d] = std::min(low[d], k[d]);
          up[d] = std::max(up[d], k[d]);
        }
      }
    });
    key_low_.assign(K, std::numeric_limits<std::int64_t>::max());
    std::vector<std::int64_t>& high = key_high_;
    high.assign(K, std::numeric_limits<std::int64_t>::min());
    for (std::size_t c = 0; c < static_cast<std::size_t>(chunks); ++c) {
      for (std::size_t d = 0; d < K; ++d) {
        key_low_[d] = std::min(key_low_[d], chunk_low_[c * K + d]);
        high[d] = std::max(high[d], chunk_high_[c * K + d]);
      }
    }
    // The cells of the bounding box, while below 2^62 (keys lie within +-2^60: no overflow).
    constexpr std::uint64_t most = std::uint64_t(1) << 62;
    std::uint64_t count = 1;
    for (int d = 0; d < keys_ && count < most; ++d) {
      const std::uint64_t side = static_cast<std::uint64_t>(high[static_cast<std::size_t>(d)] - key_low_[static_cast<std::size_t>(d)]) + 1;
      count = side >= most || count > most / side ? most : count * side;
    }
    if (count >= most) {
      std::sort(order_.begin(), order_.end(), by_key);
      return;
    }
    cell_number_.resize(static_cast<std::size_t>(n));
    parallel::for_each(n, [&](int i) {
      const std::int64_t* k = key_ptr(i);
      std::uint64_t number = 0;
      for (int d = 0; d < keys_; ++d) {
        const std::uint64_t side = static_cast<std::uint64_t>(high[static_cast<std::size_t>(d)] - key_low_[static_cast<std::size_t>(d)]) + 1;
        number = number * side + static_cast<std::uint64_t>(k[d] - key_low_[static_cast<std::size_t>(d)]);
      }
      cell_number_[static_cast<std::size_t>(i)] = number;
    });
    // LSD radix sort, 11 bits a pass: stable, so ties stay in index order. Each pass on threads
    // by chunks of order_ (Satish, Harris & Garland, IPDPS 2009): a histogram per chunk, the
    // offsets bucket by bucket and within a bucket chunk by chunk, then each chunk scatters its
    // bodies in order. The result is the one stable order, whatever the chunks.
    constexpr int bits = 11;
    constexpr std::size_t buckets = std::size_t(1) << bits;
    int passes = 0;
    while (passes * bits < 64 && (count - 1) >> (passes * bits) != 0) ++passes;
    order_tmp_.resize(static_cast<std::size_t>(n));
    bucket_.resize(buckets * static_cast<std::size_t>(chunks));
    const auto digit = [&](int i, int shift) {
      return static_cast<std::size_t>((cell_number_[static_cast<std::size_t>(i)] >> shift) & (buckets - 1));
    };
    for (int pass = 0; pass < passes; ++pass) {
      const int shift = pass * bits;
      std::fill(bucket_.begin(), bucket_.end(), 0);
      parallel::for_chunks(n, chunks, [&](int begin, int end, int c) {
        int* count_of = bucket_.data() + static_cast<std::size_t>(c) * buckets;
        for (int s = begin; s < end; ++s) ++count_of[digit(order_[static_cast<std::size_t>(s)], shift)];
      });
      int at = 0;  // counts -> first slots
      for (std::size_t b = 0; b < buckets; ++b) {
        for (std::size_t c = 0; c < static_cast<std::size_t>(chunks); ++c) {
          int& slot = bucket_[c * buckets + b];
          const int here = slot;
          slot = at;
          at += here;
        }
      }
      parallel::for_chunks(n, chunks, [&](int begin, int end, int c) {
        int* next = bucket_.data() + static_cast<std::size_t>(c) * buckets;
        for (int s = begin; s < end; ++s) {
          const int i = order_[static_cast<std::size_t>(s)];
          order_tmp_[static_cast<std::size_t>(next[digit(i, shift)]++)] = i;
        }
      });
      order_.swap(order_tmp_);
    }
  }

  // ---- H^n: upper half-space coordinates ------------------------------------------------------
  // With the hyperboloid point (s, t) (s spatial, t = x_n > 0, t^2 - |s|^2 = R^2) and a unit
  // spatial direction e toward the bodies, y = R^2 / (t + e.s) and w = R P s / (t + e.s), where P
  // projects onto the spatial directions orthogonal to e. This is the half-space model with its
  // boundary point at infinity opposite e, so for the bodies t + e.s ~ 2t has no cancellation.
  // Distances: cosh(d/R) = 1 + (|w - w'|^2 + (y - y')^2) / (2 y y').

  template <class Matrix>
  void set_half_space(const Chart& chart, const Matrix& X, Scalar reach) {
    const int a = static_cast<int>(X.rows());
    const int n = static_cast<int>(X.cols());
    radius_ = Scalar(1) / std::sqrt(-chart.curvature());
    // The bodies' direction: the spatial part of their sum (all 0: any axis will do).
    Eigen::Matrix<Scalar, Eigen::Dynamic, 1> e = Eigen::Matrix<Scalar, Eigen::Dynamic, 1>::Zero(a - 1);
    for (int i = 0; i < n; ++i) {
      if (X.col(i).allFinite()) e += X.col(i).head(a - 1) / X(a - 1, i);
    }
    if (!(e.norm() > Scalar(0))) {
      e.setZero();
      e[0] = Scalar(1);
    }
    e.normalize();
    // An orthonormal basis of e's complement: the Householder reflection taking e to the last
    // spatial axis maps that complement onto the first a - 2 axes.
    basis_.resize(a - 1, a - 1);
    Eigen::Matrix<Scalar, Eigen::Dynamic, 1> v = e;
    v[a - 2] += e[a - 2] >= Scalar(0) ? Scalar(1) : Scalar(-1);
    basis_.setIdentity();
    basis_ -= (Scalar(2) / v.squaredNorm()) * v * v.transpose();  // rows 0..a-3: the complement
    direction_ = e;
    band_ = reach;
    w_.resize(std::max(a - 2, 1), n);
    height_.resize(static_cast<std::size_t>(n));
  }
  /// Body i's half-space coordinates: w into w_.col(i), its height y into height_[i]; returns
  /// the hyperbolic height u = R log(y / R).
  template <class Matrix>
  Scalar half_space(const Matrix& X, int i) {
    const int a = static_cast<int>(X.rows());
    Scalar along(0);
    for (int k = 0; k < a - 1; ++k) along += direction_[k] * X(k, i);
    const Scalar denom = X(a - 1, i) + along;  // > 0 on the hyperboloid: t > |s|
    for (int d = 0; d + 2 < a; ++d) {
      Scalar s(0);
      for (int k = 0; k < a - 1; ++k) s += basis_(d, k) * X(k, i);
      w_(d, i) = radius_ * s / denom;
    }
    height_[static_cast<std::size_t>(i)] = radius_ * radius_ / denom;
    return radius_ * std::log(radius_ / denom);
  }
  /// The horizontal side of the boxes in band k: hyperbolic width h at the band's bottom.
  Scalar box_width(std::int64_t band) const {
    return band_ * std::exp(static_cast<Scalar>(band) * band_ / radius_);
  }

  // ---- queries ---------------------------------------------------------------------------------

  /// The boxes of cells that may hold a body within distance reach of body i.
  template <class Matrix>
  void query_boxes(const Chart& chart, const Matrix&, int i, Scalar reach, std::vector<Box>& boxes) const {
    const std::int64_t* k = key_ptr(i);
    if constexpr (detail::PeriodicCells<Chart>) {
      // The cells k - 1, k, k + 1 modulo the count on each axis, as one or two runs of keys
      // (every cell of an axis with fewer than 3), and every product of the axes' runs.
      static_cast<void>(reach);
      constexpr int most = 16;  // axes with runs of their own; beyond, every axis is searched whole
      std::int64_t runs[most][2][2];  // (axis, run, lo/hi)
      int count[most];
      int total = 1;
      for (int d = 0; d < keys_ && d < most; ++d) {
        const std::int64_t m = cells_[static_cast<std::size_t>(d)], c = k[d];
        count[d] = 1;
        if (m < 3 || keys_ > most) {
          runs[d][0][0] = 0;
          runs[d][0][1] = m - 1;
        } else if (c == 0) {
          runs[d][0][0] = 0;
          runs[d][0][1] = 1;
          runs[d][1][0] = runs[d][1][1] = m - 1;
          count[d] = 2;
        } else if (c == m - 1) {
          runs[d][0][0] = 0;
          runs[d][0][1] = 0;
          runs[d][1][0] = m - 2;
          runs[d][1][1] = m - 1;
          count[d] = 2;
        } else {
          runs[d][0][0] = c - 1;
          runs[d][0][1] = c + 1;
        }
        total *= count[d];
      }
      boxes.resize(static_cast<std::size_t>(total));
      for (int t = 0; t < total; ++t) {
        Box& b = boxes[static_cast<std::size_t>(t)];
        b.lo.resize(static_cast<std::size_t>(keys_));
        b.hi.resize(static_cast<std::size_t>(keys_));
        int rest = t;
        for (int d = 0; d < keys_; ++d) {
          if (d >= most) {
            b.lo[static_cast<std::size_t>(d)] = 0;
            b.hi[static_cast<std::size_t>(d)] = cells_[static_cast<std::size_t>(d)] - 1;
            continue;
          }
          const int r = rest % count[d];
          rest /= count[d];
          b.lo[static_cast<std::size_t>(d)] = runs[d][r][0];
          b.hi[static_cast<std::size_t>(d)] = runs[d][r][1];
        }
      }
      return;
    } else if (chart.curvature() >= Scalar(0)) {
      boxes.resize(1);
      Box& b = boxes[0];
      b.lo.assign(k, k + keys_);
      b.hi.assign(k, k + keys_);
      for (int d = 0; d < keys_; ++d) {
        b.lo[static_cast<std::size_t>(d)] -= 1;  // side = chord reach: neighbours are in adjacent cells
        b.hi[static_cast<std::size_t>(d)] += 1;
      }
      return;
    }
    using std::cosh;
    using std::exp;
    using std::sinh;
    using std::sqrt;
    // The hyperbolic ball of radius r about (w, y) is the Euclidean ball about (w, y cosh rho) of
    // radius y sinh rho (rho = r / R); widened by a relative 1e-6 for the coordinates' round-off.
    const Scalar r = reach * Scalar(1 + 1e-6) + radius_ * Scalar(1e-12);
    const Scalar rho = r / radius_;
    const Scalar y = height_[static_cast<std::size_t>(i)];
    const Scalar u = radius_ * std::log(y / radius_);
    const std::int64_t first = cell_of((u - r) / band_), last = cell_of((u + r) / band_);
    boxes.resize(static_cast<std::size_t>(last - first + 1));  // (resized, not rebuilt: no allocation)
    for (std::int64_t band = first; band <= last; ++band) {
      const Scalar bottom = radius_ * exp(static_cast<Scalar>(band) * band_ / radius_);
      const Scalar top = bottom * exp(band_ / radius_);
      // The widest horizontal section of the ball within this band.
      const Scalar centre = y * cosh(rho), half = y * sinh(rho);
      const Scalar nearest = std::clamp(centre, std::max(bottom, y * exp(-rho)), std::min(top, y * exp(rho)));
      const Scalar off = nearest - centre;
      const Scalar reach_w = sqrt(std::max(Scalar(0), half * half - off * off)) * Scalar(1 + 1e-6);
      const Scalar width = box_width(band);
      Box& b = boxes[static_cast<std::size_t>(band - first)];
      b.lo.assign(static_cast<std::size_t>(keys_), band);
      b.hi.assign(static_cast<std::size_t>(keys_), band);
      for (int d = 1; d < keys_; ++d) {
        const Scalar w = w_(d - 1, i);
        b.lo[static_cast<std::size_t>(d)] = cell_of((w - reach_w) / width);
        b.hi[static_cast<std::size_t>(d)] = cell_of((w + reach_w) / width);
      }
    }
  }

  /// f(s0, s1) for the slots [s0, s1) of order_ in each row of box: an odometer over all key
  /// coordinates but the last, and one search per row for the run of occupied cells of the last
  /// (contiguous in order_). The search gallops from hints[row], where the same row of the last
  /// query began (nearby when cells are queried in order), then bisects.
  template <class F>
  void for_rows_in(const Box& box, std::vector<std::int64_t>& key, std::vector<int>& hints, int& row, F&& f) const {
    const int last = keys_ - 1;
    for (int d = 0; d < keys_; ++d) key[static_cast<std::size_t>(d)] = box.lo[static_cast<std::size_t>(d)];
    const int cells = static_cast<int>(cell_start_.size()) - 1;
    while (true) {
      key[static_cast<std::size_t>(last)] = box.lo[static_cast<std::size_t>(last)];
      if (static_cast<std::size_t>(row) >= hints.size()) hints.resize(static_cast<std::size_t>(row) + 1, 0);
      int& hint = hints[static_cast<std::size_t>(row)];
      ++row;
      // [lo, hi] brackets the first cell >= key: below lo all cells are < key, hi's is >= key (or hi = cells).
      int lo = 0, hi = cells;
      const int h = std::min(std::max(hint, 0), cells);
      if (h < cells && compare(cell_ptr(h), key.data()) < 0) {
        lo = h + 1;
        for (int step = 1;; step *= 2) {
          const int probe = h + step;
          if (probe >= cells) break;
          if (compare(cell_ptr(probe), key.data()) < 0) {
            lo = probe + 1;
          } else {
            hi = probe;
            break;
          }
          if (step > cells) break;
        }
      } else {
        hi = h;
        for (int step = 1;; step *= 2) {
          const int probe = h - step;
          if (probe < 0) break;
          if (compare(cell_ptr(probe), key.data()) < 0) {
            lo = probe + 1;
            break;
          }
          hi = probe;
          if (step > cells) break;
        }
      }
      while (lo < hi) {
        const int mid = (lo + hi) / 2;
        if (compare(cell_ptr(mid), key.data()) < 0) lo = mid + 1; else hi = mid;
      }
      int c = lo;
      for (; c < cells; ++c) {
        const std::int64_t* k = cell_ptr(c);
        if (compare_prefix(k, key.data(), last) != 0 || k[last] > box.hi[static_cast<std::size_t>(last)]) break;
      }
      hint = lo;
      if (c > lo) f(cell_start_[static_cast<std::size_t>(lo)], cell_start_[static_cast<std::size_t>(c)]);
      int d = last - 1;  // next row
      while (d >= 0) {
        if (++key[static_cast<std::size_t>(d)] <= box.hi[static_cast<std::size_t>(d)]) break;
        key[static_cast<std::size_t>(d)] = box.lo[static_cast<std::size_t>(d)];
        --d;
      }
      if (d < 0) return;
    }
  }

  const std::int64_t* key_ptr(int i) const {
    return &key_[static_cast<std::size_t>(i) * static_cast<std::size_t>(keys_)];
  }
  const std::int64_t* cell_ptr(int c) const {
    return &cell_key_[static_cast<std::size_t>(c) * static_cast<std::size_t>(keys_)];
  }
  /// Below this many bodies sort_by_key compares keys: n log n comparisons cost less than the
  /// radix sort's passes over its buckets.
  static constexpr int radix_min_bodies = 512;
  int compare(const std::int64_t* a, const std::int64_t* b) const { return compare_prefix(a, b, keys_); }
  static int compare_prefix(const std::int64_t* a, const std::int64_t* b, int n) {
    for (int d = 0; d < n; ++d) {
      if (a[d] != b[d]) return a[d] < b[d] ? -1 : 1;
    }
    return 0;
  }

  int keys_ = 0;
  std::vector<std::int64_t> key_;       // per body, keys_ each
  std::vector<int> order_;              // bodies sorted by (key, index)
  std::vector<int> order_tmp_, bucket_;  // sort_by_key's radix sort
  std::vector<std::uint64_t> cell_number_;         // sort_by_key: per body, its cell's number in the keys' box
  std::vector<std::int64_t> key_low_, key_high_;  // sort_by_key: the keys' bounding box
  std::vector<std::int64_t> chunk_low_, chunk_high_;  // sort_by_key: each chunk's
  std::vector<std::int64_t> cell_key_;  // per occupied cell, keys_ each, ascending
  std::vector<int> cell_start_;         // cell c holds order_[cell_start_[c] .. cell_start_[c+1])
  std::vector<Scratch> scratch_;        // per chunk of build_rows
  std::vector<Scalar> packed_;          // S^n, E^n, H^n: the points in the order of order_, coordinate by
                                        // coordinate (each followed by pad slots of padding)
  std::vector<int> slot_start_;         // per slot of order_: where its row starts in its chunk's buffer
  std::vector<int> scan_;               // parallel::prefix_sums' and select_in_order's per chunk
  Scalar side_ = 1;                     // S^n, E^n: the cells' side
  std::vector<std::int64_t> cells_;     // periodic box: cells per axis
  std::vector<Scalar> cell_side_;       // periodic box: their side per axis
  std::vector<Scalar> outside_;         // surface: how far each body lies outside the domain
  std::vector<std::vector<std::pair<int, int>>> ghost_lists_, pair_lists_;  // surface: per chunk
  std::vector<int> ghost_body_, ghost_image_;  // surface: ghost g is images()[ghost_image_[g]] x_{ghost_body_[g]}
  Points points_;                       // surface: the bodies, then the ghosts
  NeighbourLists raw_;                  // surface: the rows over points_
  Scalar radius_ = 1, band_ = 1;  // H^n
  Eigen::Matrix<Scalar, Eigen::Dynamic, 1> direction_;
  Points basis_, w_;
  std::vector<Scalar> height_;
};

/// The default skin of a Verlet list as a fraction of the range: LAMMPS' default 0.3 sigma is
/// 0.12 of a Lennard-Jones cutoff of 2.5 sigma (docs/benchmarks.md, "Skin", measures it).
inline constexpr double default_skin_fraction = 0.12;

/// A neighbour list with a skin, for one short-range term in one workspace.
template <class Chart>
class VerletList {
 public:
  using Scalar = typename Chart::Scalar;

  /// The skin as a fraction of the range. The forces do not depend on it, only the time they take.
  Scalar skin_fraction = Scalar(default_skin_fraction);

  /// Lists valid for points X (ambient x bodies) and range: rebuilt when X has a different
  /// number of bodies, the range or the skin changed, or a body moved more than half the skin
  /// (with no skin, at every update).
  template <class Matrix>
  const NeighbourLists& update(const Chart& chart, const Matrix& X, Scalar range) {
    const Scalar skin = skin_fraction * range;
    if (!valid(chart, X, range, skin)) rebuild(chart, X, range, skin);
    return lists_;
  }
  /// update(chart, X, range) where X differs from the points of the last update in the columns
  /// `moved` only (the caller's promise): only those are measured against the build, since every
  /// other body was within half the skin of it at that update and has not moved since. For a
  /// gradient patched after a few bodies were re-charted (System::patch_gradient), whose full
  /// check passed over every body.
  template <class Matrix>
  const NeighbourLists& update_moved(const Chart& chart, const Matrix& X, Scalar range, std::span<const int> moved) {
    const Scalar skin = skin_fraction * range;
    if (built_at_.cols() != X.cols() || built_at_.rows() != X.rows() || range != range_ || skin != skin_ ||
        !(skin > Scalar(0))) {
      return update(chart, X, range);
    }
    for (const int i : moved) {
      if (!near_build(chart, X, i)) {
        rebuild(chart, X, range, skin);
        break;
      }
    }
    return lists_;
  }
  /// Rebuilds so far.
  long builds() const { return builds_; }
  /// The bodies in the cell order of the last build (NeighbourLists::visit_order).
  const std::vector<int>& visit_order() const { return lists_.visit_order; }
  /// Forget the lists (the next update rebuilds).
  void clear() { built_at_.resize(0, 0); }

 private:
  template <class Matrix>
  void rebuild(const Chart& chart, const Matrix& X, Scalar range, Scalar skin) {
    profile::Scope scope(profile::Phase::neighbours);
    index_.build(chart, X, range + skin, lists_);
    // The points of the build, copied on threads (a copy of every point: no serial pass).
    built_at_.resize(X.rows(), X.cols());
    const int n = static_cast<int>(X.cols());
    parallel::for_chunks(n, parallel::chunks_for(n), [&](int begin, int end, int) {
      built_at_.middleCols(begin, end - begin) = X.middleCols(begin, end - begin);
    });
    range_ = range;
    skin_ = skin;
    half_skin_chord2_ = chart.chord_of_distance(skin / Scalar(2));
    half_skin_chord2_ *= half_skin_chord2_;
    ++builds_;
  }
  /// Whether body i of X lies within half the skin of its point at the build (valid's test for
  /// one body).
  template <class Matrix>
  bool near_build(const Chart& chart, const Matrix& X, int i) const {
    if constexpr (detail::PeriodicCells<Chart>) {
      typename Chart::Topology::Vector y = built_at_.col(i);
      chart.topology().nearest_image(X.col(i), y);
      return (X.col(i) - y).squaredNorm() <= half_skin_chord2_;  // NaN: no
    } else {
      const int a = static_cast<int>(X.rows());
      Scalar c2(0);
      for (int k = 0; k < a; ++k) {
        const Scalar u = X(k, i) - built_at_(k, i);
        c2 += u * u;
      }
      if (chart.curvature() < Scalar(0)) {  // Minkowski: the last coordinate is time-like
        const Scalar u = X(a - 1, i) - built_at_(a - 1, i);
        c2 -= Scalar(2) * u * u;
      }
      return c2 <= half_skin_chord2_;  // NaN: no
    }
  }
  template <class Matrix>
  bool valid(const Chart& chart, const Matrix& X, Scalar range, Scalar skin) const {
    if (built_at_.cols() != X.cols() || built_at_.rows() != X.rows() || range != range_ || skin != skin_ ||
        !(skin > Scalar(0))) {
      return false;
    }
    // Each chunk's own verdict, then whether any chunk saw a body move (no pass over a vector of
    // marks: this runs at every step).
    const int n = static_cast<int>(X.cols());
    std::atomic<bool> any_moved{false};
    if constexpr (detail::PeriodicCells<Chart>) {
      // The displacement to the nearest image of the point at the build: a body brought back
      // into the box has moved by its true displacement only (below L/2 while it is below the
      // half skin, as the cutoff is at most L/2).
      parallel::for_chunks(n, parallel::chunks_for(n), [&](int begin, int end, int) {
        typename Chart::Topology::Vector y(X.rows());
        bool moved = false;
        for (int i = begin; i < end; ++i) {
          y = built_at_.col(i);
          chart.topology().nearest_image(X.col(i), y);
          const Scalar c2 = (X.col(i) - y).squaredNorm();
          moved = moved || !(c2 <= half_skin_chord2_);  // NaN: rebuild
        }
        if (moved) any_moved.store(true, std::memory_order_relaxed);
      });
      return !any_moved.load();
    }
    const int a = static_cast<int>(X.rows());
    const bool minkowski = chart.curvature() < Scalar(0);  // the last entry counts negatively
    const Scalar limit = half_skin_chord2_;
    parallel::for_chunks(n, parallel::chunks_for(n), [&](int begin, int end, int) {
      bool moved = false;
      for (int i = begin; i < end; ++i) {
        Scalar c2(0);
        for (int k = 0; k < a; ++k) {
          const Scalar u = X(k, i) - built_at_(k, i);
          c2 += u * u;
        }
        if (minkowski) {
          const Scalar u = X(a - 1, i) - built_at_(a - 1, i);
          c2 -= Scalar(2) * u * u;
        }
        moved |= !(c2 <= limit);  // NaN: rebuild
      }
      if (moved) any_moved.store(true, std::memory_order_relaxed);
    });
    return !any_moved.load();
  }

  NeighbourIndex<Chart> index_;
  NeighbourLists lists_;
  Eigen::Matrix<Scalar, Eigen::Dynamic, Eigen::Dynamic> built_at_;
  Scalar range_ = 0, skin_ = 0, half_skin_chord2_ = 0;
  long builds_ = 0;
};

}  // namespace sesi
