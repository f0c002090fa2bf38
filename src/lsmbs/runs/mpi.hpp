#pragma once
// Scale-out with MPI (OpenMPI from Debian; optional at build time, LSMBS_WITH_MPI). Two patterns,
// both giving the numbers of a serial run bit for bit, for any number of ranks:
//
//  * Service conditions of one evaluation (conditions_executor): every rank runs the same
//    workflow (SPMD: the same case, the same optimizer steps); the conditions of an evaluation
//    are split over the ranks (condition k on rank k mod K), each result is broadcast from the rank
//    that computed it, and every rank combines them in the conditions' order. Only rank 0
//    writes files. The interrupt flags of the ranks are made one at each exchange.
//  * Campaigns of independent tasks (task_farm: the starts of a multi-start, the points of a
//    sweep): rank 0 hands out task indices as ranks ask for them (dynamic load balancing) and
//    works on tasks itself; `done` is called on rank 0 as each task finishes, in the order they
//    finish, so that a campaign writes each result at once and a killed one resumes.
//
// A process is under MPI when an MPI launcher started it (mpirun, mpiexec, srun: the environment
// holds OMPI_COMM_WORLD_SIZE, PMI_SIZE or PMIX_RANK). Without MPI built in, such a launch is
// refused (two copies of the same run would write one folder). docs/performance.md "MPI" has the
// cost model and the measured efficiency; docs/getting-started.md a Slurm script.
#include <functional>
#include <string>

#include "lsmbs/sensitivity/conditions.hpp"

namespace lsmbs::mpi {

struct World {
  int rank = 0, size = 1;
  bool active = false;  ///< MPI was started (a launcher started this process, MPI built in)
};

/// Whether this lsmbs was built with MPI.
bool built();
/// Whether an MPI launcher started this process (see above), and with how many ranks (0: none).
int launched_size();
/// Starts MPI when an MPI launcher started this process; finalizes at exit. Throws Error when a
/// launcher started more than one process and this build has no MPI.
const World& init(int* argc, char*** argv);
/// This process's rank and the world's size (rank 0 of 1 before init or without MPI).
const World& world();
/// Ends MPI now (idempotent): a command that ends normally calls it before it exits.
void finalize();

/// How many threads one rank runs at a time: the CPUs the process is bound to when the launcher
/// bound it to fewer than the machine has (mpirun --bind-to core, srun --cpu-bind; Linux), else
/// the cores of this machine over the ranks on it (OMPI_COMM_WORLD_LOCAL_SIZE,
/// SLURM_NTASKS_PER_NODE; at least 1).
int local_threads();
/// The executor of service conditions over the ranks, `threads` at a time on each (0:
/// local_threads()); without MPI (or with one rank) the thread executor.
ConditionExecutor conditions_executor(int threads = 0);
/// How many conditions a rank runs at once when each uses `sensitivity_threads` threads: its
/// cores over that (at least 1), so that a condition's sensitivity update keeps a core of its
/// own. The conditions are independent runs: the results do not depend on this number.
int conditions_at_once(int sensitivity_threads);

/// The bytes of rank 0, on every rank.
std::string broadcast(const std::string& bytes);

/// Runs task(k), k = 0 … n−1, over the ranks (dynamic: a rank gets the next index when it has
/// finished one; rank 0 works too) or, without MPI, on `local_threads` threads. `done(k, bytes)`
/// is called on rank 0 (only) with what task k returned, as the tasks finish; a task that throws
/// gives done(k, "") and its message through `failed(k, what)` (both on rank 0). Returns on every
/// rank once every task is done.
void task_farm(int n, int local_threads, const std::function<std::string(int)>& task,
               const std::function<void(int, const std::string&)>& done,
               const std::function<void(int, const std::string&)>& failed);

}  // namespace lsmbs::mpi
