//                    lsmbs example 3: a design loop that calls the optimizer
//
// Sample run:   build/examples/design_loop
//
// The robot arm of example 2 (60 × 5 plate mesh): minimize the plate's mass subject to an
// average end-effector deviation of at most 1 mm (the paper's section 6 problem, eq. 22 with the
// constraint of eq. 45), over the 15 hole parameters, with NLopt's MMA and direct-analytic
// gradients. Every evaluation is one simulation with its sensitivities. The example checks that
// the optimizer ends on a feasible design lighter than the initial one, and exits 1 otherwise.
#include <cstdio>

#include "lsmbs/optimization/optimizer.hpp"
#include "robot_arm_model.hpp"

using namespace lsmbs;

int main() {
  // 1. The model and its design variables.
  Study study = example::robot_arm(60, 5);

  // 2. The problem: objective, constraint, optimizer, sensitivity method, stopping rule.
  OptimizationSpec spec;
  spec.objective = "plate_mass";
  spec.constraints = {{"average_tip_deviation", 1e-3}};
  spec.optimizer = "mma";
  spec.sensitivity.method = SensitivityOptions::Method::kDirectAnalytic;
  spec.tol_objective = 5e-4;
  spec.max_evaluations = 20;  // a short run: enough to reach a feasible, lighter design
  DesignProblem problem(study, spec);

  // 3. The loop: NLopt asks for values and gradients; each design is simulated once (cached).
  OptimizeOptions o;
  o.on_evaluation = [](int k, const Evaluation& e) {
    std::printf("%3d  mass %.6f kg  deviation constraint %+.3e\n", k, e.objective, e.max_violation);
  };
  const OptimizeResult r = optimize(problem, o);

  // 4. The outcome.
  const Evaluation& first = r.history.front();
  std::printf("%s after %ld evaluations: mass %.6f -> %.6f kg, max violation %.2e\n",
              r.nlopt_status.c_str(), r.evaluations, first.objective, r.final.objective,
              r.final.max_violation);
  for (int i = 0; i < study.design->size(); ++i)
    std::printf("  %-4s %.5f -> %.5f\n", study.design->variables[i].name.c_str(), first.p[i],
                r.p[i]);
  const bool ok = r.failure.empty() && r.final.ok && r.final.max_violation <= spec.tol_constraint &&
                  r.final.objective < first.objective;
  std::printf("%s\n", ok ? "feasible and lighter than the initial design" : "NO IMPROVEMENT");
  return ok ? 0 : 1;
}
