// Default options give exact gradients and converged steps on inputs nobody tuned (issue 18).
//  * The reproduction of the defect: the spring slider-crank at the default Newton tolerance and
//    h = 2.5e-4 s, where some steps converge in one Newton iteration (their only factorization is
//    the predictor's). The default gradient must equal central finite differences of whole
//    re-simulations at tight tolerances (independent reference), for every direct method.
//  * The Newton convergence test: the default run must equal a fully converged one (three Newton
//    iterations per step, tol_r 1e-14) at every h, and the order in h on a closed-loop four-bar
//    must be 2 against a fine-step reference.
#include <gtest/gtest.h>

#include <cmath>

#include "lsmbs/core/error.hpp"
#include "lsmbs/sensitivity/gradient_check.hpp"
#include "lsmbs/sensitivity/sensitivity.hpp"
#include "support/convergence.hpp"
#include "support/gradients.hpp"
#include "support/test_models.hpp"

using namespace lsmbs;
using json = nlohmann::json;
using Method = SensitivityOptions::Method;
using Matrix = SensitivityOptions::Matrix;

namespace {

// The spring slider-crank at the default Newton tolerance and step h; smooth responses only (a
// max switches its maximizer under finite differences).
json spring_crank_json(double h) {
  json c = test::spring_crank_json();
  c["simulation"].erase("tol_r");  // the default tolerance
  c["simulation"]["h"] = h;
  json keep = json::array();
  for (const auto& r : c["output"]["responses"])
    if (r["aggregate"] != "max") keep.push_back(r);
  c["output"]["responses"] = keep;
  return c;
}

// max over responses of max|g − g_ref| / max|g_ref|, both over every variable and (per-step
// responses) every step: relative to the largest gradient of each response
double worst_relative(const SensitivityResult& a, const SensitivityResult& ref) {
  return test::worst_relative(a, ref, test::Norm::kPerResponse);
}

SensitivityResult gradients(Case& cs, Method m, Matrix mx = SensitivityOptions{}.matrix,
                            double delta = 1e-6) {
  return test::gradients(cs, m, mx, delta);
}

// Reference: central differences of re-simulations converged far below the default tolerance.
SensitivityResult fd_reference(json c) {
  c["simulation"]["tol_r"] = 1e-14;
  c["simulation"]["min_iter"] = 3;
  Case cs = test::make_case(c);
  // Δp = 1e-5 relative: truncation 5e-8 of the largest gradient (1e-4: 5e-6, 1e-3: 5e-4 — it
  // falls as Δp², so 1e-5 is past the truncation-dominated range; round-off of the tight runs
  // stays below it down to 1e-6)
  return gradients(cs, Method::kFdCentral, Matrix::kRefined, 1e-5);
}

}  // namespace

TEST(GradientDefaults, SpringCrankAtDefaultToleranceMatchesCentralDifferences) {
  const json c = spring_crank_json(2.5e-4);
  const auto ref = fd_reference(c);
  Case cs = test::make_case(c);
  for (Method m : {Method::kDirectAnalytic, Method::kSemiAnalyticalCentral}) {
    const auto g = gradients(cs, m);
    // the reference's own error (Δp² truncation, ~1e-8) dominates
    EXPECT_LT(worst_relative(g, ref), 2e-7) << SensitivityOptions::name(m);
  }
  // Forward semi-analytical: exact up to its Δp truncation, which is first order — the error
  // falls tenfold with Δp (measured 6.1e-4, 6.1e-5, 6.1e-6 at δ = 1e-6, 1e-7, 1e-8: the
  // quadratic velocity terms of the rigid inertia under the perturbed rates of eq. 32).
  const double e6 =
      worst_relative(gradients(cs, Method::kSemiAnalytical, Matrix::kRefined, 1e-6), ref);
  const double e7 =
      worst_relative(gradients(cs, Method::kSemiAnalytical, Matrix::kRefined, 1e-7), ref);
  EXPECT_NEAR(e6 / e7, 10.0, 1.0) << e6 << " " << e7;
  // the two exact back-solve paths (refactorized at the converged state, the default; iterative
  // refinement with the step's factorization, or a fresh one) agree to round-off
  const auto def = gradients(cs, Method::kDirectAnalytic);
  EXPECT_EQ(SensitivityOptions{}.matrix, Matrix::kConverged);
  EXPECT_LT(worst_relative(def, gradients(cs, Method::kDirectAnalytic, Matrix::kRefined)), 1e-9);
}

TEST(GradientDefaults, LastIterationMatrixIsWrongWhereStepsTakeOneIterationAndWarns) {
  // The case exercises what broke the old default: steps whose only factorization is the
  // predictor's (at h = 6.25e-5 s about a third of the steps converge after one correction).
  // `last` (Algorithm 2 literally) is then off, and says so.
  Case cs = test::make_case(spring_crank_json(6.25e-5));
  const auto last = gradients(cs, Method::kDirectAnalytic, Matrix::kLastIteration);
  EXPECT_GT(last.counts.predictor_matrix_steps, 0);
  ASSERT_EQ(last.warnings.size(), 1u);
  EXPECT_NE(last.warnings[0].find("--matrix last"), std::string::npos);
  const auto exact = gradients(cs, Method::kDirectAnalytic);
  EXPECT_GT(worst_relative(last, exact), 1e-4);
  EXPECT_TRUE(exact.warnings.empty());
}

TEST(GradientDefaults, ModifiedNewtonKeepsTheDefaultExactAndRefusesLast) {
  json c = spring_crank_json(1e-3);
  const auto ref = fd_reference(c);
  for (const char* nw : {"modified", "modified_across_steps"}) {
    c["simulation"]["newton"] = nw;
    Case cs = test::make_case(c);
    EXPECT_LT(worst_relative(gradients(cs, Method::kDirectAnalytic), ref), 2e-7) << nw;
    EXPECT_LT(worst_relative(gradients(cs, Method::kDirectAnalytic, Matrix::kRefined), ref), 2e-7)
        << nw;
    SensitivityOptions o;
    o.matrix = Matrix::kLastIteration;
    try {
      compute_sensitivities(cs, cs.design->initial(), o);
      ADD_FAILURE() << nw << ": --matrix last accepted";
    } catch (const SetupError& e) {
      EXPECT_EQ(locate("c.json", e).json_path(), "/simulation/newton") << e.what();
    }
  }
}

namespace {

double final_value(json c, const std::string& response) {
  Case cs = test::make_case(c);
  const auto run = run_simulation(cs);
  EXPECT_TRUE(run.integrator.ok) << run.integrator.message;
  return run.responses.at(response);
}

}  // namespace

TEST(NewtonConvergence, DefaultRunEqualsAFullyConvergedRunAtEveryStepSize) {
  // The old test (one global force scale, a floor growing like h⁻²) accepted steps after one
  // correction from the predictor: 9.2e-8 rad off at h = 6.25e-5 s. Now round-off only.
  for (double h : {2.5e-4, 6.25e-5, 1.5625e-5}) {
    json c = spring_crank_json(h);
    const double def = final_value(c, "final_crank_angle");
    c["simulation"]["tol_r"] = 1e-14;
    c["simulation"]["min_iter"] = 3;
    EXPECT_LT(std::abs(def - final_value(c, "final_crank_angle")), 1e-12) << "h = " << h;
  }
}

TEST(NewtonConvergence, ClosedLoopFourBarConvergesAtOrderTwoWithDefaultOptions) {
  // A light four-bar (crank 4 g, 2e-7 kg m²; offset centres of mass) pushed by a 1.1 N force
  // against a 4530 N/m spring: constraint forces far above the forces that drive the motion,
  // as in the 7-body squeezer benchmark. Reference: h/512 with three iterations per step.
  const json base = json::parse(
      R"J({"name": "fourbar_order", "bodies": [{"name": "crank", "type": "rigid", "position": [0, 0], "angle": 0.6, "mass": 0.004, "inertia": 2e-07, "com": [0.012, 0.003], "angular_velocity": 0}, {"name": "coupler", "type": "rigid", "position": [0.02476006844729035, 0.01693927420185106], "angle": 0.4861210089130312, "mass": 0.07, "inertia": 1.2e-05, "com": [0.04, 0.005]}, {"name": "rocker", "type": "rigid", "position": [0.07, 0.0], "angle": 1.1319778676434364, "mass": 0.007, "inertia": 5.7e-07, "com": [0.03, -0.004]}], "joints": [{"name": "o2", "type": "revolute", "a": {"body": "crank", "at": [0, 0]}, "b": "ground"}, {"name": "pa", "type": "revolute", "a": {"body": "crank", "at": [0.03, 0]}, "b": {"body": "coupler", "at": [0, 0]}}, {"name": "pb", "type": "revolute", "a": {"body": "coupler", "at": [0.08, 0]}, "b": {"body": "rocker", "at": [0.06, 0]}}, {"name": "o4", "type": "revolute", "a": {"body": "rocker", "at": [0, 0]}, "b": "ground"}], "forces": [{"name": "spring", "type": "spring_damper", "a": {"body": "coupler", "at": [0.04, 0]}, "b": {"ground": [0.02, 0.09]}, "stiffness": 4530, "damping": 0, "free_length": 0.05}, {"name": "push", "type": "point_force", "point": {"body": "crank", "at": [0.03, 0]}, "force": [0, 1.1]}], "gravity": [0, 0], "simulation": {"t_end": 0.03, "h": 0.001}, "output": {"measures": [{"name": "rocker", "type": "angle", "body": "rocker"}, {"name": "crank", "type": "angle", "body": "crank"}], "responses": [{"name": "final_rocker", "measure": "rocker", "aggregate": "final"}, {"name": "final_crank", "measure": "crank", "aggregate": "final"}]}})J");
  auto at = [&](double h, bool tight) {
    json c = base;
    c["simulation"]["h"] = h;
    if (tight) {
      c["simulation"]["tol_r"] = 1e-14;
      c["simulation"]["min_iter"] = 3;
    }
    return final_value(c, "final_crank");
  };
  const double ref = at(1e-3 / 512, true);
  std::vector<double> err;
  for (int i = 0; i < 6; ++i) err.push_back(std::abs(at(1e-3 / std::pow(2.0, i), false) - ref));
  test::expect_order(err, 2.0, 0.05,
                     "four-bar, final crank angle, h = 1e-3 / 2^i, default options");
}

TEST(GradientCheck, PassesOnTheDefaultGradientAndCatchesAWrongOne) {
  Case cs = test::make_case(spring_crank_json(2.5e-4));
  const Vec p = cs.design->initial();
  const auto g = gradients(cs, Method::kDirectAnalytic);
  GradientCheckOptions o;
  const auto ok = check_gradients(cs, p, g.responses, o);
  ASSERT_TRUE(ok.ok) << ok.message;
  EXPECT_EQ(ok.simulations, 2);
  EXPECT_EQ(ok.entries.size(), g.responses.size());
  EXPECT_NEAR(ok.direction.norm(), 1.0, 1e-15);
  std::printf("gradient check on the default gradient: worst %.2e (%s)\n", ok.worst,
              ok.worst_response.c_str());
  EXPECT_LT(ok.worst, 1e-5);
  EXPECT_EQ(ok.verdict(o), "pass");
  // the same seed gives the same direction; the parameters are left at p
  EXPECT_EQ(check_gradients(cs, p, g.responses, o).direction, ok.direction);
  // the paper's literal matrix at h = 6.25e-5 s is off by ~1e-3: the check sees it
  Case cs2 = test::make_case(spring_crank_json(6.25e-5));
  const auto last = gradients(cs2, Method::kDirectAnalytic, Matrix::kLastIteration);
  const auto bad = check_gradients(cs2, cs2.design->initial(), last.responses, o);
  std::printf("gradient check on --matrix last: worst %.2e (%s)\n", bad.worst,
              bad.worst_response.c_str());
  EXPECT_GT(bad.worst, 1e-4);
  // a gradient 5 % off in every entry fails
  auto wrong = g.responses;
  for (auto& r : wrong) r.gradient *= 1.05;
  const auto caught = check_gradients(cs, p, wrong, o);
  EXPECT_GT(caught.worst, 0.04);
  EXPECT_NE(caught.verdict(o), "pass");
}
