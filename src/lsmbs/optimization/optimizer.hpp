#pragma once
// Optimizer — minimizes a DesignProblem with NLopt (LD_MMA, the globally convergent CCSA
// variant of Svanberg's MMA; LD_CCSAQ; LD_SLSQP). Design variables are scaled to [0, 1],
// the objective to f/|f(p0)| and each constraint to (g − ū)/|ū|. NLopt may evaluate several
// points per outer iteration; every new point is one simulation with its sensitivities and is
// appended to history.csv, and a checkpoint with every evaluation (exact doubles) is written
// after it. `resume` replays the run from those evaluations (NLopt is deterministic, so it
// retraces the same path through the cache) and continues: an interrupted run ends at the same
// design as an uninterrupted one.
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "lsmbs/core/status.hpp"
#include "lsmbs/optimization/kkt.hpp"
#include "lsmbs/optimization/problem.hpp"

namespace lsmbs {

struct OptimizeOptions {
  std::string out_dir;  ///< history.csv, checkpoint.json (empty: nothing written)
  /// false: out_dir is read (resume), never written (the MPI ranks but rank 0, runs/mpi.hpp)
  bool write_files = true;
  bool resume = false;  ///< seed from out_dir/checkpoint.json
  /// Hash of the input the problem was built from (a case file's SHA-256): a checkpoint of another
  /// input is refused on resume.
  std::string input_sha256;
  std::function<void(int, const Evaluation&)>
      on_evaluation;     ///< progress (evaluation index, result)
  long stop_after = -1;  ///< testing: stop (as if killed) after this many new simulations
  /// The design the run starts from; empty: the design's initial values (Design::initial).
  Vec initial;
  /// Empty string when valid, otherwise "field: what is expected".
  std::string validate() const;
};

struct OptimizeResult {
  Vec p;  ///< final design (best feasible evaluation, else NLopt's last point)
  Evaluation final;
  int nlopt_code = 0;
  std::string nlopt_status;
  /// Why the optimizer stopped, one word: ftol (relative objective change below tol_objective),
  /// xtol, success, max_evaluations, max_time, stopval, roundoff_limited, nlopt_failure,
  /// interrupted, failed (a simulation failed). Apart from whether the design is optimal.
  std::string stop_reason;
  long evaluations = 0;  ///< distinct design points evaluated (incl. replayed ones)
  long simulations = 0;  ///< simulations run in this process
  /// First-order optimality at the final design (when its evaluation has gradients).
  std::optional<KktReport> kkt;
  /// Stopped on a tolerance (ftol, xtol, success), with a feasible final design that satisfies
  /// the KKT conditions within spec().kkt_tolerance. A stop on the objective's change alone is not
  /// convergence: MMA's steps shrink on a kink of a max aggregate as well as at an optimum.
  bool converged = false;
  /// What the user should know about the result: not a KKT point, an infeasible final design,
  /// a max/min aggregate whose extreme step moved between evaluations (one sentence each).
  std::vector<std::string> warnings;
  bool interrupted = false;
  /// Non-empty when an evaluation's simulation failed (the run stops there): which evaluation,
  /// at which design, and the integrator's message (when and why).
  std::string failure;
  std::vector<Evaluation> history;  ///< every distinct evaluation in order
  double wall_seconds = 0;
  RunStatus status() const;
  std::string report() const;  ///< outcome and counts, one paragraph
};

OptimizeResult optimize(DesignProblem& problem, const OptimizeOptions& o);

/// Writes history.csv from evaluations (atomic).
void write_history(const std::string& path, const DesignProblem& problem,
                   const std::vector<Evaluation>& h);

}  // namespace lsmbs
