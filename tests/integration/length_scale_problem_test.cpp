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
