#pragma once
// DesignProblem — the optimization problem (22) of a case: minimize one response subject to
// response ≤ bound constraints (a per-step response gives one constraint per step: the local
// formulation of eq. 42; an aggregated one a single global constraint, e.g. eq. 45), over the
// design variables within their bounds. evaluate(p) runs ONE simulation with its sensitivities
// and caches the result by p: NLopt asks for the objective and the constraints separately at
// the same point, and a resumed run replays its earlier evaluations from the cache.
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "lsmbs/geometry/length_scale.hpp"
#include "lsmbs/sensitivity/conditions.hpp"
#include "lsmbs/sensitivity/gradient_check.hpp"
#include "lsmbs/sensitivity/sensitivity.hpp"
#include "lsmbs/sensitivity/study.hpp"

namespace lsmbs {

struct OptimizationSpec {
  std::string objective;  ///< response name (scalar)
  /// g ≤ upper in the optimizer's form: g = r for an upper bound r ≤ b (upper = b), g = −r for a
  /// lower bound r ≥ b (upper = −b); an `equals` is both. Scaled as (g − upper) / normalizer.
  struct Constraint {
    std::string response;
    double upper = 0;
    bool lower = false;  ///< a lower bound of the response (g = −r)
    double scale = 0;    ///< reference value of the scaling; 0: |upper| (non-zero then)
    double normalizer() const { return scale > 0 ? scale : std::abs(upper); }
  };
  std::vector<Constraint> constraints;
  std::string optimizer = "mma";  ///< mma | ccsaq | slsqp (NLopt) | mma-svanberg (classic MMA)
  /// mma-svanberg: largest step per iteration, fraction of the range (0.1: the lightest feasible
  /// robot arm of the move-limit study, docs/methods.md)
  double move_limit = 0.1;
  double asymptote_init = 0.5;  ///< mma-svanberg: initial asymptote distance, fraction of range
  SensitivityOptions sensitivity;
  double tol_objective = 1e-4;     ///< relative objective change between accepted iterates
  double tol_constraint = 2.5e-3;  ///< relative constraint violation allowed at convergence
  int max_evaluations = 100;
  int inner_max_evaluations =
      0;  ///< NLopt CCSA inner iterations per outer one (0: NLopt's default)
  /// The final design is a first-order (KKT) point when the scaled stationarity residual and the
  /// wrong-signed reduced gradients at bounds are at most this, relative to ‖∇f‖∞ (kkt.hpp).
  /// A verdict of the result, not a stopping rule: a resumed run may change it.
  double kkt_tolerance = 1e-2;
  /// How the final design is judged (runs/judge.hpp): what the fixed mesh resolves of it, and
  /// whether its responses rest on the ersatz material of the void.
  struct Judge {
    bool enabled = true;
    double min_elements = 2;        ///< parts narrower than this many element sizes are flagged
    bool ersatz = true;             ///< re-simulate with μ_min · ersatz_factor
    double ersatz_factor = 1e-3;    ///< 1000× less ersatz stiffness and mass
    double ersatz_tolerance = 0.1;  ///< relative change of a response that flags the design
  } judge;
  /// Length-scale constraints on every designed body (geometry/length_scale.hpp): each
  /// measure ≥ its bound δ [m], appended to the constraints. A bound < 0 takes min_size; a
  /// min_size < 0 is judge.min_elements element sizes of the body (what the judgement calls
  /// resolved); 0 turns a kind off.
  struct LengthScale {
    bool enabled = false;
    double min_size = -1;
    double min_ligament = -1, min_edge = -1, min_member = -1;
    double no_cut = 0;  ///< off by default: min_edge > 0 keeps every feature off the edges
    double tolerance = 0.05;
  } length_scale;
  nlohmann::json to_json() const;
};

/// One evaluation: the objective and constraints (raw and scaled) with gradients.
struct Evaluation {
  Vec p;
  double objective = 0;
  /// g_j, each ≤ upper_j: the response for an upper bound, minus the response for a lower
  /// bound (OptimizationSpec::Constraint)
  std::vector<double> constraints;
  std::vector<double> upper;  ///< bounds of g_j
  std::vector<double> scale;  ///< normalizer of g_j − upper_j (|bound| or the given reference)
  Vec objective_gradient;     ///< ∂f/∂p
  Mat constraint_gradient;    ///< m × n_v
  double max_violation = 0;  ///< max_j (g_j − ū_j)/scale_j  (≤ 0: feasible; 0 without constraints)
  double wall_seconds = 0;
  bool ok = true;
  /// The objective's and constraints' max and min aggregates: the time of the step whose value
  /// each takes, by response name (a change between evaluations is a kink of the response).
  std::map<std::string, double> extreme_times;
  /// Stopped by an interrupt before the simulation ended: not a result of p (never cached).
  bool interrupted = false;
  std::string message;
};

class DesignProblem {
 public:
  /// The problem of one study.
  DesignProblem(const Study& cs, OptimizationSpec spec);
  /// The problem over service conditions: the objective and constraints name the gathered
  /// responses (sensitivity/conditions.hpp: "<condition>.<response>", state-independent ones
  /// unprefixed, combinations). A constraint on an exact-max combination is one constraint per
  /// term. `run` evaluates the conditions (default: threads of this process); its results do not
  /// depend on it.
  DesignProblem(Conditions conditions, OptimizationSpec spec, ConditionExecutor run = {});
  int num_variables() const { return design().size(); }
  /// Number of scalar constraints (per-step responses count one per step).
  int num_constraints() const { return num_constraints_; }
  /// Name of each scalar constraint: its response's name, followed by ".k" for step k of a
  /// per-step response's window (the step of gradients.csv).
  const std::vector<std::string>& constraint_names() const { return constraint_names_; }
  const Evaluation& evaluate(const Vec& p);
  /// Without length-scale constraints p0 itself; with them, the design nearest to p0 (in the
  /// variables scaled to [0, 1]) that keeps them, found without simulating (NLopt SLSQP on the
  /// geometric constraints alone, at most 300 evaluations): a random start of a multi-start made
  /// geometrically admissible. `violation` receives the largest scaled violation left (≤ 0:
  /// admissible).
  Vec admissible_start(const Vec& p0, double* violation = nullptr) const;
  /// The largest scaled violation of the responses' constraints alone (the length-scale
  /// constraints left out; 0 without any), NaN for a failed evaluation.
  double response_violation(const Evaluation& e) const;
  long simulations() const { return simulations_; }
  long cache_hits() const { return cache_hits_; }
  /// Seeds the cache (resume from a checkpoint).
  void seed(const Evaluation& e);
  const std::map<std::vector<double>, Evaluation>& cache() const { return cache_; }
  const OptimizationSpec& spec() const { return spec_; }
  /// The first condition's study (the only one without conditions).
  const Study& study() const { return conditions_.first(); }
  const Conditions& conditions() const { return conditions_; }
  const Design& design() const { return *conditions_.first().design; }
  /// The length-scale measures at p (spec.length_scale; null when off): per body, each
  /// constraint's kind, features, value, bound δ, aggregation error bound [m] and where it is
  /// smallest.
  nlohmann::json length_scale_json(const Vec& p) const;
  /// Evaluates the conditions of the problem (for its gradient check: check_problem_gradients).
  const ConditionExecutor& executor() const { return run_; }

 private:
  Conditions conditions_;
  ConditionExecutor run_;
  OptimizationSpec spec_;
  std::vector<std::string> names_;  // the gathered responses' names (Conditions::response_names)
  /// The constraints as evaluated: spec's, an exact max turned into one per term.
  std::vector<OptimizationSpec::Constraint> expanded_;
  int objective_index_ = -1;
  std::vector<int> constraint_index_;
  int num_constraints_ = 0;
  std::vector<double>
      constraint_upper_;  // the bound of each scalar constraint (per-step: each step)
  std::vector<double> constraint_scale_;  // … and its normalizer
  std::vector<std::string> constraint_names_;
  /// The length-scale constraints of each designed body (spec.length_scale), after the
  /// responses' constraints in the order of `names()`.
  struct BodyLengthScale {
    std::string body;
    std::unique_ptr<LengthScaleMeasures> measures;
  };
  std::vector<BodyLengthScale> length_scales_;
  int num_response_constraints_ = 0;
  void add_length_scales();
  void add_length_scale(const std::string& body, std::unique_ptr<LengthScaleMeasures> measures);
  /// The bounds of spec.length_scale on a body of median element size h (defaults: min_size, or
  /// judge.min_elements · h).
  LengthScaleOptions length_scale_options(double h) const;
  void evaluate_length_scales(Evaluation& e, int& row) const;
  /// The largest of the length-scale constraints' scaled violations (δ − value)/δ at p; g and J
  /// receive each one and its gradient.
  double geometric_violation(const Vec& p, Vec* g, Mat* J) const;
  std::map<std::vector<double>, Evaluation> cache_;
  Evaluation interrupted_;  // the last interrupted evaluation (not cached)
  long simulations_ = 0, cache_hits_ = 0;
};

/// The gradient check (sensitivity/gradient_check.hpp) of the problem's objective and constraints
/// at p, with the problem's sensitivity options: what `optimize` runs at the initial design of a
/// new run. nullopt when the sensitivity run itself failed (the first evaluation then reports it).
std::optional<GradientCheckResult> check_problem_gradients(DesignProblem& problem, const Vec& p,
                                                           const GradientCheckOptions& o);

/// Evaluation to/from JSON (checkpoints): exact doubles via their bit patterns in hex.
nlohmann::json evaluation_to_json(const Evaluation& e);
Evaluation evaluation_from_json(const nlohmann::json& j);

}  // namespace lsmbs
