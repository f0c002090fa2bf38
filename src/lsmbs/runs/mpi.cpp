#include "lsmbs/runs/mpi.hpp"

#ifdef __linux__
#include <sched.h>
#endif

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <deque>
#include <mutex>
#include <thread>
#include <vector>

#include "lsmbs/core/error.hpp"
#include "lsmbs/core/interrupt.hpp"

#ifdef LSMBS_HAVE_MPI
#include <mpi.h>
#endif

namespace lsmbs::mpi {
namespace {

World g_world;
bool g_finalized = false;
bool g_lost = false;  // a rank stopped answering: MPI cannot end in order (no MPI_Finalize)

int env_int(const char* name) {
  const char* v = std::getenv(name);
  return v ? std::atoi(v) : 0;
}

}  // namespace

bool built() {
#ifdef LSMBS_HAVE_MPI
  return true;
#else
  return false;
#endif
}

int launched_size() {
  for (const char* v : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_SIZE", "SLURM_NTASKS"})
    if (std::getenv(v) &&
        (std::string(v) != "SLURM_NTASKS" || std::getenv("PMI_RANK") || std::getenv("PMIX_RANK")))
      return env_int(v);
  if (std::getenv("PMIX_RANK")) return 1;  // a PMIx launch that does not say its size here
  return 0;
}

const World& world() { return g_world; }

int conditions_at_once(int sensitivity_threads) {
  return std::max(1, local_threads() / std::max(1, sensitivity_threads));
}

int local_threads() {
  const int cores = std::max(1u, std::thread::hardware_concurrency());
#ifdef __linux__
  // a launcher that binds each rank to its cores (mpirun --bind-to core, srun --cpu-bind) has
  // already shared them out: the process's own CPUs are this rank's
  cpu_set_t set;
  CPU_ZERO(&set);
  if (sched_getaffinity(0, sizeof set, &set) == 0) {
    const int mine = CPU_COUNT(&set);
    if (mine > 0 && mine < cores) return mine;
  }
#endif
  int local = env_int("OMPI_COMM_WORLD_LOCAL_SIZE");
  if (local <= 0) local = env_int("SLURM_NTASKS_PER_NODE");
  if (local <= 0) local = 1;
  return std::max(1, cores / local);
}

#ifndef LSMBS_HAVE_MPI

const World& init(int*, char***) {
  if (launched_size() > 1)
    throw Error(
        "this lsmbs was built without MPI, and an MPI launcher started it as " +
        std::to_string(launched_size()) +
        " processes, which would each run the whole job into the same folder: build with MPI "
        "(Debian's libopenmpi-dev; cmake -DLSMBS_WITH_MPI=ON), or run it without mpirun");
  return g_world;
}
void finalize() {}
ConditionExecutor conditions_executor(int threads) {
  return thread_executor(threads > 0 ? threads : local_threads());
}
std::string broadcast(const std::string& bytes) { return bytes; }

#else  // LSMBS_HAVE_MPI

const World& init(int* argc, char*** argv) {
  if (launched_size() <= 0 || g_world.active) return g_world;
  int provided = 0;
  MPI_Init_thread(argc, argv, MPI_THREAD_FUNNELED, &provided);
  // errors are returned (and reported by the caller), not fatal in MPI's own handler
  MPI_Comm_set_errhandler(MPI_COMM_WORLD, MPI_ERRORS_RETURN);
  MPI_Comm_rank(MPI_COMM_WORLD, &g_world.rank);
  MPI_Comm_size(MPI_COMM_WORLD, &g_world.size);
  g_world.active = true;
  std::atexit([] { finalize(); });
  return g_world;
}

void finalize() {
  if (!g_world.active || g_finalized) return;
  g_finalized = true;
  if (g_lost) return;  // a peer is gone: MPI_Finalize would wait for it
  MPI_Finalize();
}

namespace {

// Waits for a request, polling; a rank that has not delivered half a second after this process
// was interrupted (mpirun ends a job whose rank was killed by signalling the others) is reported
// by rank and condition, and the run ends (Interrupted: the caller flags it, exit 1).
void wait(MPI_Request& req, int from, const std::string& what) {
  int flag = 0;
  std::chrono::steady_clock::time_point since{};
  for (;;) {
    MPI_Test(&req, &flag, MPI_STATUS_IGNORE);
    if (flag) return;
    if (interrupted()) {
      const auto now = std::chrono::steady_clock::now();
      if (since == std::chrono::steady_clock::time_point{}) since = now;
      if (now - since > std::chrono::milliseconds(500)) {
        g_lost = true;
        throw NumericalFailure("MPI rank " + std::to_string(from) + " did not deliver " + what +
                               " (it was killed, or the job is being torn down: mpirun names the "
                               "rank that ended); the run stops here, the checkpoint keeps the "
                               "evaluations before");
      }
    }
    std::this_thread::sleep_for(std::chrono::microseconds(200));
  }
}

// Bytes of rank `root` to every rank (a size, then the bytes).
void bcast_bytes(std::string& bytes, int root, const std::string& what) {
  uint64_t n = bytes.size();
  MPI_Request req;
  MPI_Ibcast(&n, 1, MPI_UINT64_T, root, MPI_COMM_WORLD, &req);
  wait(req, root, what);
  if (g_world.rank != root) bytes.assign(n, '\0');
  if (n == 0) return;
  MPI_Ibcast(bytes.data(), static_cast<int>(n), MPI_BYTE, root, MPI_COMM_WORLD, &req);
  wait(req, root, what);
}

// The first interrupt of any rank, on every rank.
void sync_interrupts() {
  int mine = interrupted(), any = 0;
  MPI_Request req;
  MPI_Iallreduce(&mine, &any, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD, &req);
  wait(req, -1, "the interrupt flags");
  if (any && !interrupted()) interrupt_signal().store(any);
}

}  // namespace

std::string broadcast(const std::string& bytes) {
  if (!g_world.active || g_world.size == 1) return bytes;
  std::string b = bytes;
  bcast_bytes(b, 0, "rank 0's data");
  return b;
}

ConditionExecutor conditions_executor(int threads) {
  if (threads <= 0) threads = local_threads();
  if (!g_world.active || g_world.size == 1) return thread_executor(threads);
  return [threads](const ConditionTasks& t) {
    const int size = g_world.size, rank = g_world.rank;
    const std::vector<int> owner = assign_tasks(t, size);  // the same on every rank
    std::vector<int> mine;
    for (int k = 0; k < t.n; ++k)
      if (owner[static_cast<size_t>(k)] == rank) mine.push_back(k);
    std::vector<std::string> errors(static_cast<size_t>(t.n));
    ConditionTasks local;
    local.n = static_cast<int>(mine.size());
    for (const int k : mine)
      if (!t.cost.empty()) local.cost.push_back(t.cost[static_cast<size_t>(k)]);
    local.run = [&](int i) {
      const int k = mine[static_cast<size_t>(i)];
      try {
        t.run(k);
      } catch (const NumericalFailure& e) {
        errors[static_cast<size_t>(k)] = std::string("N") + e.what();
      } catch (const Error& e) {
        errors[static_cast<size_t>(k)] = std::string("E") + e.what();
      } catch (const std::exception& e) {
        errors[static_cast<size_t>(k)] = std::string("X") + e.what();
      }
    };
    thread_executor(threads)(local);
    std::string first_error;
    for (int k = 0; k < t.n; ++k) {
      const int from = owner[static_cast<size_t>(k)];
      std::string bytes;
      if (rank == from)
        bytes = errors[static_cast<size_t>(k)].empty() ? "R" + t.save(k) : errors[k];
      bcast_bytes(bytes, from, "the result of condition " + std::to_string(k));
      if (bytes.empty()) continue;
      if (bytes[0] == 'R') {
        if (rank != from) t.load(k, bytes.substr(1));
      } else if (first_error.empty()) {
        first_error = bytes;
      }
    }
    sync_interrupts();
    if (first_error.empty()) return;
    const std::string what = first_error.substr(1);
    if (first_error[0] == 'N') throw NumericalFailure(what);
    if (first_error[0] == 'E') throw Error(what);
    throw std::runtime_error(what);
  };
}

#endif  // LSMBS_HAVE_MPI

namespace {

using Task = std::function<std::string(int)>;
using Done = std::function<void(int, const std::string&)>;

// One task on this process: "R" + its result, or "F" + why it failed.
std::string run_one(const Task& task, int k) {
  try {
    return "R" + task(k);
  } catch (const std::exception& e) {
    return std::string("F") + e.what();
  }
}

// A finished task's message to the caller's callbacks ("I": not run, interrupted).
void report(int k, const std::string& msg, const Done& done, const Done& failed) {
  if (msg.empty() || msg[0] == 'I') return;
  if (msg[0] == 'R')
    done(k, msg.substr(1));
  else
    failed(k, msg.substr(1));
}

#ifdef LSMBS_HAVE_MPI
enum : int { kAsk = 1, kTask = 2, kResult = 3 };

// A rank other than 0: asks for a task, runs it, reports it, until told nothing is left (−1).
void farm_worker(const Task& task) {
  int k = -1;
  for (;;) {
    MPI_Send(&k, 1, MPI_INT, 0, kAsk, MPI_COMM_WORLD);
    MPI_Recv(&k, 1, MPI_INT, 0, kTask, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
    if (k < 0) return;
    const std::string msg = interrupted() ? std::string("I") : run_one(task, k);
    MPI_Send(msg.data(), static_cast<int>(msg.size()), MPI_BYTE, 0, kResult, MPI_COMM_WORLD);
  }
}

// Rank 0: hands out tasks to the workers as they ask and to a thread of its own, and receives
// the results; a task not run because of an interrupt is left for a resume. Interrupted (Ctrl-C,
// or mpirun ending a job whose rank was killed), the workers stop at their next step and report;
// one that has not within 2 s is named and given up.
class FarmServer {
 public:
  FarmServer(int n, const Task& task, const Done& done, const Done& failed)
      : n_(n), done_(done), failed_(failed), given_(static_cast<size_t>(g_world.size), -1) {
    own_ = std::thread([this, &task] {
      for (int k; !interrupted() && (k = next_++) < n_;) {
        std::string msg = run_one(task, k);
        const std::lock_guard<std::mutex> g(lock_);
        local_done_.emplace_back(k, std::move(msg));
      }
      own_done_ = true;
    });
  }
  ~FarmServer() {
    if (own_.joinable()) own_.join();
  }
  void serve() {
    const int workers = g_world.size - 1;
    for (;;) {
      report_local();
      if (stopped_ == workers && outstanding_ == 0 && own_done_) break;
      int flag = 0;
      MPI_Status st;
      MPI_Iprobe(MPI_ANY_SOURCE, MPI_ANY_TAG, MPI_COMM_WORLD, &flag, &st);
      if (!flag) {
        if (interrupted()) give_up_after_grace();
        std::this_thread::sleep_for(std::chrono::microseconds(500));
        continue;
      }
      if (st.MPI_TAG == kAsk)
        hand_out(st.MPI_SOURCE);
      else
        receive(st);
    }
    own_.join();
  }

 private:
  void report_local() {
    const std::lock_guard<std::mutex> g(lock_);
    for (; !local_done_.empty(); local_done_.pop_front())
      report(local_done_.front().first, local_done_.front().second, done_, failed_);
  }
  void give_up_after_grace() {
    const auto now = std::chrono::steady_clock::now();
    if (since_ == std::chrono::steady_clock::time_point{}) since_ = now;
    if (now - since_ <= std::chrono::seconds(2) || !own_done_) return;
    std::string ranks;
    for (int r = 1; r < g_world.size; ++r)
      if (given_[static_cast<size_t>(r)] >= 0)
        ranks += (ranks.empty() ? "" : ", ") + std::to_string(r) + " (task " +
                 std::to_string(given_[static_cast<size_t>(r)]) + ")";
    g_lost = true;
    own_.join();
    throw NumericalFailure("MPI rank " + ranks +
                           " did not report after the interrupt (killed, or the job is being torn "
                           "down: mpirun names the rank that ended); the tasks finished so far "
                           "are written");
  }
  void hand_out(int rank) {
    int last;
    MPI_Recv(&last, 1, MPI_INT, rank, kAsk, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
    int k = interrupted() ? -1 : next_++;
    if (k >= n_) k = -1;
    MPI_Send(&k, 1, MPI_INT, rank, kTask, MPI_COMM_WORLD);
    given_[static_cast<size_t>(rank)] = k;
    if (k < 0)
      ++stopped_;
    else
      ++outstanding_;
  }
  void receive(const MPI_Status& st) {
    int count = 0;
    MPI_Get_count(&st, MPI_BYTE, &count);
    std::string msg(static_cast<size_t>(count), '\0');
    MPI_Recv(msg.data(), count, MPI_BYTE, st.MPI_SOURCE, kResult, MPI_COMM_WORLD,
             MPI_STATUS_IGNORE);
    --outstanding_;
    report(given_[static_cast<size_t>(st.MPI_SOURCE)], msg, done_, failed_);
    given_[static_cast<size_t>(st.MPI_SOURCE)] = -1;
  }

  const int n_;
  const Done& done_;
  const Done& failed_;
  std::atomic<int> next_{0};
  std::atomic<bool> own_done_{false};
  std::mutex lock_;
  std::deque<std::pair<int, std::string>> local_done_;  // this rank's finished tasks
  std::vector<int> given_;                              // each worker's task (−1: none)
  int stopped_ = 0, outstanding_ = 0;
  std::chrono::steady_clock::time_point since_{};
  std::thread own_;
};
#endif  // LSMBS_HAVE_MPI

}  // namespace

void task_farm(int n, int local_threads, const Task& task, const Done& done, const Done& failed) {
#ifdef LSMBS_HAVE_MPI
  if (g_world.active && g_world.size > 1) {
    if (g_world.rank != 0) return farm_worker(task);
    FarmServer(n, task, done, failed).serve();
    return;
  }
#endif
  // one process: `local_threads` at a time
  std::atomic<int> next{0};
  std::mutex lock;
  std::vector<std::thread> pool;
  for (int w = 0; w < std::max(1, std::min(local_threads, n)); ++w)
    pool.emplace_back([&] {
      for (int k; !interrupted() && (k = next++) < n;) {
        const std::string msg = run_one(task, k);
        const std::lock_guard<std::mutex> g(lock);
        report(k, msg, done, failed);
      }
    });
  for (auto& t : pool) t.join();
}

}  // namespace lsmbs::mpi
