#include "ranks.hpp"

#include <algorithm>
#include <climits>
#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <vector>

#include "launcher.hpp"

#ifdef SESI_HAVE_MPI
#include <mpi.h>
#endif

namespace sesi::program {

namespace launcher {

namespace {
/// Set in the environment of a sweep's runs (mark_children_not_ranks).
constexpr const char* not_a_rank = "SESI_NOT_AN_MPI_RANK";
}  // namespace

bool started_by_mpi() {
  for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_RANK", "PMI_SIZE"}) {
    if (std::getenv(name) != nullptr) return true;
  }
  return false;
}

long processes() {
  long most = 1;
  for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "SLURM_STEP_NUM_TASKS"}) {
    if (const char* value = std::getenv(name)) most = std::max(most, std::strtol(value, nullptr, 10));
  }
  return most;
}

void mark_children_not_ranks() { ::setenv(not_a_rank, "1", 1); }

bool marked_not_a_rank() { return std::getenv(not_a_rank) != nullptr; }

}  // namespace launcher

long Ranks::launched_processes() { return launcher::marked_not_a_rank() ? 1 : launcher::processes(); }

#ifdef SESI_HAVE_MPI

namespace {

/// An MPI count: the library's counts are ints (more than 2^31 - 1 doubles to one rank, 16 GiB,
/// is refused rather than wrapped).
int count_of(std::size_t n) {
  if (n > static_cast<std::size_t>(INT_MAX)) throw std::length_error("sesi: a message to an MPI rank over 2^31 values");
  return static_cast<int>(n);
}

/// Offsets of blocks of these counts laid end to end.
void offsets(const std::vector<int>& counts, std::vector<int>& displacements) {
  displacements.resize(counts.size());
  long at = 0;
  for (std::size_t r = 0; r < counts.size(); ++r) {
    displacements[r] = count_of(static_cast<std::size_t>(at));
    at += counts[r];
  }
  static_cast<void>(count_of(static_cast<std::size_t>(at)));
}

/// Each rank's doubles, in rank order, to rank 0 (everyone false: MPI_Gatherv) or to every rank
/// (MPI_Allgatherv), with each rank's count; elsewhere all and counts are left empty.
void gather_doubles(int size, bool root, bool everyone, const std::vector<double>& mine, std::vector<double>& all,
                    std::vector<int>& counts) {
  if (size < 2) {
    all = mine;
    counts.assign(1, count_of(mine.size()));
    return;
  }
  const bool receives = everyone || root;
  const int n = count_of(mine.size());
  if (receives) {
    counts.resize(static_cast<std::size_t>(size));
  } else {
    counts.clear();
  }
  static thread_local std::vector<int> displacements;
  if (everyone) {
    MPI_Allgather(&n, 1, MPI_INT, counts.data(), 1, MPI_INT, MPI_COMM_WORLD);
  } else {
    MPI_Gather(&n, 1, MPI_INT, counts.data(), 1, MPI_INT, 0, MPI_COMM_WORLD);
  }
  if (receives) {
    offsets(counts, displacements);
    all.resize(static_cast<std::size_t>(displacements.back()) + static_cast<std::size_t>(counts.back()));
  } else {
    all.clear();
  }
  if (everyone) {
    MPI_Allgatherv(mine.data(), n, MPI_DOUBLE, all.data(), counts.data(), displacements.data(), MPI_DOUBLE,
                   MPI_COMM_WORLD);
  } else {
    MPI_Gatherv(mine.data(), n, MPI_DOUBLE, all.data(), counts.data(), displacements.data(), MPI_DOUBLE, 0,
                MPI_COMM_WORLD);
  }
}

}  // namespace

Ranks Ranks::start() {
  Ranks ranks;
  if (launcher::marked_not_a_rank() || !launcher::started_by_mpi()) return ranks;
  int initialised = 0;
  MPI_Initialized(&initialised);
  if (!initialised) {
    // Threads (OpenMP) run inside a rank's steps, but only the thread that runs them calls MPI.
    int provided = 0;
    MPI_Init_thread(nullptr, nullptr, MPI_THREAD_FUNNELED, &provided);
    ranks.mpi_ = true;
  }
  MPI_Comm_rank(MPI_COMM_WORLD, &ranks.rank_);
  MPI_Comm_size(MPI_COMM_WORLD, &ranks.size_);
  return ranks;
}

Ranks::~Ranks() {
  if (mpi_) MPI_Finalize();
}

bool Ranks::available() { return true; }

bool Ranks::any(bool value) const {
  if (size_ < 2) return value;
  int mine = value ? 1 : 0, out = 0;
  MPI_Allreduce(&mine, &out, 1, MPI_INT, MPI_LOR, MPI_COMM_WORLD);
  return out != 0;
}

double Ranks::max(double value) const {
  if (size_ < 2) return value;
  double out = value;
  MPI_Allreduce(&value, &out, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
  return out;
}

long Ranks::min(long value) const {
  if (size_ < 2) return value;
  long out = value;
  MPI_Allreduce(&value, &out, 1, MPI_LONG, MPI_MIN, MPI_COMM_WORLD);
  return out;
}

bool Ranks::from_root(bool value) const {
  if (size_ < 2) return value;
  int v = value ? 1 : 0;
  MPI_Bcast(&v, 1, MPI_INT, 0, MPI_COMM_WORLD);
  return v != 0;
}

long Ranks::from_root(long value) const {
  if (size_ >= 2) MPI_Bcast(&value, 1, MPI_LONG, 0, MPI_COMM_WORLD);
  return value;
}

double Ranks::from_root(double value) const {
  if (size_ >= 2) MPI_Bcast(&value, 1, MPI_DOUBLE, 0, MPI_COMM_WORLD);
  return value;
}

void Ranks::from_root(std::vector<double>& values) const {
  if (size_ < 2) return;
  long n = from_root(static_cast<long>(values.size()));
  values.resize(static_cast<std::size_t>(n));
  MPI_Bcast(values.data(), count_of(values.size()), MPI_DOUBLE, 0, MPI_COMM_WORLD);
}

void Ranks::from_root(std::string& text) const {
  if (size_ < 2) return;
  long n = from_root(static_cast<long>(text.size()));
  text.resize(static_cast<std::size_t>(n));
  MPI_Bcast(text.data(), count_of(text.size()), MPI_CHAR, 0, MPI_COMM_WORLD);
}

void Ranks::gather(const std::vector<double>& mine, std::vector<double>& all, std::vector<int>& counts) const {
  gather_doubles(size_, root(), false, mine, all, counts);
}

void Ranks::all_gather(const std::vector<double>& mine, std::vector<double>& all, std::vector<int>& counts) const {
  gather_doubles(size_, root(), true, mine, all, counts);
}

void Ranks::exchange(const std::vector<std::vector<double>>& send, std::vector<std::vector<double>>& received) const {
  if (send.size() != static_cast<std::size_t>(size_)) {
    throw std::logic_error("Ranks::exchange: one block per rank expected");
  }
  received.resize(static_cast<std::size_t>(size_));
  if (size_ < 2) {
    received[0] = send[0];
    return;
  }
  // Kept between calls (one exchange a step): no allocation once they have grown.
  static thread_local std::vector<int> send_counts, receive_counts, send_offsets, receive_offsets;
  static thread_local std::vector<double> outgoing, incoming;
  const auto ranks = static_cast<std::size_t>(size_);
  send_counts.resize(ranks);
  receive_counts.resize(ranks);
  for (std::size_t r = 0; r < ranks; ++r) send_counts[r] = count_of(send[r].size());
  MPI_Alltoall(send_counts.data(), 1, MPI_INT, receive_counts.data(), 1, MPI_INT, MPI_COMM_WORLD);
  offsets(send_counts, send_offsets);
  offsets(receive_counts, receive_offsets);
  outgoing.resize(static_cast<std::size_t>(send_offsets.back()) + static_cast<std::size_t>(send_counts.back()));
  incoming.resize(static_cast<std::size_t>(receive_offsets.back()) +
                  static_cast<std::size_t>(receive_counts.back()));
  for (std::size_t r = 0; r < ranks; ++r) {
    std::copy(send[r].begin(), send[r].end(), outgoing.begin() + send_offsets[r]);
  }
  MPI_Alltoallv(outgoing.data(), send_counts.data(), send_offsets.data(), MPI_DOUBLE, incoming.data(),
                receive_counts.data(), receive_offsets.data(), MPI_DOUBLE, MPI_COMM_WORLD);
  for (std::size_t r = 0; r < ranks; ++r) {
    const auto from = incoming.begin() + receive_offsets[r];
    received[r].assign(from, from + receive_counts[r]);
  }
  // A domain's cut sends every body's state once (0.1 GB at 10^6 bodies); the halo exchanges of
  // each step, a small part of it: the buffers do not keep a cut's size.
  constexpr std::size_t kept = std::size_t{1} << 20;  // doubles (8 MB)
  if (outgoing.capacity() > kept) std::vector<double>().swap(outgoing);
  if (incoming.capacity() > kept) std::vector<double>().swap(incoming);
}

void Ranks::abort(int status) const {
  std::fflush(stdout);
  std::fflush(stderr);
  if (size_ >= 2) MPI_Abort(MPI_COMM_WORLD, status);
  std::exit(status);
}

#else  // one process: every call a copy

Ranks Ranks::start() { return Ranks(); }
Ranks::~Ranks() = default;
bool Ranks::available() { return false; }
bool Ranks::any(bool value) const { return value; }
double Ranks::max(double value) const { return value; }
long Ranks::min(long value) const { return value; }
bool Ranks::from_root(bool value) const { return value; }
long Ranks::from_root(long value) const { return value; }
double Ranks::from_root(double value) const { return value; }
void Ranks::from_root(std::vector<double>&) const {}
void Ranks::from_root(std::string&) const {}

void Ranks::gather(const std::vector<double>& mine, std::vector<double>& all, std::vector<int>& counts) const {
  all = mine;
  counts.assign(1, static_cast<int>(mine.size()));
}

void Ranks::all_gather(const std::vector<double>& mine, std::vector<double>& all, std::vector<int>& counts) const {
  all = mine;
  counts.assign(1, static_cast<int>(mine.size()));
}

void Ranks::exchange(const std::vector<std::vector<double>>& send, std::vector<std::vector<double>>& received) const {
  if (send.size() != 1) throw std::logic_error("Ranks::exchange: one block per rank expected");
  received.resize(1);
  received[0] = send[0];
}

void Ranks::abort(int status) const {
  std::fflush(stdout);
  std::fflush(stderr);
  std::exit(status);
}

#endif

Ranks::Ranks(Ranks&& other) noexcept : rank_(other.rank_), size_(other.size_), mpi_(other.mpi_) {
  other.rank_ = 0;
  other.size_ = 1;
  other.mpi_ = false;
}

}  // namespace sesi::program
