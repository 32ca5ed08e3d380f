#include "sweep_comm.hpp"

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <thread>
#include <vector>

#include "launcher.hpp"

#ifdef SESI_HAVE_MPI
#include <mpi.h>
#endif

namespace sesi::program {

long SweepComm::launched_processes() { return launcher::processes(); }

#ifdef SESI_HAVE_MPI

namespace {

constexpr int tag_work = 1;
constexpr int tag_result = 2;

/// Wait for a message without spinning: Open MPI's blocking receive polls at full speed, and
/// would take a core from the runs.
MPI_Status wait_for(int source, int tag) {
  MPI_Status status;
  int flag = 0;
  auto pause = std::chrono::microseconds(50);
  while (true) {
    MPI_Iprobe(source, tag, MPI_COMM_WORLD, &flag, &status);
    if (flag) return status;
    std::this_thread::sleep_for(pause);
    if (pause < std::chrono::milliseconds(5)) pause *= 2;
  }
}

}  // namespace

SweepComm::SweepComm() {
  // The runs this sweep starts inherit the launcher's environment: they are no ranks of it.
  launcher::mark_children_not_ranks();
  // Started by hand (launcher::started_by_mpi), the sweep runs on this machine alone.
  if (!launcher::started_by_mpi()) return;
  int initialised = 0;
  MPI_Initialized(&initialised);
  if (!initialised) MPI_Init(nullptr, nullptr);
  MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
  MPI_Comm_size(MPI_COMM_WORLD, &size_);
  mpi_ = true;
}

SweepComm::~SweepComm() {
  if (mpi_) MPI_Finalize();
}

int SweepComm::max_over_ranks(int value) const {
  if (!mpi_) return value;
  int out = value;
  MPI_Allreduce(&value, &out, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
  return out;
}

int SweepComm::from_rank0(int value) const {
  if (mpi_) MPI_Bcast(&value, 1, MPI_INT, 0, MPI_COMM_WORLD);
  return value;
}

void SweepComm::send_index(int rank, long index) const {
  MPI_Send(&index, 1, MPI_LONG, rank, tag_work, MPI_COMM_WORLD);
}

std::optional<std::pair<int, std::string>> SweepComm::poll_result() const {
  if (!mpi_ || size_ < 2) return std::nullopt;
  int flag = 0;
  MPI_Status status;
  MPI_Iprobe(MPI_ANY_SOURCE, tag_result, MPI_COMM_WORLD, &flag, &status);
  if (!flag) return std::nullopt;
  int count = 0;
  MPI_Get_count(&status, MPI_CHAR, &count);
  std::string text(static_cast<std::size_t>(count), '\0');
  MPI_Recv(text.data(), count, MPI_CHAR, status.MPI_SOURCE, tag_result, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
  return std::pair{status.MPI_SOURCE, std::move(text)};
}

long SweepComm::receive_index() const {
  (void)wait_for(0, tag_work);
  long index = -1;
  MPI_Recv(&index, 1, MPI_LONG, 0, tag_work, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
  return index;
}

void SweepComm::send_result(const std::string& text) const {
  MPI_Send(text.data(), static_cast<int>(text.size()), MPI_CHAR, 0, tag_result, MPI_COMM_WORLD);
}

void SweepComm::abort(int status) const {
  if (mpi_) MPI_Abort(MPI_COMM_WORLD, status);
  std::exit(status);
}

#else  // one process

SweepComm::SweepComm() { launcher::mark_children_not_ranks(); }  // as above
SweepComm::~SweepComm() = default;
int SweepComm::max_over_ranks(int value) const { return value; }
int SweepComm::from_rank0(int value) const { return value; }
void SweepComm::send_index(int, long) const {}
std::optional<std::pair<int, std::string>> SweepComm::poll_result() const { return std::nullopt; }
long SweepComm::receive_index() const { return -1; }
void SweepComm::send_result(const std::string&) const {}
void SweepComm::abort(int status) const { std::exit(status); }

#endif

}  // namespace sesi::program
