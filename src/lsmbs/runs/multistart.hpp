#pragma once
// run_multistart — `lsmbs optimize --starts N` and `lsmbs.optimize(case, starts=N)` as one library
// call: N feasible initial designs drawn uniformly within the bounds (std::mt19937_64 seeded with
// `seed`; a candidate is kept when its evaluation is feasible, max_violation <= 0), each optimized
// by run_optimize in OUT/start_k, `jobs` starts at a time on threads of this process (the study is
// const during an evaluation: starts share it). Each start is a whole optimize run with its own
// summary.json, history and checkpoint; OUT/multistart.json holds the starts (written before any
// start runs, so that resume reuses them); OUT/starts.csv and OUT/summary.json rank the results.
// The numbers of a start do not depend on `jobs`: a start is the same run whichever thread runs it.
#include <cmath>
#include <functional>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "lsmbs/io/case.hpp"
#include "lsmbs/io/optimization_spec.hpp"
#include "lsmbs/sensitivity/gradient_check.hpp"

namespace lsmbs {

struct MultistartOptions {
  int starts = 0;          ///< number of starts (>= 1)
  unsigned long seed = 1;  ///< of the random initial designs
  int jobs = 2;            ///< starts optimized at once (threads)
  bool resume = false;     ///< continue the multi-start out_dir holds (same seed and starts)
  bool overwrite = false;  ///< replace the earlier runs of the start folders
  std::string out_dir;     ///< required
  std::string command;     ///< summary.json's "command"
  /// The gradient check at each start's initial design (none: no check).
  std::optional<GradientCheckOptions> check;
  /// Progress in words ("multi-start: candidate 3 feasible, kept", "start 2 ended (exit 0)").
  std::function<void(const std::string&)> on_message;
  /// Empty when valid, else "field: what is expected".
  std::string validate() const;
};

/// One start as starts.csv lists it.
struct MultistartRow {
  int start = 0;
  /// What `lsmbs optimize` run alone on this start would exit with: 0, 1 (numerical failure or a
  /// refused gradient check), 2 (the start's folder could not be claimed), 130 (interrupted);
  /// -1: not run (the multi-start was interrupted before it began).
  int exit_code = -1;
  std::string status = "not run";  ///< the start's summary.json status
  std::string message;             ///< why a start did not run or failed
  double objective = NAN, violation = NAN, wall = NAN;
  long evaluations = 0;
  bool feasible = false, converged = false;
  std::string stop_reason, kkt_verdict;
  Vec initial, final_design;
  /// The final design's verdict (runs/judge.hpp: sound, unresolved, not a structure; empty:
  /// not judged) and its flags; unresolved designs rank after sound ones, and designs that are
  /// no structure after both
  std::string verdict;
  std::vector<std::string> flags;
  int verdict_rank() const {
    return verdict == "not a structure" ? 2 : verdict == "unresolved" ? 1 : 0;
  }
  /// 0 converged, 1 stopped on a tolerance without meeting the KKT conditions, 2 cut off
  int tier() const;
};

struct MultistartRun {
  /// Interrupted while drawing the starts (nothing was written: run it again).
  bool interrupted_in_screening = false;
  int candidates = 0;  ///< random designs evaluated to find the starts
  std::vector<MultistartRow> rows;
  std::vector<int> order;  ///< feasible starts (1-based), best first (summary.json ranking):
                           ///< by the judgement's verdict, then by tier and objective
  int best = -1, lowest = -1;
  bool all_ran = false;  ///< every start exited 0
  nlohmann::json summary;
  /// 0 every start ran and one is feasible; 1 otherwise; 130 interrupted (under MPI: rank 0's,
  /// on every rank).
  int exit_code() const;
  int ranks_exit = -1;  ///< under MPI: rank 0's exit code, handed to every rank
};

/// Throws Error for an option or a resume that does not fit (another seed or number of starts),
/// NumericalFailure when too few random designs are feasible (20 candidates per start at most).
MultistartRun run_multistart(const Case& cs, const OptimizationSpec& spec,
                             const MultistartOptions& o);

}  // namespace lsmbs
