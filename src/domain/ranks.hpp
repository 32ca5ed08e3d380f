#pragma once
/// @file ranks.hpp
/// The processes of one simulation across MPI ranks (`mpirun -np K sesi run SCENE`,
/// docs/parallel.md): MPI's world when the program is built with MPI (SESI_BUILD_MPI) and started
/// by a launcher with more than one process, else this process alone (rank 0 of 1, every call
/// below then a copy or nothing). Every call is collective: all ranks make it, in the same order.
/// Values travel as doubles (body indices too: exact below 2^53).

#include <string>
#include <vector>

namespace sesi::program {

class Ranks {
 public:
  /// One process, no MPI.
  Ranks() = default;
  /// MPI's world, initialised here, when a launcher (mpirun, srun) started this process as one of
  /// several and the program has MPI; else one process. The launcher's count is
  /// launched_processes().
  static Ranks start();
  /// MPI_Finalize, if start() initialised MPI.
  ~Ranks();
  Ranks(Ranks&& other) noexcept;
  Ranks& operator=(Ranks&&) = delete;
  Ranks(const Ranks&) = delete;
  Ranks& operator=(const Ranks&) = delete;

  int rank() const { return rank_; }
  int size() const { return size_; }
  bool root() const { return rank_ == 0; }
  /// Whether several ranks share the simulation (size() > 1).
  bool distributed() const { return size_ > 1; }
  /// Whether this program was built with MPI.
  static bool available();
  /// How many processes a launcher started with this one, as its environment says (1: none).
  static long launched_processes();

  /// Whether any rank's value is true.
  bool any(bool value) const;
  double max(double value) const;
  long min(long value) const;
  /// Rank 0's value on every rank.
  bool from_root(bool value) const;
  long from_root(long value) const;
  double from_root(double value) const;
  void from_root(std::vector<double>& values) const;
  void from_root(std::string& text) const;

  /// Rank 0 gets every rank's values one after another in rank order (counts: how many from each);
  /// the other ranks get all and counts empty.
  void gather(const std::vector<double>& mine, std::vector<double>& all, std::vector<int>& counts) const;
  /// The same on every rank.
  void all_gather(const std::vector<double>& mine, std::vector<double>& all, std::vector<int>& counts) const;
  /// send[r] goes to rank r; received[r] is what rank r sent here (both of size()).
  void exchange(const std::vector<std::vector<double>>& send, std::vector<std::vector<double>>& received) const;

  /// End every rank at once with status (after an error on one rank that the others cannot see).
  [[noreturn]] void abort(int status) const;

 private:
  int rank_ = 0, size_ = 1;
  bool mpi_ = false;  // MPI initialised by start(), finalised by the destructor
};

}  // namespace sesi::program
