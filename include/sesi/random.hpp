#pragma once
/// @file random.hpp
/// Counter-based normal random numbers for the thermostats (issue #25; docs/thermostats.md).
///
/// Every number is a pure function of its key (seed, stream, step, body, component): no
/// generator state exists, so a thermostatted run is bit-identical for any thread count, in any
/// order of the bodies, and across a resume (a checkpoint needs the seed and the step only).
///
/// Generator: Philox4x64-10 of Random123 (Salmon, Moraes, Dror and Shaw, "Parallel random
/// numbers: as easy as 1, 2, 3", SC'11, 2011), counter (step, body, component / 2, 0) and key
/// (seed, stream). Normals: the Box-Muller transform (Box and Muller, Ann. Math. Statist. 29,
/// 610, 1958) of the first two output words, r123::boxmuller: z = sqrt(-2 log u1) (sin, cos)(pi u0)
/// with u1 = r123::u01(w1) in (0, 1] (never 0, so the logarithm is finite: |z| < 9.5) and
/// u0 = r123::uneg11(w0) in [-1, 1]. Components 2j and 2j+1 are the two normals of one Philox call.
///
/// Chi-squared and gamma variates (the CSVR thermostat's sum of squared normals, thermostats/csvr.hpp):
/// gamma_variate() by Marsaglia and Tsang's rejection method ("A simple method for generating gamma
/// variables", ACM TOMS 26(3), 363-372, 2000), every attempt its own Philox call, so the value is a
/// pure function of its key like the normals; chi_squared() as the exact sum of squared normals for
/// a small integer number of degrees of freedom, 2 gamma_variate(dof / 2) above.
///
/// Requires Random123's headers (Debian: librandom123-dev; header-only). The core library does
/// not: sesi/sesi.hpp leaves this header and thermostat.hpp out; include sesi/thermostat.hpp.

#include <array>
#include <cmath>
#include <cstdint>

#include <Random123/boxmuller.hpp>
#include <Random123/philox.h>
#include <Random123/uniform.hpp>

namespace sesi::random {

/// Streams: the second key word, so that one seed gives independent numbers to each use
/// (the Langevin thermostat's noise, a sweep's seeded perturbations, ...).
namespace stream {
inline constexpr std::uint64_t langevin = 0x4c414e4745564e31ULL;      // "LANGEVN1"
inline constexpr std::uint64_t perturbation = 0x5045525455524231ULL;  // "PERTURB1"
inline constexpr std::uint64_t csvr = 0x4353565252455331ULL;          // "CSVRRES1"
}  // namespace stream

/// Two independent standard normals, keyed by (seed, stream, step, body, pair): the normals of
/// components 2 pair and 2 pair + 1.
inline std::array<double, 2> normal_pair(std::uint64_t seed, std::uint64_t stream, std::uint64_t step,
                                         std::uint64_t body, std::uint64_t pair) {
  using Philox = r123::Philox4x64;
  const Philox::ctr_type counter = {{step, body, pair, 0}};
  const Philox::key_type key = {{seed, stream}};
  const Philox::ctr_type words = Philox()(counter, key);
  const r123::double2 z = r123::boxmuller(words[0], words[1]);
  return {z.x, z.y};
}

/// One standard normal, keyed by (seed, stream, step, body, component): the same number as
/// normal_pair(seed, stream, step, body, component / 2)[component % 2], whenever and in whatever
/// order it is asked for.
inline double normal(std::uint64_t seed, std::uint64_t stream, std::uint64_t step, std::uint64_t body,
                     std::uint64_t component) {
  return normal_pair(seed, stream, step, body, component / 2)[component % 2];
}

namespace detail {
/// The four Philox words of counter (step, body, component, word) under key (seed, stream).
inline r123::Philox4x64::ctr_type philox_words(std::uint64_t seed, std::uint64_t stream, std::uint64_t step,
                                               std::uint64_t body, std::uint64_t component, std::uint64_t word) {
  using Philox = r123::Philox4x64;
  const Philox::ctr_type counter = {{step, body, component, word}};
  const Philox::key_type key = {{seed, stream}};
  return Philox()(counter, key);
}
}  // namespace detail

/// The most attempts gamma_variate() makes. Marsaglia and Tsang's acceptance rate is at least 0.95
/// for every shape >= 1 (0.951 at shape 1, rising with the shape), so all 64 attempts fail with
/// probability below 0.05^64 < 1e-83; then the mean (the shape) is returned, still a pure function
/// of the key.
inline constexpr int gamma_max_attempts = 64;

/// A Gamma(shape, 1) variate (density x^(shape-1) e^-x / Gamma(shape)), shape > 0, keyed by
/// (seed, stream, step, body, component). Attempt j uses the Philox counter (step, body,
/// component, 1 + j): its first two words give the normal x (Box-Muller), the third the uniform u
/// in (0, 1], the fourth (shape < 1 only) the uniform of the boost Gamma(a) = Gamma(a + 1) u^(1/a)
/// (Marsaglia and Tsang 2000). The fourth counter word is >= 1, so within one stream these
/// numbers never share a Philox call with normal_pair (fourth word 0).
inline double gamma_variate(double shape, std::uint64_t seed, std::uint64_t stream, std::uint64_t step,
                            std::uint64_t body, std::uint64_t component) {
  const bool boost = shape < 1;
  const double d = (boost ? shape + 1 : shape) - 1.0 / 3.0;
  const double c = 1 / std::sqrt(9 * d);
  for (int j = 0; j < gamma_max_attempts; ++j) {
    const auto w = detail::philox_words(seed, stream, step, body, component, 1 + static_cast<std::uint64_t>(j));
    const double x = r123::boxmuller(w[0], w[1]).x;
    const double t = 1 + c * x;
    if (t <= 0) continue;
    const double v = t * t * t;
    const double u = r123::u01<double>(w[2]);  // (0, 1]: log u is finite
    const double x2 = x * x;
    // The squeeze first (no logarithm), then the exact test (Marsaglia and Tsang 2000).
    if (u < 1 - 0.0331 * x2 * x2 || std::log(u) < x2 / 2 + d * (1 - v + std::log(v))) {
      const double g = d * v;
      return boost ? g * std::pow(r123::u01<double>(w[3]), 1 / shape) : g;
    }
  }
  return shape;
}

/// The largest number of degrees of freedom that chi_squared() draws as an exact sum of squares.
inline constexpr double chi_squared_exact_dof = 16;

/// A chi-squared variate with dof >= 0 degrees of freedom, keyed by (seed, stream, step, body,
/// component): 0 for dof = 0; for an integer dof <= chi_squared_exact_dof the sum of dof squared
/// normals, the two normals of Philox counter (step, body, component, 1 + j) for j = 0, 1, ...;
/// else 2 gamma_variate(dof / 2) with the same key (chi-squared(k) = 2 Gamma(k/2, 1)).
inline double chi_squared(double dof, std::uint64_t seed, std::uint64_t stream, std::uint64_t step,
                          std::uint64_t body, std::uint64_t component) {
  if (!(dof > 0)) return 0;
  if (dof <= chi_squared_exact_dof && dof == std::floor(dof)) {
    const auto n = static_cast<std::uint64_t>(dof);
    double sum = 0;
    for (std::uint64_t j = 0; 2 * j < n; ++j) {
      const auto w = detail::philox_words(seed, stream, step, body, component, 1 + j);
      const r123::double2 z = r123::boxmuller(w[0], w[1]);
      sum += z.x * z.x;
      if (2 * j + 1 < n) sum += z.y * z.y;
    }
    return sum;
  }
  return 2 * gamma_variate(dof / 2, seed, stream, step, body, component);
}

}  // namespace sesi::random
