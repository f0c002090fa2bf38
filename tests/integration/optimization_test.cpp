// Fully coupled optimization (NLopt MMA) on a coarse robot arm (§6: minimize the plate mass
// subject to the average tip deviation over the constant-speed phase ≤ 1 mm, eq. 45): the
// paper's stopping rule ends at a feasible, lighter design on the deviation bound with a positive
// multiplier (not at a KKT point: see the test), and an interrupted run resumed from its
// checkpoint ends at exactly the same design. The one-hole connecting rod (§5.2) with Svanberg's
// classic MMA against the optimum found by bisection.
#include <gtest/gtest.h>

#include <algorithm>
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
  json c = json::parse(
      std::ifstream(std::string(LSMBS_SOURCE_DIR) + "/data/robot_arm/robot_arm_holes.json"));
  c["bodies"][2]["mesh"]["elements"] = {30, 3};
  c["simulation"]["h"] = 0.01;
  c["output"]["vtu_stride"] = 0;
  c["optimization"]["stop"]["max_evaluations"] = 100;
  return c;
}

// Loads the case (file names resolved against base_dir) and optimizes it.
OptimizeResult run(const json& j, const std::string& out, bool resume, long stop_after,
                   DesignProblem** keep = nullptr, const std::string& base_dir = LSMBS_SOURCE_DIR) {
  static std::vector<std::unique_ptr<Case>> cases;  // keep alive for `keep`
  static std::vector<std::unique_ptr<DesignProblem>> probs;
  cases.push_back(std::make_unique<Case>(load_case_json(j, "<test>", base_dir)));
  probs.push_back(
      std::make_unique<DesignProblem>(*cases.back(), parse_optimization(*cases.back())));
  OptimizeOptions o;
  o.out_dir = out;
  o.resume = resume;
  o.stop_after = stop_after;
  std::filesystem::create_directories(out);
  if (keep) *keep = probs.back().get();
  return optimize(*probs.back(), o);
}

}  // namespace

TEST(Optimization,
     CoarseRobotArmEndsFeasibleAndLighterOnTheDeviationBoundAndResumesToTheSameDesign) {
  const std::string dir = testing::TempDir() + "lsmbs_opt";
  std::filesystem::remove_all(dir);
  DesignProblem* prob = nullptr;
  const auto full = run(tiny_robot_arm(), dir + "/full", false, -1, &prob);
  const double m0 = full.history.front().objective, m1 = full.final.objective;
  const auto kkt = kkt_report(*prob, full.final);
  std::printf(
      "mass %.4f g -> %.4f g (%.1f %%), %ld evaluations, %s; max violation %+.2e; KKT: %d active, "
      "lambda %.3f, "
      "stationarity %.3f, bound-sign %.3f\n",
      1e3 * m0, 1e3 * m1, 100 * (1 - m1 / m0), full.evaluations, full.nlopt_status.c_str(),
      full.final.max_violation, kkt.active_constraints,
      kkt.multipliers.empty() ? 0.0 : kkt.multipliers[0], kkt.stationarity,
      kkt.bound_sign_violation);
  // MMA stops on the paper's relative-change rule at a design that is not a KKT point (below):
  // stopped on 'ftol', not converged, and said in a warning
  EXPECT_EQ(full.stop_reason, "ftol") << full.nlopt_status;
  EXPECT_GT(kkt.stationarity, prob->spec().kkt_tolerance);
  EXPECT_FALSE(full.converged) << "a design that is not a KKT point is not converged";
  EXPECT_TRUE(std::any_of(full.warnings.begin(), full.warnings.end(), [](const std::string& w) {
    return w.find("not a first-order (KKT) point") != std::string::npos;
  }));
  EXPECT_LE(full.final.max_violation, 2.5e-3) << "feasible within the paper's 0.25 %";
  EXPECT_GE(full.final.max_violation, -1e-2) << "the deviation constraint is active";
  // the paper's optimum is 29.9 % lighter (Table 5) on the fine model; this coarse one (30 × 3
  // mesh, h = 0.01 s) at least half of that
  EXPECT_GT(1 - m1 / m0, 0.15) << "substantial mass reduction";
  // One active constraint with a positive multiplier and correctly signed reduced gradients at
  // the bounds. The design is not a KKT point and the stationarity residual on the free
  // variables is reported, not asserted: NLopt's MMA stops on the paper's relative-change rule
  // at 0.44 of ‖∇f‖, and at 0.38 with a 1e-6 rule after 172 evaluations; Svanberg's MMA leaves
  // the constraint inactive (docs/verification.md).
  ASSERT_EQ(kkt.active_constraints, 1);
  EXPECT_GT(kkt.multipliers[0], 0);
  EXPECT_LT(kkt.bound_sign_violation, 0.05);

  // interrupted after 20 simulations, then resumed from the checkpoint
  const auto part = run(tiny_robot_arm(), dir + "/resumed", false, 20);
  EXPECT_TRUE(part.interrupted);
  EXPECT_EQ(part.simulations, 20);
  const auto resumed = run(tiny_robot_arm(), dir + "/resumed", true, -1);
  EXPECT_EQ(resumed.simulations, full.evaluations - 20)
      << "earlier evaluations come from the checkpoint";
  ASSERT_EQ(resumed.p.size(), full.p.size());
  for (Eigen::Index i = 0; i < full.p.size(); ++i)
    EXPECT_EQ(resumed.p[i], full.p[i]) << "variable " << i;
  EXPECT_EQ(resumed.final.objective, full.final.objective);
  // the resumed run's history is the uninterrupted run's (replayed points included, numbered from
  // 1)
  ASSERT_EQ(resumed.history.size(), full.history.size());
  for (size_t k = 0; k < full.history.size(); ++k) {
    EXPECT_EQ(resumed.history[k].p, full.history[k].p) << "evaluation " << k + 1;
    EXPECT_EQ(resumed.history[k].objective, full.history[k].objective) << "evaluation " << k + 1;
  }
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
    EXPECT_NE(std::string(e.what()).find("optimization options changed"), std::string::npos)
        << e.what();
  }
}

// The optimizer differentiates the grid responses; idas-adjoint gives gradients of the IDAS
// quadratures only and is refused with the JSON path.
TEST(Optimization, RefusesTheAdjointSensitivityMethod) {
  json j = tiny_robot_arm();
  j["optimization"]["sensitivity"] = {{"method", "idas-adjoint"}};
  Case cs = test::make_case(j);
  try {
    parse_optimization(cs);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("/optimization/sensitivity/method"), std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("idas-adjoint"), std::string::npos) << e.what();
  }
}

namespace {

// One-hole connecting rod of §5.2 on the 3 mm mesh, with Svanberg's classic MMA.
json coarse_rod() {
  json c = json::parse(std::ifstream(std::string(LSMBS_SOURCE_DIR) +
                                     "/data/slider_crank/slider_crank_1hole_coarse.json"));
  c["output"]["vtu_stride"] = 0;
  c["optimization"]["optimizer"] = "mma-svanberg";
  return c;
}

const std::string kRodDir = std::string(LSMBS_SOURCE_DIR) + "/data/slider_crank";

OptimizeResult run_rod(const json& j, const std::string& out, bool resume, long stop_after,
                       DesignProblem** keep) {
  return run(j, out, resume, stop_after, keep, kRodDir);
}

}  // namespace

TEST(Optimization, CoarseOneHoleRodReachesTheElongationBoundFoundByBisection) {
  const std::string dir = testing::TempDir() + "lsmbs_rod";
  std::filesystem::remove_all(dir);
  DesignProblem* prob = nullptr;
  const auto full = run_rod(coarse_rod(), dir + "/full", false, -1, &prob);
  const auto kkt = kkt_report(*prob, full.final);
  double worst = -1e300;
  for (double g : full.final.constraints) worst = std::max(worst, g);
  std::printf(
      "rod: mass %.3f g -> %.3f g (%.2f %%), p = %.5f, max elongation %.4f um, %ld simulations, "
      "%s; KKT: %d active, "
      "stationarity %.2e\n",
      1e3 * full.history.front().objective, 1e3 * full.final.objective,
      100 * (1 - full.final.objective / full.history.front().objective), full.p[0], 1e6 * worst,
      full.evaluations, full.nlopt_status.c_str(), kkt.active_constraints, kkt.stationarity);
  EXPECT_TRUE(full.converged) << full.nlopt_status;
  // the paper's classic MMA took 7 iterations (one simulation each); the reconstructed rod and
  // pressure (calibrated to the paper's initial values only) may take up to twice as many
  EXPECT_LE(full.evaluations, 14)
      << "the classic MMA leaves the tiny start hole in a few iterations (paper: 7)";
  EXPECT_NEAR(1e6 * worst, 16.0, 16.0 * 2.5e-3) << "the elongation bound is active";
  ASSERT_GE(kkt.active_constraints, 1);
  EXPECT_LT(kkt.stationarity, 1e-3);

  // Independent reference: the mass falls monotonically with p, so the optimum is the p at which
  // the maximum elongation reaches 16 um — found by bisection on plain simulations. The final
  // design may violate the bound by the accepted 0.25 %, so p lies between the roots for
  // 16 um and 16.04 um.
  Case cs = load_case_json(coarse_rod(), "<coarse rod>", kRodDir);
  DesignProblem bis(cs, parse_optimization(cs));
  auto root = [&](double violation) {
    double lo = 0.03, hi = 0.12;
    for (int k = 0; k < 11; ++k) {
      const double mid = 0.5 * (lo + hi);
      (bis.evaluate(Vec::Constant(1, mid)).max_violation > violation ? hi : lo) = mid;
    }
    return 0.5 * (lo + hi);
  };
  const double p16 = root(0), p16_04 = root(2.5e-3);
  std::printf("rod: bisection p*(16 um) = %.5f, p*(16.04 um) = %.5f\n", p16, p16_04);
  EXPECT_GT(full.p[0], p16 - 1e-4);
  EXPECT_LT(full.p[0], p16_04 + 1e-4);

  // interrupted after 2 simulations, resumed: the same final design
  const auto part = run_rod(coarse_rod(), dir + "/resumed", false, 2, nullptr);
  EXPECT_TRUE(part.interrupted);
  const auto resumed = run_rod(coarse_rod(), dir + "/resumed", true, -1, nullptr);
  EXPECT_EQ(resumed.simulations, full.evaluations - 2);
  EXPECT_EQ(resumed.p[0], full.p[0]);
  EXPECT_EQ(resumed.final.objective, full.final.objective);
  ASSERT_EQ(resumed.history.size(), full.history.size());
  for (size_t k = 0; k < full.history.size(); ++k)
    EXPECT_EQ(resumed.history[k].p, full.history[k].p);
  // resuming a finished run replays it without a simulation and ends on the same design
  const auto again = run_rod(coarse_rod(), dir + "/resumed", true, -1, nullptr);
  EXPECT_EQ(again.simulations, 0);
  EXPECT_EQ(again.p[0], full.p[0]);
  EXPECT_EQ(again.history.size(), full.history.size());
}
