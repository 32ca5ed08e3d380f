#pragma once
/// @file check_chart.hpp
/// sesi::check_chart: the first thing to run on a new chart (docs/concepts.md). The concepts
/// check that a chart has the right members; this checks numerically, at sample points, what
/// they cannot:
///   - the hierarchy: K_i depends on q_1..q_{i-1} (and p_i) only. A K_i that reads q_j, j >= i,
///     compiles and runs, but the splitting is then neither symplectic nor explicit;
///   - kinetic_dp and kinetic_dq against central differences of kinetic;
///   - for an EmbeddedChart, pullback(q, g) against J^T g with J from central differences of
///     embed.
/// The differences use the step h = eps^(1/3) (1 + |z|), whose error is about eps^(2/3) of the
/// derivatives' scale (truncation h^2 f''' / 6 and rounding eps f / h balance there); the
/// tolerance is 1e-6 of that scale, far above it and far below a missing term or a wrong sign.

#include <cmath>
#include <limits>
#include <span>
#include <sstream>
#include <string>
#include <vector>

#include "sesi/chart.hpp"

namespace sesi {

/// What check_chart found: one line per failure (empty: none).
struct ChartCheck {
  std::vector<std::string> failures;
  int checked = 0;  ///< the comparisons made
  explicit operator bool() const { return failures.empty(); }
  /// The failures, one per line.
  std::string report() const {
    std::string out;
    for (const std::string& f : failures) out += f + "\n";
    return out;
  }
};

/// Check chart at each sample point q (with momenta p = 0.3, -0.7, 1.1, ... and mass m).
template <HierarchicalChart C>
ChartCheck check_chart(const C& chart, std::span<const typename C::Point> samples,
                       typename C::Scalar m = typename C::Scalar(1)) {
  using Scalar = typename C::Scalar;
  using std::abs;
  using std::cbrt;
  using std::max;
  const Scalar eps = std::numeric_limits<Scalar>::epsilon();
  const Scalar tolerance = Scalar(1e-6);
  const int n = dim_of(chart);
  ChartCheck out;
  const auto fail = [&](int sample, const std::string& what) {
    std::ostringstream line;
    line << "sample " << sample + 1 << ": " << what;
    out.failures.push_back(line.str());
  };
  const auto step = [&](Scalar z) { return cbrt(eps) * (Scalar(1) + abs(z)); };

  for (std::size_t s = 0; s < samples.size(); ++s) {
    const int sample = static_cast<int>(s);
    const typename C::Point& q = samples[s];
    for (int i = 0; i < n; ++i) {
      const Scalar pi = Scalar(0.3) + Scalar(0.4) * Scalar(i) * (i % 2 == 0 ? Scalar(1) : Scalar(-1));
      const Scalar k = chart.kinetic(i, q, pi, m);
      // The hierarchy: moving q_j, j >= i (0-based: level i sees q_0..q_{i-1}), leaves K_i as it is.
      for (int j = i; j < n; ++j) {
        typename C::Point moved = q;
        moved[j] += Scalar(0.1);
        ++out.checked;
        const Scalar changed = chart.kinetic(i, moved, pi, m);
        if (abs(changed - k) > Scalar(16) * eps * (abs(k) + Scalar(1))) {
          std::ostringstream what;
          what << "K_" << i + 1 << " depends on q_" << j + 1 << " (moving it by 0.1 changes K_" << i + 1
               << " from " << k << " to " << changed << "); level " << i + 1 << " may read q_1..q_" << i
               << " only";
          fail(sample, what.str());
        }
      }
      // dK_i/dp_i.
      {
        const Scalar h = step(pi);
        const Scalar fd = (chart.kinetic(i, q, pi + h, m) - chart.kinetic(i, q, pi - h, m)) / (Scalar(2) * h);
        const Scalar got = chart.kinetic_dp(i, q, pi, m);
        ++out.checked;
        if (abs(got - fd) > tolerance * max({Scalar(1), abs(fd), abs(k)})) {
          std::ostringstream what;
          what << "kinetic_dp(" << i << ") = " << got << ", central difference of kinetic " << fd;
          fail(sample, what.str());
        }
      }
      // dK_i/dq_k, k < i.
      for (int c = 0; c < i; ++c) {
        typename C::Point plus = q, minus = q;
        const Scalar h = step(q[c]);
        plus[c] += h;
        minus[c] -= h;
        const Scalar fd = (chart.kinetic(i, plus, pi, m) - chart.kinetic(i, minus, pi, m)) / (Scalar(2) * h);
        const Scalar got = chart.kinetic_dq(i, c, q, pi, m);
        ++out.checked;
        if (abs(got - fd) > tolerance * max({Scalar(1), abs(fd), abs(k)})) {
          std::ostringstream what;
          what << "kinetic_dq(" << i << ", " << c << ") = " << got << ", central difference of kinetic " << fd;
          fail(sample, what.str());
        }
      }
    }
    // The pull-back: J^T g for g = e_a, column by column of J.
    if constexpr (EmbeddedChart<C>) {
      const int a_dim = ambient_dim_of(chart);
      typename C::Ambient x(a_dim), xp(a_dim), xm(a_dim), g(a_dim);
      typename C::Point pulled(n);
      chart.embed(q, x);
      const Scalar scale = max(Scalar(1), x.cwiseAbs().maxCoeff());
      for (int a = 0; a < a_dim; ++a) {
        g.setZero();
        g[a] = Scalar(1);
        chart.pullback(q, g, pulled);
        for (int c = 0; c < n; ++c) {
          typename C::Point plus = q, minus = q;
          const Scalar h = step(q[c]);
          plus[c] += h;
          minus[c] -= h;
          chart.embed(plus, xp);
          chart.embed(minus, xm);
          const Scalar fd = (xp[a] - xm[a]) / (Scalar(2) * h);
          ++out.checked;
          if (abs(pulled[c] - fd) > tolerance * scale) {
            std::ostringstream what;
            what << "pullback: (J^T e_" << a + 1 << ")_" << c + 1 << " = " << pulled[c]
                 << ", central difference of embed " << fd;
            fail(sample, what.str());
          }
        }
      }
    }
  }
  return out;
}

}  // namespace sesi
