//                 lsmbs example 2: the robot arm with level-set holes, built in code
//
// Sample runs:  build/examples/robot_arm_gradients              (60 × 5 plate mesh, a few seconds)
//               build/examples/robot_arm_gradients --paper-mesh  (the paper's 120 × 10 mesh)
//
// The robot arm of Tromme et al. section 6 (examples/robot_arm_model.hpp) with five super-ellipse
// holes in its flexible plate, at Table 5's initial design. The example computes the plate's mass
// and the end effector's average path deviation with their gradients with respect to the 15 hole
// parameters by the direct analytic method (one simulation), prints them, and checks them along
// a random direction against central differences of two more simulations (the library's
// GradientCheck). It fails (exit 1) above a relative disagreement of 1e-4.
//
// Equations: the level-set features (eq. 43) and their mapping to element densities μ_e (eq. 3);
// generalized-α (Algorithm 1); the path deviation (eq. 44) averaged over the constant-speed phase;
// direct sensitivities (Algorithm 2, eq. 37) with exact ∂r/∂p from ∂μ_e/∂p.
#include <cstdio>
#include <cstring>

#include "lsmbs/sensitivity/gradient_check.hpp"
#include "lsmbs/sensitivity/sensitivity.hpp"
#include "robot_arm_model.hpp"

using namespace lsmbs;

int main(int argc, char** argv) {
  const bool paper_mesh = argc > 1 && std::strcmp(argv[1], "--paper-mesh") == 0;

  // 1. The model, the responses and the 15 design variables (robot_arm_model.hpp).
  Study study = paper_mesh ? example::robot_arm(120, 10) : example::robot_arm(60, 5);
  const Vec p = study.design->initial();
  std::printf("robot arm: %d unknowns, %d constraint equations, %d design variables\n",
              study.model->nq(), study.model->nc(), study.design->size());

  // 2. Responses and gradients: one simulation with the direct sensitivities.
  SensitivityOptions so;
  so.method = SensitivityOptions::Method::kDirectAnalytic;
  const SensitivityResult res = compute_sensitivities(study, p, so);
  if (!res.ok) {
    std::printf("simulation failed: %s\n", res.message.c_str());
    return 1;
  }
  for (const auto& r : res.responses) {
    std::printf("%-22s %.9e\n", r.name.c_str(), r.values[0]);
    for (int i = 0; i < study.design->size(); i += 3)  // the first hole's ∂/∂c_x, ∂/∂a, ∂/∂b, …
      std::printf("    d/d%-4s %+.6e  d/d%-4s %+.6e  d/d%-4s %+.6e\n",
                  study.design->variables[i].name.c_str(), r.gradient(0, i),
                  study.design->variables[i + 1].name.c_str(), r.gradient(0, i + 1),
                  study.design->variables[i + 2].name.c_str(), r.gradient(0, i + 2));
  }

  // 3. The check: central differences along a random direction of the scaled variables. The
  //    maximum over the phase is left out: its derivative jumps where the maximum changes step.
  std::vector<ResponseSensitivity> smooth;
  for (const auto& r : res.responses)
    if (r.name != "max_tip_deviation") smooth.push_back(r);
  const GradientCheckResult check = check_gradients(study, p, smooth);
  for (const auto& e : check.entries)
    std::printf(
        "check %-22s central difference %+.9e, gradient %+.9e, relative disagreement %.2e\n",
        e.response.c_str(), e.finite_difference, e.method, e.relative_error);
  const bool ok = check.ok && check.worst < 1e-4;
  std::printf("%s\n", ok ? "gradients agree with central differences" : "GRADIENTS DISAGREE");
  return ok ? 0 : 1;
}
