// Design sensitivities (§4.3, Algorithm 2) against independent references:
//  * central finite differences of whole re-simulations (fd-central),
//  * the exact direct method (direct-analytic) for the semi-analytical variants,
// on the robot arm with five super-ellipses (coarse mesh, short horizon) and on the rigid
// slider-crank whose spring stiffness and damping are the design variables.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>

#include "lsmbs/core/error.hpp"
#include "lsmbs/sensitivity/sensitivity.hpp"
#include "support/test_models.hpp"

using namespace lsmbs;
using json = nlohmann::json;
using Method = SensitivityOptions::Method;

namespace {

// Gradient-check metric: for every response value (a per-step response has one per step),
// ‖g − g_ref‖∞ / ‖g_ref‖∞ over the design variables; the largest over all values. (Relative to
// the gradient's norm rather than entry-wise: components that are small by cancellation carry
// no relative accuracy in any method.)
double worst_relative(const SensitivityResult& a, const SensitivityResult& ref, std::string* where = nullptr) {
  double worst = 0;
  for (size_t r = 0; r < ref.responses.size(); ++r) {
    const Mat& A = a.responses[r].gradient;
    const Mat& B = ref.responses[r].gradient;
    EXPECT_EQ(A.rows(), B.rows());
    for (Eigen::Index i = 0; i < B.rows(); ++i) {
      const double n = B.row(i).cwiseAbs().maxCoeff();
      if (n == 0) continue;
      const double e = (A.row(i) - B.row(i)).cwiseAbs().maxCoeff() / n;
      if (e > worst) {
        worst = e;
        if (where) *where = ref.responses[r].name + "[" + std::to_string(i) + "]";
      }
    }
  }
  return worst;
}

SensitivityResult run(Case& cs, Method m, double delta = 1e-6, bool relative = true,
                      SensitivityOptions::Matrix mx = SensitivityOptions{}.matrix) {
  SensitivityOptions o;
  o.method = m;
  o.delta = delta;
  o.relative = relative;
  o.matrix = mx;
  auto r = compute_sensitivities(cs, cs.design->initial(), o);
  EXPECT_TRUE(r.ok) << r.message;
  return r;
}

// Robot arm of §6 with Table 5's initial holes, 60 × 5 mesh, 0.3 s; band 2 sub-cells so that
// finite differences of the geometry resolve the smoothing band (ε = 2.5 mm).
Case robot_arm_case() {
  json c = json::parse(std::ifstream(std::string(LSMBS_SOURCE_DIR) + "/data/robot_arm/robot_arm_holes.json"));
  c["bodies"][2]["mesh"]["elements"] = {60, 5};
  c["design"]["geometry"][0]["band"] = 2.0;
  c["simulation"]["t_end"] = 0.3;
  c["simulation"]["tol_r"] = 1e-11;
  c["output"]["vtu_stride"] = 0;
  c["output"]["measures"].push_back(
      {{"name", "plate_elongation"}, {"type", "elongation"}, {"a", {{"body", "plate"}, {"nearest", {0.2, 0.0}}}},
       {"b", {{"body", "plate"}, {"nearest", {0.8, 0.0}}}}});
  c["output"]["responses"] = json::parse(R"([
    {"name": "average_tip_deviation", "measure": "tip_deviation", "aggregate": "average", "window": {"t0": 0.1, "t1": 0.3}},
    {"name": "plate_mass", "measure": "plate_mass", "aggregate": "final"},
    {"name": "kinetic_energy_integral", "measure": "kinetic_energy", "aggregate": "integral"},
    {"name": "elongation_per_step", "measure": "plate_elongation", "aggregate": "per_step", "window": {"t0": 0.2, "t1": 0.3}}
  ])");
  return test::make_case(c);
}

Case slider_crank_case() {
  return load_case(std::string(LSMBS_SOURCE_DIR) + "/data/slider_crank_rigid/slider_crank_spring.json");
}

}  // namespace

TEST(Sensitivity, RobotArmDirectAnalyticMatchesCentralFiniteDifferences) {
  // Tight Newton iterations (three per step): Algorithm 2's last-iteration matrix is then that
  // of an essentially converged state. With two iterations per step its approximation costs
  // 1.5e-5 on the per-step elongation (see LastIterationMatrix… below and docs/verification.md).
  Case cs = robot_arm_case();
  cs.simulation.min_iter = 3;
  ASSERT_EQ(cs.design->size(), 15);
  const auto direct = run(cs, Method::kDirectAnalytic);
  // finite differences: absolute step 1e-5 m (all variables are lengths; a step relative to
  // |c_x| = 0.74 m would be comparable to the band)
  const auto fd = run(cs, Method::kFdCentral, 1e-5, false);
  EXPECT_EQ(fd.counts.simulations, 31);
  std::string where;
  const double e = worst_relative(direct, fd, &where);
  std::printf("robot arm: direct-analytic vs fd-central: worst %.2e (%s)\n", e, where.c_str());
  EXPECT_LT(e, 1e-5);
  ASSERT_EQ(direct.responses[3].values.size(), 21u) << "per-step response over [0.2, 0.3] s";
}

TEST(Sensitivity, RobotArmSemiAnalyticalCentralMatchesDirectAnalytic) {
  Case cs = robot_arm_case();
  const auto direct = run(cs, Method::kDirectAnalytic);
  const auto semi = run(cs, Method::kSemiAnalyticalCentral);
  std::string where;
  const double e = worst_relative(semi, direct, &where);
  std::printf("robot arm: semi-analytical-central vs direct-analytic: worst %.2e (%s)\n", e, where.c_str());
  EXPECT_LT(e, 1e-6);
  EXPECT_EQ(semi.counts.factorizations, direct.counts.factorizations) << "no factorization for the sensitivities";
  EXPECT_EQ(semi.counts.pseudo_load_residuals, 0) << "element-local pseudo-loads";
  // Algorithm 2 literally: 2 n_v whole perturbed residuals per step (plus the consistent start);
  // the same gradients up to round-off
  SensitivityOptions o;
  o.method = Method::kSemiAnalyticalCentral;
  o.full_residual = true;
  const auto full = compute_sensitivities(cs, cs.design->initial(), o);
  EXPECT_EQ(full.counts.pseudo_load_residuals, 2 * 15 * (full.counts.steps + 1));
  const double ef = worst_relative(semi, full);
  std::printf("element-local vs whole-residual pseudo-loads: %.2e\n", ef);
  EXPECT_LT(ef, 1e-6);
}

TEST(Sensitivity, SliderCrankSpringDamperAllMethodsAgreeWithTheConvergedMatrix) {
  Case cs = slider_crank_case();
  using M = SensitivityOptions::Matrix;
  const auto fd = run(cs, Method::kFdCentral, 1e-5);
  const auto direct = run(cs, Method::kDirectAnalytic, 1e-6, true, M::kRefined);
  const auto conv = run(cs, Method::kDirectAnalytic, 1e-6, true, M::kConverged);
  const auto semi = run(cs, Method::kSemiAnalyticalCentral, 1e-6, true, M::kRefined);
  std::string w1, w2, w3;
  const double e1 = worst_relative(direct, fd, &w1), e2 = worst_relative(semi, direct, &w2), e3 = worst_relative(direct, conv, &w3);
  std::printf("slider-crank: direct (refined) vs fd-central %.2e (%s); semi-central vs direct %.2e; refined vs converged %.2e\n",
              e1, w1.c_str(), e2, e3);
  EXPECT_LT(e1, 1e-5);
  EXPECT_LT(e2, 1e-6);
  EXPECT_LT(e3, 1e-9);
  EXPECT_EQ(direct.counts.factorizations, fd.counts.factorizations / 5) << "refinement adds no factorization";
}

TEST(Sensitivity, ModifiedNewtonAcrossStepsNeedsAnExactSensitivityMatrix) {
  // factorizations kept across steps are no matrix Algorithm 2 can back-solve with: refused with
  // the case path; with the converged matrix the gradients match central finite differences
  Case cs = slider_crank_case();
  const auto fd = run(cs, Method::kFdCentral, 1e-5);
  cs.simulation.newton = GeneralizedAlphaOptions::Newton::kModifiedAcrossSteps;
  SensitivityOptions o;
  o.method = Method::kDirectAnalytic;
  o.matrix = SensitivityOptions::Matrix::kLastIteration;
  try {
    compute_sensitivities(cs, cs.design->initial(), o);
    ADD_FAILURE() << "expected an error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("/simulation/newton"), std::string::npos) << e.what();
  }
  for (auto [threads, mx] : {std::pair{1, SensitivityOptions::Matrix::kConverged},
                             std::pair{2, SensitivityOptions::Matrix::kConverged},
                             std::pair{2, SensitivityOptions::Matrix::kRefined}}) {
    o.matrix = mx;
    o.threads = threads;
    const auto r = compute_sensitivities(cs, cs.design->initial(), o);
    ASSERT_TRUE(r.ok) << r.message;
    const double e = worst_relative(r, fd);
    std::printf("slider-crank, modified Newton across steps, converged matrix, %d thread(s): vs fd-central %.2e\n",
                threads, e);
    EXPECT_LT(e, 1e-5);
  }
}

TEST(Sensitivity, LastIterationMatrixErrorShrinksWithTighterNewtonIterations) {
  // Algorithm 2 back-solves with the last Newton iteration's matrix: exact only when the last
  // Newton increment vanishes. Forcing more iterations per step (min_iter) tightens it.
  Case cs = slider_crank_case();
  const auto fd = run(cs, Method::kFdCentral, 1e-5);
  using M = SensitivityOptions::Matrix;
  const double e2 = worst_relative(run(cs, Method::kDirectAnalytic, 1e-6, true, M::kLastIteration), fd);
  cs.simulation.min_iter = 3;
  const double e3 = worst_relative(run(cs, Method::kDirectAnalytic, 1e-6, true, M::kLastIteration), fd);
  std::printf("last-iteration matrix: worst vs fd-central %.2e (2 Newton iterations/step), %.2e (min_iter 3)\n", e2, e3);
  EXPECT_GT(e2, 1e-5) << "the approximation is visible on this fast mechanism";
  EXPECT_LT(e3, 1e-6) << "down to the finite-difference floor";
}

TEST(Sensitivity, SemiAnalyticalErrorFallsLinearlyWithDeltaThenRisesFromRoundOff) {
  // Robot arm (absolute nodal coordinates make the round-off branch visible). Same matrix for
  // all methods (refined), so only the pseudo-load differs.
  Case cs = robot_arm_case();
  using M = SensitivityOptions::Matrix;
  const auto direct = run(cs, Method::kDirectAnalytic, 1e-6, true, M::kRefined);
  auto err = [&](Method m, double d) { return worst_relative(run(cs, m, d, true, M::kRefined), direct); };
  const double f4 = err(Method::kSemiAnalytical, 1e-4), f5 = err(Method::kSemiAnalytical, 1e-5),
               f6 = err(Method::kSemiAnalytical, 1e-6), f10 = err(Method::kSemiAnalytical, 1e-10);
  // central: the asymptotic range (at 1e-3 the c_x step, 0.74 mm, is not small against the band)
  const double c4 = err(Method::kSemiAnalyticalCentral, 1e-4), c5 = err(Method::kSemiAnalyticalCentral, 1e-5);
  std::printf("forward: %.2e %.2e %.2e (delta 1e-4, 1e-5, 1e-6), %.2e (1e-10); central: %.2e %.2e (1e-4, 1e-5)\n", f4, f5,
              f6, f10, c4, c5);
  EXPECT_NEAR(std::log10(f4 / f5), 1.0, 0.15) << "slope 1 (forward)";
  EXPECT_NEAR(std::log10(f5 / f6), 1.0, 0.15) << "slope 1 (forward)";
  EXPECT_NEAR(std::log10(c4 / c5), 2.0, 0.3) << "slope 2 (central)";
  EXPECT_GT(f10, 10 * f6) << "round-off dominates for tiny delta";
}
