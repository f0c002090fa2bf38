// The §6 robot arm (solid plate, h = 0.005 s, ρ∞ = 0.8) runs through the whole trajectory.
// References: the plate mass equals ρ·t·area = 202.5 g; with the plate made 10⁴ times stiffer
// the tip follows the rigid forward kinematics of the drivers (the prescribed path, eq. 44)
// to within 10⁻³ of the flexible deviation; the tip ends at the rigid end pose (−1, 1) m up to
// the residual vibration. The deviation itself is reported for orientation (the paper's
// design with five small holes: 0.6037 mm).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "support/test_models.hpp"

using namespace lsmbs;

namespace {
Case robot_arm() {
  return load_case(std::string(LSMBS_SOURCE_DIR) + "/data/robot_arm/robot_arm.json");
}
}  // namespace

TEST(RobotArm, SolidPlateRunsTheTrajectoryAndReportsMassAndTipDeviation) {
  Case cs = robot_arm();
  const auto res = run_simulation(cs);
  ASSERT_TRUE(res.integrator.ok) << res.integrator.message;
  EXPECT_EQ(res.integrator.steps, 500);
  EXPECT_EQ(res.integrator.halvings, 0);
  EXPECT_NEAR(res.responses.at("plate_mass"), 2700 * 0.0025 * 0.6 * 0.05, 1e-12);
  const double avg = res.responses.at("average_tip_deviation"),
               mx = res.responses.at("max_tip_deviation");
  // constant-speed phase of θ1: [0.25, 2.0944] s → 369 grid steps of 0.005 s
  EXPECT_EQ(res.response_counts.at("average_tip_deviation"), 369);
  std::printf(
      "solid plate: mass %.4f g, average tip deviation %.4f mm, max %.4f mm (paper, 5 small holes: "
      "0.6037 mm)\n",
      1e3 * res.responses.at("plate_mass"), 1e3 * avg, 1e3 * mx);
  EXPECT_GT(avg, 0);
  EXPECT_LE(avg, mx);
  const auto x = res.column("tip.x"), y = res.column("tip.y");
  EXPECT_NEAR(x.back(), -1.0, 2 * mx);
  EXPECT_NEAR(y.back(), 1.0, 2 * mx);

  // Rigid limit: the deviation is a flexibility effect and vanishes with the compliance.
  Case stiff = robot_arm();
  stiff.model->params().scalars[stiff.model->parameter_index("plate.E")] *= 1e4;
  const auto rs = run_simulation(stiff);
  ASSERT_TRUE(rs.integrator.ok) << rs.integrator.message;
  std::printf("plate 1e4 times stiffer: average tip deviation %.3e mm\n",
              1e3 * rs.responses.at("average_tip_deviation"));
  EXPECT_LT(rs.responses.at("average_tip_deviation"), 1e-3 * avg);
}
