#include "sweep_command.hpp"

#include <chrono>
#include <cstdio>
#include <deque>
#include <exception>
#include <thread>
#include <vector>

#include <sched.h>

#include "errors.hpp"
#include "signals.hpp"
#include "sweep_comm.hpp"
#include "sweep_file.hpp"
#include "sweep_runs.hpp"

namespace sesi::program {

namespace fs = std::filesystem;

namespace {

using Clock = std::chrono::steady_clock;

long cores() {
  cpu_set_t set;
  if (sched_getaffinity(0, sizeof set, &set) == 0) return std::max(1, CPU_COUNT(&set));
  return std::max(1U, std::thread::hardware_concurrency());
}

void pause() { std::this_thread::sleep_for(std::chrono::milliseconds(2)); }

/// Rank 0: hand out the runs not done yet to its own run processes and to the other ranks,
/// record each result as it comes, keep sweep.csv up to date.
class Dispatcher {
 public:
  Dispatcher(const Sweep& sweep, SweepDir& dir, const SweepComm& comm, long slots, bool quiet)
      : sweep_(sweep), dir_(dir), comm_(comm), slots_(slots), quiet_(quiet), host_(host_name()) {}

  int run() {
    const std::size_t total = sweep_.variants.size();
    results_.resize(total);
    for (std::size_t i = 0; i < total; ++i) {
      results_[i].index = static_cast<long>(i);
      if (dir_.done()[i]) {
        results_[i] = *dir_.done()[i];
        ++skipped_;
      } else {
        queue_.push_back(static_cast<long>(i));
      }
    }
    dir_.write_csv(results_);
    if (!quiet_) {
      std::printf("sesi sweep: %zu runs into %s (%zu done before, skipped); %ld at a time here%s\n", total,
                  dir_.path().string().c_str(), skipped_, slots_,
                  comm_.size() > 1 ? (" and 1 on each of " + std::to_string(comm_.size() - 1) + " more ranks").c_str()
                                   : "");
      std::fflush(stdout);
    }
    std::vector<bool> idle(static_cast<std::size_t>(comm_.size()), true), stopped(idle.size(), false);
    int busy_ranks = 0;
    auto last_csv = Clock::now();
    bool dirty = false;
    while (true) {
      if (signals::stop_requested().load() && !stopping_) stop_all();
      for (int r = 1; r < comm_.size(); ++r) {
        if (!idle[r] || stopped[r]) continue;
        if (queue_.empty() || stopping_) {
          comm_.send_index(r, -1);  // no more work: the rank ends (and does not wait spinning)
          stopped[r] = true;
        } else {
          comm_.send_index(r, queue_.front());
          queue_.pop_front();
          idle[r] = false;
          ++busy_ranks;
        }
      }
      while (!stopping_ && !queue_.empty() && static_cast<long>(running_.size()) < slots_) {
        const Variant& variant = sweep_.variants[static_cast<std::size_t>(queue_.front())];
        queue_.pop_front();
        running_.emplace_back(dir_.path(), sweep_, variant, !variant.sets_threads);
      }
      bool progress = false;
      for (std::size_t k = 0; k < running_.size();) {
        if (!running_[k].poll()) {
          ++k;
          continue;
        }
        record(running_[k].finish(0, host_));
        running_.erase(running_.begin() + static_cast<std::ptrdiff_t>(k));
        progress = dirty = true;
      }
      while (auto message = comm_.poll_result()) {
        const std::optional<RunResult> result = parse_marker(message->second);
        if (!result || result->index < 0 || result->index >= static_cast<long>(total)) {
          throw std::runtime_error("a bad answer from rank " + std::to_string(message->first));
        }
        record(*result);
        idle[static_cast<std::size_t>(message->first)] = true;
        --busy_ranks;
        progress = dirty = true;
      }
      const bool all_stopped = std::all_of(stopped.begin() + 1, stopped.end(), [](bool s) { return s; });
      if (running_.empty() && busy_ranks == 0 && (queue_.empty() || stopping_) && all_stopped) break;
      if (dirty && Clock::now() - last_csv > std::chrono::seconds(1)) {
        dir_.write_csv(results_);
        last_csv = Clock::now();
        dirty = false;
      }
      if (!progress) pause();
    }
    dir_.write_csv(results_);
    const int status = stopping_ ? exit_interrupted : sweep_status(results_);
    report(status);
    return status;
  }

 private:
  void stop_all() {
    stopping_ = true;
    for (RunProcess& run : running_) run.stop();
  }

  void record(const RunResult& result) {
    results_[static_cast<std::size_t>(result.index)] = result;
    if (result.status == "interrupted") {
      results_[static_cast<std::size_t>(result.index)] = RunResult{};
      results_[static_cast<std::size_t>(result.index)].index = result.index;
      if (!stopping_) stop_all();
      return;
    }
    if (quiet_) return;
    const std::string name = run_name(result.index, static_cast<long>(sweep_.variants.size()));
    std::string line = "run " + name + ": " + result.status;
    if (result.status == "ok") {
      line += ", max energy error " + (result.max_energy_error.empty() ? "-" : result.max_energy_error);
    } else {
      line += " (exit " + std::to_string(result.exit_status) + "): " + result.message;
    }
    char wall[48];
    std::snprintf(wall, sizeof wall, ", %.3f s", result.wall_seconds);
    line += std::string(wall) + " (rank " + std::to_string(result.rank) + ", " + result.host + ")";
    std::printf("%s\n", line.c_str());
    std::fflush(stdout);
  }

  void report(int status) const {
    std::size_t ok = 0, failed = 0, errors = 0, pending = 0;
    for (const RunResult& r : results_) {
      ok += r.status == "ok";
      failed += r.status == "failed";
      errors += r.status == "error";
      pending += r.status == "pending";
    }
    const std::string csv = (dir_.path() / "sweep.csv").string();
    if (status == exit_interrupted) {
      print_error("sweep interrupted: " + std::to_string(pending) +
                  " runs not done (not kept); run the same command again to do them; " + csv);
    } else if (status != exit_ok) {
      print_error("sweep: " + std::to_string(failed) + " runs failed (exit 3) and " + std::to_string(errors) +
                  " ended in an error, of " + std::to_string(results_.size()) + "; each run's message is in " + csv +
                  " and its log.txt");
    }
    if (!quiet_) {
      std::printf("sesi sweep: %zu runs: %zu ok, %zu failed, %zu errors, %zu not done; %zu skipped (done before); %s\n",
                  results_.size(), ok, failed, errors, pending, skipped_, csv.c_str());
      std::fflush(stdout);
    }
  }

  const Sweep& sweep_;
  SweepDir& dir_;
  const SweepComm& comm_;
  long slots_;
  bool quiet_;
  std::string host_;
  std::vector<RunResult> results_;
  std::deque<long> queue_;
  std::vector<RunProcess> running_;
  std::size_t skipped_ = 0;
  bool stopping_ = false;
};

/// A rank other than 0: run what rank 0 hands out, one at a time, until it says stop.
void work(const Sweep& sweep, const fs::path& dir, const SweepComm& comm) {
  const std::string host = host_name();
  while (true) {
    const long index = comm.receive_index();
    if (index < 0) return;
    const Variant& variant = sweep.variants.at(static_cast<std::size_t>(index));
    RunProcess run(dir, sweep, variant, !variant.sets_threads);
    while (!run.poll()) {
      if (signals::stop_requested().load()) run.stop();
      pause();
    }
    comm.send_result(marker_text(run.finish(comm.rank(), host)));
  }
}

}  // namespace

CLI::App* add_sweep_subcommand(CLI::App& app, SweepOptions& options) {
  CLI::App* s = app.add_subcommand(
      "sweep", "Run every variant of a scene that a sweep file describes, in parallel (MPI across machines).");
  s->add_option("SWEEP", options.file, "Sweep file (TOML, docs/sweeps.md): a base scene and [[vary]] tables.")
      ->type_name("FILE")
      ->required();
  s->add_option("--out,-o", options.out,
                "Output directory (default ./sesi-out/<sweep name>): sweep.csv and runs/NNNN/. A rerun into it "
                "skips the runs already done.")
      ->type_name("DIR");
  s->add_option("--jobs,-j", options.jobs,
                "Runs at a time in this process, >= 1 (default: the cores here; under mpirun with several "
                "ranks, 0 on rank 0 and 1 on each other rank).")
      ->type_name("N");
  s->add_flag("--quiet,-q", options.quiet, "No line per run on stdout.");
  s->add_flag("--check", options.check, "Check the sweep file and every variant, print the number of runs; run nothing.");
  s->footer(
      "\nEach run is `sesi run` of its scene (DIR/runs/NNNN/scene.toml); its outputs, log.txt and its row\n"
      "(sweep-run.toml) go to DIR/runs/NNNN when it ends; DIR/sweep.csv has one row per run.\n"
      "Across machines: mpirun -np K sesi sweep SWEEP.toml --out DIR (or srun); rank 0 hands out the runs.\n"
      "\nEXIT STATUS:\n"
      "  0 every run done;  2 bad sweep file, scene, variant or DIR (one line on stderr, nothing run);\n"
      "  3 some run failed with exit status 3 (recorded in sweep.csv; the others ran);\n"
      "  1 some run ended otherwise (an internal error, killed);\n"
      "  130 interrupted by a signal: the runs not done are redone by the same command.\n");
  return s;
}

int sweep_command(const SweepOptions& options) {
  SweepComm comm;
  int status = exit_ok;
  std::string error;
  std::optional<Sweep> sweep;
  std::optional<SweepDir> dir;
  const fs::path out =
      options.out.empty() ? fs::path("sesi-out") / fs::path(options.file).stem() : fs::path(options.out);
  try {
    if (options.jobs && *options.jobs < 1) throw InputError(Origin{}, "--jobs", "expected an integer >= 1");
    if (!comm.mpi() && SweepComm::launched_processes() > 1) {
      throw InputError(Origin{}, "sweep",
                       "started as one of " + std::to_string(SweepComm::launched_processes()) +
                           " processes (mpirun, srun) without MPI in use (a sesi built without MPI: "
                           "SESI_BUILD_MPI, libopenmpi-dev; or srun without --mpi=pmix), so each would run "
                           "the whole sweep; start one process, or use an MPI build");
    }
    sweep = read_sweep_file(options.file);
    if (comm.rank() == 0 && !options.check) dir.emplace(out, *sweep);
  } catch (const InputError& e) {
    error = e.what();
    status = exit_bad_input;
  } catch (const std::exception& e) {
    error = e.what();
    status = exit_internal;
  }
  // Every rank has read the sweep: stop together if any failed (only one message: rank 0's,
  // else the failing rank's).
  const int rank0_status = comm.from_rank0(status);
  const int worst = comm.max_over_ranks(status);
  if (worst != exit_ok) {
    if (status != exit_ok && (comm.rank() == 0 || rank0_status == exit_ok)) {
      print_error(comm.rank() == 0 ? error : "rank " + std::to_string(comm.rank()) + ": " + error);
    }
    return worst;
  }

  if (options.check) {
    if (comm.rank() == 0) {
      std::printf("%s: %zu runs, every variant a valid scene\n", options.file.c_str(), sweep->variants.size());
    }
    return exit_ok;
  }
  signals::begin_run();  // from here a signal stops the sweep between runs (and its running runs)
  try {
    if (comm.rank() > 0) {
      work(*sweep, out, comm);
      return exit_ok;
    }
    const long slots = options.jobs ? *options.jobs : comm.size() > 1 ? 0 : cores();
    return Dispatcher(*sweep, *dir, comm, slots, options.quiet).run();
  } catch (const std::exception& e) {
    print_error(std::string("sweep: ") + e.what());
    if (comm.size() > 1) comm.abort(exit_internal);
    return exit_internal;
  }
}

}  // namespace sesi::program
