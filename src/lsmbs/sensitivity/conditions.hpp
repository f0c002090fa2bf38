#pragma once
// Service conditions: one design, several studies. Each condition is a Study of its own (the
// base model with its driver laws, loads, payloads, t_end, h or initial state changed), all
// sharing the design variables. A condition's response r is named "<condition>.r"; a response
// that does not depend on the motion (a mass: Measure::state_independent) is evaluated once, in
// the first condition, under its own name. Combinations of responses (a weighted sum, the KS
// envelope, the exact max) are responses too, with the gradients that combine the conditions'
// (eqs. of ResponseCombination). The conditions of one evaluation are independent runs: they may
// run at once (threads, MPI ranks), and the gathered responses do not depend on how they ran.
#include <functional>
#include <string>
#include <vector>

#include "lsmbs/sensitivity/gradient_check.hpp"
#include "lsmbs/sensitivity/sensitivity.hpp"
#include "lsmbs/sensitivity/study.hpp"

namespace lsmbs {

/// A response made of other responses (scalar ones: per-step responses are refused):
///   sum: Σ w_i r_i (weights default 1);
///   ks:  (1/ρ) ln Σ exp(ρ r_i), a smooth upper envelope: max r_i ≤ KS ≤ max r_i + ln(n)/ρ;
///   max: max r_i, exact. Its gradient is the one of the largest term (a kink where two terms
///        tie); as a constraint, DesignProblem turns it into one constraint per term.
struct ResponseCombination {
  enum class Kind { kSum, kKs, kMax };
  std::string name;
  Kind kind = Kind::kSum;
  std::vector<std::string> of;  ///< response names (of conditions, or other combinations before)
  std::vector<double> weights;  ///< sum only; empty: all 1
  double ks = 0;                ///< ks only: ρ > 0, in 1 / (the responses' unit)
  static const char* kind_name(Kind k);
  /// The bound of KS − max: ln(n)/ρ (0 for sum and max).
  double error_bound() const;
};

/// The studies of one design under its service conditions.
struct Conditions {
  std::vector<std::string> names;     ///< one per study; a single unnamed study: {""}
  std::vector<const Study*> studies;  ///< the same design variables in each
  std::vector<ResponseCombination> combinations;
  /// Per study, whether it evaluates a variant of the design (an offset level set: the robust
  /// formulation's eroded or dilated design); empty: none. A variant reports every response under
  /// its condition's name, a mass too; the unprefixed state-independent responses are those of
  /// the first study that is not a variant.
  std::vector<char> design_variant;
  bool variant(size_t k) const { return k < design_variant.size() && design_variant[k]; }

  /// A single study (no prefix on its responses, no combinations).
  static Conditions single(const Study& s);
  size_t size() const { return studies.size(); }
  const Study& first() const { return *studies.front(); }
  bool several() const { return studies.size() > 1 || !names.front().empty(); }
  /// The response names in the order gather() returns them: each condition's (state-independent
  /// ones once, unprefixed, from the first condition), then the combinations.
  std::vector<std::string> response_names() const;
  /// Whether response r of condition k is reported (state-independent responses: once, from the
  /// first condition that is not a design variant, and from every variant).
  bool reported(size_t k, size_t r) const;
  /// The name condition k's response r is reported under.
  std::string response_name(size_t k, size_t r) const;
  /// SI unit of a response by its gathered name ("" if unknown).
  std::string unit(const std::string& name) const;
  /// Whether response r of study s is state-independent (a scalar aggregate of a measure that
  /// does not depend on the motion, such as a mass).
  static bool state_independent(const Study& s, size_t r);
  /// Checks the combinations (names new, terms known and scalar, weights, ρ): SetupError
  /// "combined" (with the combination as entity) otherwise.
  void validate() const;
  /// The estimated cost of each condition's run: its number of time steps (the conditions share
  /// one model), the weights by which the executors balance the conditions.
  std::vector<double> costs() const;
};

/// The responses of one evaluation of every condition (per_condition[k] is condition k's
/// result), named and combined as Conditions::response_names: values, gradients and, for a
/// per-step response, its times. Conditions that failed contribute nothing: check their `ok`.
std::vector<ResponseSensitivity> gather(const Conditions& c,
                                        const std::vector<SensitivityResult>& per_condition);

/// The evaluations of the conditions of one evaluation: run(k) computes condition k's result into
/// the caller's storage; save(k) gives it as bytes and load(k, bytes) puts it back, so that an
/// executor may compute a task in another process and hand its result over (runs/mpi.hpp).
struct ConditionTasks {
  int n = 0;
  std::function<void(int)> run;
  std::function<std::string(int)> save;
  std::function<void(int, const std::string&)> load;
  std::vector<double> cost;  ///< estimated cost of each task (empty: equal costs)
};

/// The order in which tasks are started: the costliest first (ties by index), so that a pool of
/// workers that takes the next task as one ends is not left waiting on a long one started last.
std::vector<int> costliest_first(const ConditionTasks& t);
/// Which of `workers` runs each task, fixed before any runs: longest processing time first (each
/// task, costliest first, to the worker with the least cost so far; ties to the lowest worker).
/// With equal costs, task k goes to worker k mod workers.
std::vector<int> assign_tasks(const ConditionTasks& t, int workers);
/// Runs the tasks, possibly at once and elsewhere. Whoever runs them, each task computes the same
/// numbers: the results do not depend on the executor.
using ConditionExecutor = std::function<void(const ConditionTasks&)>;
/// On threads of this process, at most `threads` at a time (1: one after the other); the first
/// exception of a task is thrown once every task has ended.
ConditionExecutor thread_executor(int threads);

/// Sensitivities of every condition at p with the options o (one method for all), run by `run`.
std::vector<SensitivityResult> compute_conditions(const Conditions& c, const Vec& p,
                                                  const SensitivityOptions& o,
                                                  const ConditionExecutor& run);

/// The sensitivities of every condition at p, merged (merge); a single study without combinations
/// is compute_sensitivities itself.
SensitivityResult compute_sensitivities(const Conditions& c, const Vec& p,
                                        const SensitivityOptions& o, const ConditionExecutor& run);

/// The gradient check (gradient_check.hpp) of gathered responses: plain runs of every condition at
/// p ± δ w, run by `run`, gathered and combined as the gradients were.
GradientCheckResult check_gradients(const Conditions& c, const Vec& p,
                                    const std::vector<ResponseSensitivity>& gradients,
                                    const GradientCheckOptions& o, const ConditionExecutor& run);

/// One SensitivityResult of the gathered responses of every condition (counts summed, the first
/// failure's message, every warning prefixed with its condition).
SensitivityResult merge(const Conditions& c, const std::vector<SensitivityResult>& per_condition);

}  // namespace lsmbs
