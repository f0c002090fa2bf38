// Length-scale constraints in an optimization problem (DesignProblem, optimization.length_scale)
// on the getting-started arm (a 400 × 30 mm plate, circular holes of radii r1, r2 at x = 120 and
// 280 mm on its axis), against closed forms: the ligament between the holes, 160 mm − r1 − r2,
// is beyond 3δ and reported as 3δ; a hole's edge ligament is 15 mm − r, its width 2r. The
// constraints are appended after the responses', as lower bounds (g = −value ≤ −δ); their rows are
// the same, to the bit, whatever the sensitivity method (they do not depend on the motion). A
// design that violates them is moved to the nearest one that keeps them (the multi-start's
// screening): only r2 changes, to where its edge ligament is δ within the aggregation's bound.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

#include "lsmbs/io/case.hpp"
#include "lsmbs/io/optimization_spec.hpp"
#include "lsmbs/optimization/problem.hpp"
#include "support/test_models.hpp"

using namespace lsmbs;
using json = nlohmann::json;

namespace {

json arm(const std::string& method) {
  json j = json::parse(
      std::ifstream(std::string(LSMBS_SOURCE_DIR) + "/examples/getting_started/flexible_arm.json"));
  j["simulation"]["t_end"] = 0.05;
  j["output"]["vtu_stride"] = 0;
  j["optimization"]["length_scale"] = {{"min_size", 0.004}};
  j["optimization"]["sensitivity"] = {{"method", method}};
  return j;
}

int row(const DesignProblem& P, const std::string& name) {
  const auto& n = P.constraint_names();
  const auto it = std::find(n.begin(), n.end(), name);
  return it == n.end() ? -1 : static_cast<int>(it - n.begin());
}

}  // namespace

TEST(LengthScaleProblem, ConstraintsMatchTheClosedFormsInEveryMethod) {
  const Case direct = test::make_case(arm("direct-analytic"));
  const Case adjoint = test::make_case(arm("adjoint"));
  DesignProblem P(conditions_of(direct), parse_optimization(direct));
  DesignProblem Q(conditions_of(adjoint), parse_optimization(adjoint));
  const int lig = row(P, "-length_scale.arm.ligament.hole1.hole2");
  const int e2 = row(P, "-length_scale.arm.edge.hole2");
  const int m1 = row(P, "-length_scale.arm.member.hole1");
  ASSERT_GE(lig, 1) << "after the response's constraint";
  ASSERT_GE(e2, 0);
  ASSERT_GE(m1, 0);
  EXPECT_EQ(P.num_constraints(), 1 + 1 + 2 + 2);  // rms, ligament, 2 edges, 2 members
  const Vec p = (Vec(2) << 0.006, 0.012).finished();
  const Evaluation& a = P.evaluate(p);
  const Evaluation& b = Q.evaluate(p);
  ASSERT_TRUE(a.ok && b.ok) << a.message << b.message;
  const double err = 0.05 * 0.004;  // the KS bound: tolerance · δ
  // the ligament, 142 mm, is beyond 3δ: reported as 3δ with no gradient (the bound holds by far)
  EXPECT_EQ(-a.constraints[lig], 3 * 0.004);
  EXPECT_EQ(a.constraint_gradient.row(lig).norm(), 0);
  EXPECT_GE(-a.constraints[e2], 0.003 - err);  // 15 − 12 mm, under its 4 mm bound
  EXPECT_LE(-a.constraints[e2], 0.003 + 1e-6);
  EXPECT_NEAR(-a.constraints[m1], 0.012, 1e-15);
  EXPECT_EQ(a.upper[e2], -0.004);
  EXPECT_NEAR(a.max_violation, (0.004 + a.constraints[e2]) / 0.004, 1e-15);
  // ∂(15 mm − r2)/∂r2 = −1 (the samples along the edge weigh in by the cosine of their angle)
  EXPECT_NEAR(a.constraint_gradient(e2, 1), 1, 5e-3);
  EXPECT_EQ(a.constraint_gradient(e2, 0), 0);
  for (int k = 1; k < P.num_constraints(); ++k) {
    EXPECT_EQ(a.constraints[k], b.constraints[k]);
    EXPECT_EQ(a.constraint_gradient.row(k), b.constraint_gradient.row(k));
  }
  double v = 0;
  const Vec q = P.admissible_start(p, &v);
  EXPECT_LE(v, 1e-3);
  EXPECT_NEAR(q[0], 0.006, 1e-6);
  EXPECT_GE(q[1], 0.011 - err);
  EXPECT_LE(q[1], 0.011 + 1e-6);
}

// The same on a solid body (data/spatial/solid_arm.json: a 400 × 10 × 80 mm plate of 20 mm
// bricks, sampled at 5 mm; holes of radii r1, r2 through its 10 mm thickness at x = 100 and
// 200 mm, and a super-ellipse pocket (a = 50, b = 25 mm, at x = 310 mm) machined to `depth` from
// its +y face), against closed forms: hole1's edge ligament is 40 mm − r1 (the faces it passes
// through are not edges), the pocket's is its floor, 10 mm − depth; the ligaments between the
// features (54 and 44 mm) are beyond 3δ. The rows are the same in every method.
TEST(LengthScaleProblem, SolidBodyConstraintsMatchTheClosedForms) {
  auto solid_arm = [](const std::string& method) {
    json j =
        json::parse(std::ifstream(std::string(LSMBS_SOURCE_DIR) + "/data/spatial/solid_arm.json"));
    j["simulation"]["t_end"] = 0.003;
    j["optimization"] = {
        {"objective", "plate_mass"},
        {"constraints", json::array({{{"response", "mean_tip_z"}, {"lower", -1}}})},
        {"length_scale", {{"min_size", 0.004}}},
        {"sensitivity", {{"method", method}}}};
    return j;
  };
  const Case direct = test::make_case(solid_arm("direct-analytic"));
  const Case adjoint = test::make_case(solid_arm("adjoint"));
  DesignProblem P(conditions_of(direct), parse_optimization(direct));
  DesignProblem Q(conditions_of(adjoint), parse_optimization(adjoint));
  EXPECT_EQ(P.num_constraints(), 1 + 3 + 3 + 3);  // response, 3 ligaments, 3 edges, 3 members
  const int e1 = row(P, "-length_scale.plate.edge.hole1");
  const int ep = row(P, "-length_scale.plate.edge.pocket");
  const int lig = row(P, "-length_scale.plate.ligament.hole2.pocket");
  const int m1 = row(P, "-length_scale.plate.member.hole1");
  ASSERT_GE(e1, 1);
  ASSERT_GE(ep, 1);
  ASSERT_GE(lig, 1);
  ASSERT_GE(m1, 1);
  const Vec p = (Vec(3) << 0.03, 0.016, 0.007).finished();
  const Evaluation& a = P.evaluate(p);
  const Evaluation& b = Q.evaluate(p);
  ASSERT_TRUE(a.ok && b.ok) << a.message << b.message;
  const double err = 0.05 * 0.004;
  // face samples 2.5 mm off the foot along x: 0.08 mm above 10 mm
  EXPECT_GE(-a.constraints[e1], 0.010 - err);
  EXPECT_LE(-a.constraints[e1], 0.010 + 1e-4);
  EXPECT_NEAR(a.constraint_gradient(e1, 0), 1, 1e-2);  // g = −value: ∂/∂r1 = +1
  EXPECT_GE(-a.constraints[ep], 0.003 - err);
  EXPECT_LE(-a.constraints[ep], 0.003 + 1e-9);
  EXPECT_NEAR(a.constraint_gradient(ep, 2), 1, 1e-2);
  EXPECT_EQ(-a.constraints[lig], 3 * 0.004);
  EXPECT_EQ(a.constraint_gradient.row(lig).norm(), 0);
  EXPECT_NEAR(-a.constraints[m1], 0.06, 1e-15);
  for (int k = 1; k < P.num_constraints(); ++k) {
    EXPECT_EQ(a.constraints[k], b.constraints[k]);
    EXPECT_EQ(a.constraint_gradient.row(k), b.constraint_gradient.row(k));
  }
  // no_cut needs a boundary curve: refused on a solid body, naming the key
  json j = solid_arm("direct-analytic");
  j["optimization"]["length_scale"]["no_cut"] = 0.004;
  const Case cut = test::make_case(j);
  try {
    DesignProblem R(conditions_of(cut), parse_optimization(cut));
    ADD_FAILURE() << "no_cut accepted on a solid body";
  } catch (const SetupError& e) {
    EXPECT_NE(std::string(e.what()).find("optimization.length_scale.no_cut"), std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("min_edge"), std::string::npos) << e.what();
  }
}
