// Fully coupled optimization (NLopt MMA) on a coarse robot arm (§6: minimize the plate mass
// subject to the average tip deviation over the constant-speed phase ≤ 1 mm, eq. 45):
// convergence (the paper's stopping rule) to a feasible design with an active constraint and a
// positive multiplier, and an interrupted run resumed from its checkpoint ends at exactly the
// same design.
#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>

#include "lsmbs/core/error.hpp"
#include "lsmbs/io/optimization_spec.hpp"
#include "lsmbs/optimization/kkt.hpp"
#include "lsmbs/optimization/optimizer.hpp"
#include "support/test_models.hpp"

using namespace lsmbs;
using json = nlohmann::json;

namespace {

// 30 × 3 mesh, h = 0.01 s: a design evaluation (simulation + 15 gradients) takes ~0.1 s.
json tiny_robot_arm() {
  json c = json::parse(std::ifstream(std::string(LSMBS_SOURCE_DIR) + "/data/robot_arm/robot_arm_holes.json"));
  c["bodies"][2]["mesh"]["elements"] = {30, 3};
  c["simulation"]["h"] = 0.01;
  c["output"]["vtu_stride"] = 0;
  c["optimization"]["stop"]["max_evaluations"] = 100;
  return c;
}

OptimizeResult run(const json& j, const std::string& out, bool resume, long stop_after, DesignProblem** keep = nullptr) {
  static std::vector<std::unique_ptr<Case>> cases;  // keep alive for `keep`
  static std::vector<std::unique_ptr<DesignProblem>> probs;
  cases.push_back(std::make_unique<Case>(test::make_case(j)));
  probs.push_back(std::make_unique<DesignProblem>(*cases.back(), parse_optimization(*cases.back())));
  OptimizeOptions o;
  o.out_dir = out;
  o.resume = resume;
  o.stop_after = stop_after;
  std::filesystem::create_directories(out);
  if (keep) *keep = probs.back().get();
  return optimize(*probs.back(), o);
}

}  // namespace

TEST(Optimization, CoarseRobotArmConvergesToAFeasibleKktPointAndResumesToTheSameDesign) {
  const std::string dir = testing::TempDir() + "lsmbs_opt";
  std::filesystem::remove_all(dir);
  DesignProblem* prob = nullptr;
  const auto full = run(tiny_robot_arm(), dir + "/full", false, -1, &prob);
  const double m0 = full.history.front().objective, m1 = full.final.objective;
  const auto kkt = kkt_report(*prob, full.final);
  std::printf("mass %.4f g -> %.4f g (%.1f %%), %ld evaluations, %s; max violation %+.2e; KKT: %d active, lambda %.3f, "
              "stationarity %.3f, bound-sign %.3f\n",
              1e3 * m0, 1e3 * m1, 100 * (1 - m1 / m0), full.evaluations, full.nlopt_status.c_str(), full.final.max_violation,
              kkt.active_constraints, kkt.multipliers.empty() ? 0.0 : kkt.multipliers[0], kkt.stationarity,
              kkt.bound_sign_violation);
  EXPECT_TRUE(full.converged) << full.nlopt_status;
  EXPECT_LE(full.final.max_violation, 2.5e-3) << "feasible within the paper's 0.25 %";
  EXPECT_GE(full.final.max_violation, -1e-2) << "the deviation constraint is active";
  EXPECT_GT(1 - m1 / m0, 0.15) << "substantial mass reduction";
  // KKT: one active constraint with a positive multiplier and correctly signed reduced gradients
  // at the bounds. The stationarity residual on the free variables is reported, not asserted:
  // NLopt's MMA stops on the paper's relative-change rule at 0.2–0.3 of ‖∇f‖ on this problem
  // (0.21 even with a 1e-5 rule after 138 evaluations) — see docs/methods.md.
  ASSERT_EQ(kkt.active_constraints, 1);
  EXPECT_GT(kkt.multipliers[0], 0);
  EXPECT_LT(kkt.bound_sign_violation, 0.05);

  // interrupted after 20 simulations, then resumed from the checkpoint
  const auto part = run(tiny_robot_arm(), dir + "/resumed", false, 20);
  EXPECT_TRUE(part.interrupted);
  EXPECT_EQ(part.simulations, 20);
  const auto resumed = run(tiny_robot_arm(), dir + "/resumed", true, -1);
  EXPECT_EQ(resumed.simulations, full.evaluations - 20) << "earlier evaluations come from the checkpoint";
  ASSERT_EQ(resumed.p.size(), full.p.size());
  for (Eigen::Index i = 0; i < full.p.size(); ++i) EXPECT_EQ(resumed.p[i], full.p[i]) << "variable " << i;
  EXPECT_EQ(resumed.final.objective, full.final.objective);
}

TEST(Optimization, ResumeRefusesACheckpointOfAnotherCase) {
  const std::string dir = testing::TempDir() + "lsmbs_opt2";
  std::filesystem::remove_all(dir);
  json j = tiny_robot_arm();
  j["optimization"]["stop"]["max_evaluations"] = 2;
  run(j, dir, false, -1);
  json other = j;
  other["optimization"]["stop"]["max_evaluations"] = 3;  // different options
  try {
    run(other, dir, true, -1);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("optimization options changed"), std::string::npos) << e.what();
  }
}
