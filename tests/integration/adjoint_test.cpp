// The discrete adjoint of generalized-α (method adjoint, adjoint_method.hpp) against independent
// references and against the direct method it transposes:
//  * central finite differences of whole re-simulations (fd-central, tight Newton tolerance):
//    the adjoint differentiates the discrete solution, and so do they;
//  * direct-analytic, the forward recurrence of Algorithm 2 on the same discrete solution: the
//    two compute the same numbers in another order, so they agree to round-off (1e-9);
//  * every term of the backward recurrence, dropped one at a time, must break that agreement
//    (a term the test cases never exercise would let a wrong transpose of it pass);
//  * 10, 100 and 1,000 steps: the agreement does not degrade with the step count;
//  * recomputation from checkpoints (--adjoint-memory) gives the full-storage gradients;
//  * adjoint-semi-analytical converges to the adjoint as O(Δp).
// Cases: the rigid slider-crank with a spring-damper (k, c: every scalar aggregate, a constraint
// force, a window), the robot arm with five super-ellipses (15 variables, coarse mesh, short
// horizon), the coarse slider-crank rod with one level-set hole.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>

#include "lsmbs/core/error.hpp"
#include "lsmbs/sensitivity/adjoint_method.hpp"
#include "support/gradients.hpp"
#include "support/test_models.hpp"

using namespace lsmbs;
using json = nlohmann::json;
using Method = SensitivityOptions::Method;

namespace {

double worst(const SensitivityResult& a, const SensitivityResult& ref,
             std::string* where = nullptr) {
  return test::worst_relative(a, ref, test::Norm::kPerValue, where);
}

SensitivityResult run(Case& cs, Method m, double memory_mb = 0, double delta = 1e-6) {
  SensitivityOptions o;
  o.method = m;
  o.adjoint_memory_mb = memory_mb;
  o.delta = delta;
  auto r = compute_sensitivities(cs, cs.design->initial(), o);
  EXPECT_TRUE(r.ok) << r.message;
  return r;
}

// The spring slider-crank with every scalar aggregate (no per-step response), h given.
json spring_crank(double h) {
  json c = test::spring_crank_json();
  c["simulation"]["h"] = h;
  c["simulation"]["tol_r"] = 1e-12;
  c["output"]["responses"] = json::parse(R"([
    {"name": "final_crank_angle", "measure": "crank_angle", "aggregate": "final"},
    {"name": "mean_piston_x", "measure": "piston.x", "aggregate": "average"},
    {"name": "mean_eq45_piston_y", "measure": "piston.x", "aggregate": "average_eq45", "window": {"t0": 0.05, "t1": 0.2}},
    {"name": "energy_integral", "measure": "energy", "aggregate": "integral"},
    {"name": "rms_side_force", "measure": "cylinder_force.0", "aggregate": "rms"},
    {"name": "max_side_force", "measure": "cylinder_force.0", "aggregate": "max", "window": {"t0": 0.1, "t1": 0.25}},
    {"name": "min_energy", "measure": "energy", "aggregate": "min", "window": {"t0": 0.1, "t1": 0.25}},
    {"name": "ks_piston_x", "measure": "piston.x", "aggregate": "ks", "ks": 2000}
  ])");
  return c;
}

Case robot_arm_case() {
  json c = json::parse(
      std::ifstream(std::string(LSMBS_SOURCE_DIR) + "/data/robot_arm/robot_arm_holes.json"));
  c["bodies"][2]["mesh"]["elements"] = {60, 5};
  c["simulation"]["t_end"] = 0.3;
  c["simulation"]["tol_r"] = 1e-11;
  c["output"]["vtu_stride"] = 0;
  c["output"]["responses"] = json::parse(R"([
    {"name": "average_tip_deviation", "measure": "tip_deviation", "aggregate": "average", "window": {"t0": 0.1, "t1": 0.3}},
    {"name": "max_tip_deviation", "measure": "tip_deviation", "aggregate": "max"},
    {"name": "plate_mass", "measure": "plate_mass", "aggregate": "final"},
    {"name": "kinetic_energy_integral", "measure": "kinetic_energy", "aggregate": "integral"}
  ])");
  return test::make_case(c);
}

}  // namespace

TEST(Adjoint, SpringCrankEveryAggregateAgreesWithDirectAndCentralDifferences) {
  Case cs = test::make_case(spring_crank(1e-3));
  const auto adj = run(cs, Method::kAdjoint);
  const auto dir = run(cs, Method::kDirectAnalytic);
  const auto fd = run(cs, Method::kFdCentral, 0, 1e-5);
  std::string w1, w2;
  const double e_dir = worst(adj, dir, &w1), e_fd = worst(adj, fd, &w2);
  std::printf("spring crank: adjoint vs direct-analytic %.2e (%s), vs fd-central %.2e (%s)\n",
              e_dir, w1.c_str(), e_fd, w2.c_str());
  EXPECT_LT(e_dir, 1e-9);
  // fd-central's own error (sensitivity_test: Δp² truncation and tol_r / Δp noise)
  EXPECT_LT(e_fd, 5e-7);
  EXPECT_EQ(adj.counts.simulations, 1);
  EXPECT_EQ(adj.counts.adjoint_solves, adj.counts.steps + 1) << "one per step and the start";
  EXPECT_EQ(adj.counts.adjoint_recomputed_steps, 0);
  EXPECT_GT(adj.counts.adjoint_memory_bytes, 0);
}

TEST(Adjoint, EveryTermOfTheRecurrenceIsNeeded) {
  Case cs = test::make_case(spring_crank(1e-3));
  SensitivityOptions o;
  o.method = Method::kAdjoint;
  const Vec p = cs.design->initial();
  const auto exact = adjoint_sensitivities(cs, p, o, AdjointTerms{});
  ASSERT_TRUE(exact.ok) << exact.message;
  ASSERT_LT(worst(exact, run(cs, Method::kDirectAnalytic)), 1e-9);
  bool AdjointTerms::*terms[] = {
      &AdjointTerms::mass,    &AdjointTerms::damping,         &AdjointTerms::alpha_f,
      &AdjointTerms::alpha_m, &AdjointTerms::velocity_update, &AdjointTerms::acceleration_update,
      &AdjointTerms::start,   &AdjointTerms::multipliers};
  const char* names[] = {"mass",    "damping",         "alpha_f",
                         "alpha_m", "velocity_update", "acceleration_update",
                         "start",   "multipliers"};
  for (size_t k = 0; k < std::size(terms); ++k) {
    AdjointTerms t;
    t.*terms[k] = false;
    const auto dropped = adjoint_sensitivities(cs, p, o, t);
    std::string w;
    const double e = worst(dropped, exact, &w);
    std::printf("without %-20s: %.2e (%s)\n", names[k], e, w.c_str());
    EXPECT_GT(e, 1e-4) << "dropping the term " << names[k] << " went unnoticed";
  }
}

TEST(Adjoint, AgreementDoesNotDegradeFromTenToAThousandSteps) {
  for (int n : {10, 100, 1000}) {
    Case cs = test::make_case(spring_crank(0.25 / n));
    const auto adj = run(cs, Method::kAdjoint), dir = run(cs, Method::kDirectAnalytic);
    EXPECT_GE(adj.counts.steps, n);  // a kink of the driver law may split one step
    std::string w;
    const double e = worst(adj, dir, &w);
    std::printf("%4d steps: adjoint vs direct-analytic %.2e (%s)\n", n, e, w.c_str());
    EXPECT_LT(e, 1e-9);
  }
}

TEST(Adjoint, CheckpointsAndRecomputationGiveTheFullStorageGradients) {
  Case cs = test::make_case(spring_crank(1e-3));
  const auto full = run(cs, Method::kAdjoint);
  // 250 steps of 7 unknowns (a few hundred bytes each): 0.02 MB holds about 45 states, so the
  // trajectory is stored at checkpoints and recomputed segment by segment
  const auto ck = run(cs, Method::kAdjoint, 0.02);
  std::printf("checkpointed: %ld steps recomputed, %.0f bytes (full storage %.0f)\n",
              ck.counts.adjoint_recomputed_steps, ck.counts.adjoint_memory_bytes,
              full.counts.adjoint_memory_bytes);
  EXPECT_GT(ck.counts.adjoint_recomputed_steps, 0);
  EXPECT_LE(ck.counts.adjoint_memory_bytes, 0.02e6);
  EXPECT_LT(ck.counts.adjoint_memory_bytes, full.counts.adjoint_memory_bytes);
  EXPECT_LT(worst(ck, full), 1e-12);
  // a bound that even √N checkpoints cannot meet: a clear error that names the option
  SensitivityOptions o;
  o.method = Method::kAdjoint;
  o.adjoint_memory_mb = 1e-4;
  try {
    compute_sensitivities(cs, cs.design->initial(), o);
    ADD_FAILURE() << "no error for a memory bound that cannot hold the checkpoints";
  } catch (const SetupError& e) {
    const std::string w = e.what();
    // the case key of the bound (the command line names its option, cli_end_to_end)
    EXPECT_EQ(e.subject(), "optimization.sensitivity.adjoint_memory_mb") << w;
    // the least memory it states (rounded up) works, 1 % less is refused
    const auto at = w.find("needs at least ");
    ASSERT_NE(at, std::string::npos) << w;
    const double need = std::stod(w.substr(at + 15));
    o.adjoint_memory_mb = need;
    const auto ok = compute_sensitivities(cs, cs.design->initial(), o);
    ASSERT_TRUE(ok.ok) << ok.message;
    EXPECT_LT(worst(ok, full), 1e-12);
    o.adjoint_memory_mb = 0.99 * need;
    EXPECT_THROW(compute_sensitivities(cs, cs.design->initial(), o), SetupError) << w;
  }
}

TEST(Adjoint, PerStepResponsesAreRefusedWithTheDirectMethodNamed) {
  json c = spring_crank(1e-3);
  c["output"]["responses"].push_back(
      {{"name", "x_per_step"}, {"measure", "piston.x"}, {"aggregate", "per_step"}});
  Case cs = test::make_case(c);
  SensitivityOptions o;
  o.method = Method::kAdjoint;
  try {
    compute_sensitivities(cs, cs.design->initial(), o);
    ADD_FAILURE() << "a per-step response was accepted";
  } catch (const SetupError& e) {
    EXPECT_NE(std::string(e.what()).find("direct-analytic"), std::string::npos) << e.what();
    // the entry at fault: the last response (/output/responses/<i> in a case file)
    EXPECT_EQ(e.subject(), "responses." + std::to_string(cs.responses.size() - 1));
  }
  o.adjoint_skip_per_step = true;  // what optimize sets: values kept, no gradient
  const auto r = compute_sensitivities(cs, cs.design->initial(), o);
  ASSERT_TRUE(r.ok);
  EXPECT_TRUE(std::isnan(r.responses.back().gradient(0, 0)));
  EXPECT_TRUE(std::isfinite(r.responses.front().gradient(0, 0)));
}

TEST(Adjoint, RobotArmFifteenVariablesAgreesWithDirectAndCentralDifferences) {
  Case cs = robot_arm_case();
  ASSERT_EQ(cs.design->size(), 15);
  const auto adj = run(cs, Method::kAdjoint), dir = run(cs, Method::kDirectAnalytic);
  std::string w;
  const double e = worst(adj, dir, &w);
  std::printf("robot arm (15 variables): adjoint vs direct-analytic %.2e (%s)\n", e, w.c_str());
  EXPECT_LT(e, 1e-9);
  const auto semi = run(cs, Method::kAdjointSemiAnalytical, 0, 1e-4);
  const auto semi6 = run(cs, Method::kAdjointSemiAnalytical, 0, 1e-6);
  const double e4 = worst(semi, adj), e6 = worst(semi6, adj);
  std::printf("adjoint-semi-analytical vs adjoint: Δp 1e-4 %.2e, 1e-6 %.2e\n", e4, e6);
  // a forward difference of μ(p) through the level-set map: O(Δp), so 100 times smaller at
  // a 100 times smaller step (until round-off ε/Δp ~ 1e-10)
  EXPECT_LT(e6, e4 / 20);
  EXPECT_GT(e4, 1e-8) << "the semi-analytical contraction is not a difference quotient";
}

TEST(Adjoint, CoarseRodOneHoleAgreesWithDirect) {
  json c = json::parse(std::ifstream(std::string(LSMBS_SOURCE_DIR) +
                                     "/data/slider_crank/slider_crank_1hole_coarse.json"));
  c["output"]["vtu_stride"] = 0;
  json scalar = json::array();
  for (const auto& r : c["output"]["responses"])
    if (r["aggregate"] != "per_step") scalar.push_back(r);
  scalar.push_back(
      {{"name", "mean_elongation"}, {"measure", "elongation"}, {"aggregate", "average"}});
  c["output"]["responses"] = scalar;
  Case cs = load_case_json(c, "<test>", std::string(LSMBS_SOURCE_DIR) + "/data/slider_crank");
  const auto adj = run(cs, Method::kAdjoint), dir = run(cs, Method::kDirectAnalytic);
  std::string w;
  const double e = worst(adj, dir, &w);
  std::printf("coarse rod: adjoint vs direct-analytic %.2e (%s)\n", e, w.c_str());
  EXPECT_LT(e, 1e-9);
}
