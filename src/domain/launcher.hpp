#pragma once
/// @file launcher.hpp
/// What the environment says of the launcher (mpirun, srun, Hydra) that started this process:
/// shared by `sesi run` across ranks (ranks.hpp) and `sesi sweep` (sweep_comm.hpp); defined in
/// ranks.cpp.

namespace sesi::program::launcher {

/// Whether a launcher started this process as one rank of several: Open MPI's mpirun, or a
/// PMI/PMIx launcher (srun --mpi=pmix, Hydra). Started by hand, sesi does not initialise MPI (no
/// singleton start of Open MPI's runtime).
bool started_by_mpi();
/// How many processes the launcher started with this one, as its environment says (1: none).
long processes();
/// Mark the processes this one starts (a sweep's `sesi run` children, which inherit the
/// launcher's environment) as no MPI ranks: Ranks::start() then keeps them to one process each.
void mark_children_not_ranks();
/// Whether this process was started so marked.
bool marked_not_a_rank();

}  // namespace sesi::program::launcher
