#pragma once
// run_sensitivity — the `lsmbs sensitivity` job as one library call, for the command line and
// Python alike: the responses and their design gradients at p by one method (§4.3), other methods
// compared with it (methods.csv, methods.png), an optional gradient check along a random
// direction, gradients.csv and summary.json. The callers only parse their options and report.
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "lsmbs/io/case.hpp"
#include "lsmbs/sensitivity/gradient_check.hpp"
#include "lsmbs/sensitivity/sensitivity.hpp"

namespace lsmbs {

struct SensitivityRunOptions {
  SensitivityOptions options;  ///< the first method: its results are the gradients
  /// Further methods, each run with `options` but its method and compared with the first one
  /// (methods.csv, methods.png, summary.json "methods").
  std::vector<SensitivityOptions::Method> compare;
  std::optional<GradientCheckOptions> check;  ///< central differences along a random direction
  std::string out_dir;                        ///< empty: nothing is written
  /// Runs the service conditions of one evaluation (empty: threads of this process; runs/mpi.hpp
  /// on MPI ranks).
  ConditionExecutor executor;
  std::string command;  ///< summary.json's "command"
};

struct SensitivityRun {
  SensitivityResult result;                 ///< the first method's
  std::vector<SensitivityResult> compared;  ///< every method run, the first one first
  std::optional<GradientCheckResult> checked;
  bool stopped = false;  ///< an interrupt came in some part (the method, a compared one, the check)
  bool others_ok = true;   ///< every compared method completed
  nlohmann::json summary;  ///< summary.json's content (also when nothing is written)
  /// 0 complete; 1 a numerical failure of a method or a failed gradient check; 130 interrupted.
  int exit_code(const std::optional<GradientCheckOptions>& check) const;
  /// Why exit_code is 1, in words (empty otherwise).
  std::string failure(const std::optional<GradientCheckOptions>& check) const;
};

/// Runs the sensitivity job of `cs` at p (p within the bounds of the case's design; the case needs
/// design variables and at least one response: SetupError otherwise). Throws SetupError for
/// options of a method that do not fit the study.
SensitivityRun run_sensitivity(const Case& cs, const Vec& p, const SensitivityRunOptions& o);

}  // namespace lsmbs
