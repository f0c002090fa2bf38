#pragma once
// Outcomes. `Status` is the outcome of one numerical operation the caller may recover from
// (retry with a smaller step, report); input errors throw lsmbs::Error instead.
// `RunStatus` is how a whole run ended. Every run result of the library (IntegratorSummary,
// IdasStats, StaticResult, SensitivityResult, GradientCheckResult, OptimizeResult,
// SimulationResult) has the same contract, the RunResult concept: status(), its counts as
// members, and report(), a short human-readable account of the outcome and the counts.
#include <concepts>
#include <string>

namespace lsmbs {

struct Status {
  enum class Code { kOk, kNotConverged, kSingular, kNonFinite };
  Code code = Code::kOk;
  std::string message;

  bool ok() const { return code == Code::kOk; }
  static Status Ok() { return {}; }
  static Status Fail(Code c, std::string msg) { return {c, std::move(msg)}; }
};

enum class RunStatus {
  kComplete,     ///< the run did all it was asked to
  kFailed,       ///< a numerical failure (the result's message says when and why); results partial
  kInterrupted,  ///< stopped by SIGINT/SIGTERM or an observer; results partial
};

inline const char* run_status_name(RunStatus s) {
  return s == RunStatus::kComplete ? "complete"
         : s == RunStatus::kFailed ? "failed"
                                   : "interrupted";
}

template <class R>
concept RunResult = requires(const R& r) {
  { r.status() } -> std::same_as<RunStatus>;
  { r.report() } -> std::convertible_to<std::string>;
};

}  // namespace lsmbs
