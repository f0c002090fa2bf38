// The mesh study's verdict (responses/mesh_convergence.hpp) against closed forms: responses that
// follow R(h) = R* + C h^p exactly give p, R* and the grid convergence index of Celik et al.
// (2008); the peak stress of a user's study (13.1, 16.8, 19.2 MPa at 128, 512 and 2048 elements),
// which `verify` passed, is not converged.
#include "lsmbs/responses/mesh_convergence.hpp"

#include <gtest/gtest.h>

#include <cmath>

using namespace lsmbs;

TEST(MeshConvergence, APowerLawGivesItsOrderLimitAndGci) {
  auto R = [](double h) { return 1 + 0.5 * h * h; };
  const auto m = mesh_convergence(R(0.4), R(0.2), R(0.1), 0.4, 0.2, 0.1, 1e-2);
  EXPECT_NEAR(m.order, 2.0, 1e-12);
  EXPECT_NEAR(m.extrapolated, 1.0, 1e-13);
  // GCI = 1.25 |ε21 / R1| / (2² − 1), ε21 = 0.5 (0.01 − 0.04)
  EXPECT_NEAR(m.gci, 1.25 * 0.015 / 1.005 / 3, 1e-14);
  EXPECT_EQ(m.verdict, MeshConvergence::Verdict::kConverged) << m.explanation;
  // the same response judged against a tighter tolerance
  EXPECT_FALSE(mesh_convergence(R(0.4), R(0.2), R(0.1), 0.4, 0.2, 0.1, 1e-3).pass());
}

TEST(MeshConvergence, UnequalRefinementRatiosRecoverTheOrder) {
  auto R = [](double h) { return 2 + std::pow(h, 1.5); };
  const auto m = mesh_convergence(R(0.3), R(0.2), R(0.1), 0.3, 0.2, 0.1, 1e-1);
  EXPECT_NEAR(m.order, 1.5, 1e-8);
  EXPECT_NEAR(m.extrapolated, 2.0, 1e-9);
  EXPECT_TRUE(m.pass()) << m.explanation;
}

TEST(MeshConvergence, AStressThatGrowsWithTheMeshIsNotConverged) {
  const double h[] = {1 / std::sqrt(128.0), 1 / std::sqrt(512.0), 1 / std::sqrt(2048.0)};
  const auto m = mesh_convergence(13.1e6, 16.8e6, 19.2e6, h[0], h[1], h[2], 1e-2);
  // p = ln(3.7/2.4)/ln 2, GCI = 1.25 (2.4/19.2) / (2^p − 1)
  const double p = std::log(3.7 / 2.4) / std::log(2.0);
  EXPECT_NEAR(m.order, p, 1e-9);
  EXPECT_NEAR(m.gci, 1.25 * (2.4 / 19.2) / (std::pow(2.0, p) - 1), 1e-9);
  EXPECT_EQ(m.verdict, MeshConvergence::Verdict::kNotConverged);
  EXPECT_NE(m.explanation.find("not converged in the mesh"), std::string::npos) << m.explanation;
}

TEST(MeshConvergence, DivergingOscillatingAndMeshIndependentResponses) {
  // growing changes: not converged, however small
  const auto up = mesh_convergence(1.0, 1.001, 1.003, 0.4, 0.2, 0.1, 1e-2);
  EXPECT_EQ(up.verdict, MeshConvergence::Verdict::kNotConverged);
  EXPECT_TRUE(std::isinf(up.gci));
  // oscillating with halving changes: p = 1 (ratio 2), GCI = 1.25 · 0.075/1.025
  const auto osc = mesh_convergence(1.1, 0.95, 1.025, 0.4, 0.2, 0.1, 1e-2);
  EXPECT_NEAR(osc.order, 1.0, 1e-12);
  EXPECT_NEAR(osc.gci, 1.25 * 0.075 / 1.025, 1e-12);
  EXPECT_FALSE(osc.pass());
  // a rigid body's response: the same on every mesh
  const auto rigid = mesh_convergence(0.25, 0.25, 0.25, 0.4, 0.2, 0.1, 1e-2);
  EXPECT_EQ(rigid.verdict, MeshConvergence::Verdict::kIndependent);
  EXPECT_TRUE(rigid.pass());
  EXPECT_FALSE(mesh_convergence(1, NAN, 1, 0.4, 0.2, 0.1, 1e-2).pass());
}
