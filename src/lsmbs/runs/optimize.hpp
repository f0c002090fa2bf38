#pragma once
// run_optimize — the `lsmbs optimize` job as one library call, for the command line and Python
// alike: the gradient check at the initial design of a new run, the optimization with its
// checkpoint and history, the final design's pictures, the convergence plot and summary.json.
// The callers only parse their options and report: the command line prints and returns an exit
// code, Python returns a dict and raises. A run started by one resumes in the other (one
// resume_hash).
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "lsmbs/io/case.hpp"
#include "lsmbs/io/optimization_spec.hpp"
#include "lsmbs/optimization/optimizer.hpp"
#include "lsmbs/runs/judge.hpp"
#include "lsmbs/sensitivity/gradient_check.hpp"

namespace lsmbs {

struct OptimizeRunOptions {
  std::string out_dir;  ///< empty: nothing is written
  /// summary.json's "command": the command line, or "lsmbs.optimize (Python)"
  std::string command;
  bool resume = false;  ///< continue from out_dir/checkpoint.json
  /// The gradient check at the initial design of a new run (none on resume: the first run did it).
  std::optional<GradientCheckOptions> check;
  long stop_after = -1;  ///< testing: stop as if interrupted after this many new simulations
  /// The design the run starts from; empty: the initial values of the case's design variables.
  /// Given (a start of a multi-start), it is part of the resume hash.
  Vec initial;
  /// Called once the problem is set up, before the check: the number of constraints.
  std::function<void(int)> on_start;
  std::function<void(int, const Evaluation&)> on_evaluation;  ///< progress
  /// Runs the service conditions of an evaluation (empty: threads of this process; runs/mpi.hpp
  /// on MPI ranks).
  ConditionExecutor executor;
  /// This process runs the whole job by itself (a task of a campaign handed to one rank): its
  /// conditions on threads of this process, its files written by this process, whatever its rank.
  bool alone = false;
};

/// The phase an interrupted run's summary.json names when it stopped in the gradient check: no
/// checkpoint exists, and --resume starts the run anew.
inline constexpr const char* kInitialCheckPhase = "gradient check at the initial design";

struct OptimizeRun {
  enum class Stage {
    kOptimized,          ///< the optimization ran (result holds it; it may be partial)
    kCheckFailed,        ///< refused: the gradient check disagreed above its fail threshold
    kInterruptedInCheck  ///< interrupted during the gradient check: nothing optimized
  };
  Stage stage = Stage::kOptimized;
  std::optional<GradientCheckResult> checked;  ///< the check, when one ran and finished
  std::string check_verdict;                   ///< pass | warn | fail; empty without a check
  std::string check_message;  ///< the worst disagreement (or the check's failure) in words
  OptimizeResult result;      ///< stage kOptimized only
  Vec initial;                ///< the initial design
  /// What the user should know: the optimizer's warnings and the design's (coincident features,
  /// features outside their body, idle variables, a start from a static equilibrium).
  std::vector<std::string> warnings;
  /// The final design judged (runs/judge.hpp; spec.judge): none when judging is off, or the final
  /// design could not be evaluated or was interrupted.
  std::optional<DesignJudgement> judgement;
  nlohmann::json summary;  ///< summary.json's content (also when nothing is written)
  /// What `lsmbs optimize` exits with: 0 a complete run; 1 a numerical failure, a final design
  /// that could not be evaluated, or a refused gradient check; 130 interrupted.
  int exit_code() const;
};

/// Whether out_dir holds a run interrupted during its gradient check (no checkpoint, summary.json's
/// interrupted_phase kInitialCheckPhase): resuming it starts it anew.
bool interrupted_in_initial_check(const std::string& out_dir);

/// Runs the optimization of cs's design with spec (its sensitivity progress callback included).
/// Throws lsmbs::Error for an option or a checkpoint that does not fit.
OptimizeRun run_optimize(const Case& cs, const OptimizationSpec& spec, const OptimizeRunOptions& o);

}  // namespace lsmbs
