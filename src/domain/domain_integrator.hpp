#pragma once
/// @file domain_integrator.hpp
/// One simulation across MPI ranks (`mpirun -np K sesi run SCENE`; docs/parallel.md): spatial
/// domain decomposition (Plimpton, J. Comput. Phys. 117, 1 (1995)). Each rank steps the bodies of
/// its slab of space and holds copies of the bodies within reach of them (its halo), refreshed
/// from their owners after every drift; bodies change rank when the slabs are cut again.
///
/// Results are one process's to the bit, for any number of ranks: a rank holds its bodies and
/// its halo in global body order, so each body's force is summed over the same partners in the
/// same order as in one process (System's rows), and every sum over bodies (the energy's rows,
/// the momentum map) is taken by rank 0 over all bodies in body order.
///
/// The slabs: bodies sorted by one coordinate of their world points (the one of widest extent),
/// cut into K runs of equal count. A rank's halo holds every other body whose coordinate lies
/// within cutoff + 2 skin of its slab (a chord, which bounds the coordinate's difference, is at
/// most the distance). The slabs are cut again, and bodies move to their new ranks, whenever a
/// body has moved more than half the skin since the last cut: until then every pair closer than
/// the cutoff at a force evaluation had been within cutoff + 2 skin at the cut, as long as no
/// body moves more than half the skin in one step (checked after every step: a run that breaks
/// it stops with a message).

#include <memory>

#include "integrator.hpp"
#include "ranks.hpp"
#include "scene.hpp"

namespace sesi::program {

/// The integrator of scene across ranks (ranks.distributed()). Every call on it is collective:
/// every rank makes it, in the same order (docs/parallel.md). Throws InputError (one line) for
/// what a run across ranks does not support yet: a compact surface, a geodesic or processed
/// method, fewer bodies than System::rows_from (256). Pair terms without a cutoff pair each own
/// body with every body of the run (the points of all gathered at every evaluation).
std::unique_ptr<Integrator> make_domain_integrator(const Scene& scene, const Ranks& ranks);

}  // namespace sesi::program
