#pragma once
/// @file sweep_comm.hpp
/// The processes of a sweep: MPI's world when the program is built with MPI (SESI_BUILD_MPI)
/// and started by a launcher (mpirun, srun), else this process alone. Rank 0 hands out run
/// indices one at a time and collects each run's result; the other ranks run what they get.
///
/// Messages (MPI_COMM_WORLD): rank 0 sends a worker an index (tag_work, one long; -1: no more
/// work), the worker answers with its run's marker text (tag_result, chars) and waits for the
/// next index.

#include <optional>
#include <string>
#include <utility>

namespace sesi::program {

class SweepComm {
 public:
  /// MPI_Init when the program was started by an MPI launcher; nothing otherwise.
  SweepComm();
  /// MPI_Finalize.
  ~SweepComm();
  SweepComm(const SweepComm&) = delete;
  SweepComm& operator=(const SweepComm&) = delete;

  int rank() const { return rank_; }
  int size() const { return size_; }
  /// Whether MPI is in use (false: one process, size 1).
  bool mpi() const { return mpi_; }

  /// The largest of every rank's value (all ranks call it).
  int max_over_ranks(int value) const;
  /// Rank 0's value on every rank (all ranks call it).
  int from_rank0(int value) const;

  /// Rank 0: give worker `rank` run `index` (-1: stop).
  void send_index(int rank, long index) const;
  /// Rank 0: a worker's answer, if one has arrived (does not wait): its rank and text.
  std::optional<std::pair<int, std::string>> poll_result() const;
  /// A worker: the next run index from rank 0 (-1: stop). Waits without spinning.
  long receive_index() const;
  /// A worker: answer rank 0.
  void send_result(const std::string& text) const;

  /// How many processes a launcher (mpirun, srun) started with this one, as its environment
  /// says (1 when none did): a sesi built without MPI refuses to run a sweep several times.
  static long launched_processes();

  /// End every rank at once (after an internal error on one rank).
  [[noreturn]] void abort(int status) const;

 private:
  int rank_ = 0, size_ = 1;
  bool mpi_ = false;
};

}  // namespace sesi::program
