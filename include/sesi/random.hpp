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
/// Requires Random123's headers (Debian: librandom123-dev; header-only). The core library does
/// not: sesi/sesi.hpp leaves this header and thermostat.hpp out; include sesi/thermostat.hpp.

#include <array>
#include <cstdint>

#include <Random123/boxmuller.hpp>
#include <Random123/philox.h>

namespace sesi::random {

/// Streams: the second key word, so that one seed gives independent numbers to each use
/// (the Langevin thermostat's noise, a sweep's seeded perturbations, ...).
namespace stream {
inline constexpr std::uint64_t langevin = 0x4c414e4745564e31ULL;      // "LANGEVN1"
inline constexpr std::uint64_t perturbation = 0x5045525455524231ULL;  // "PERTURB1"
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

}  // namespace sesi::random
