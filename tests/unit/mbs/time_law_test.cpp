// Driver laws against closed forms and their derivatives against central differences.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "lsmbs/mbs/time_law.hpp"

using namespace lsmbs;

TEST(TrapezoidLaw, RobotJointProfileMatchesTheClosedForm) {
  // §6: π/3 → π/2, 1 rad/s², 0.25 rad/s: t_a = 0.25 s, t_c = (π/6 − 0.0625)/0.25.
  TrapezoidLaw law(M_PI / 3, M_PI / 2, 1.0, 0.25);
  const double tc = (M_PI / 6 - 0.0625) / 0.25;
  EXPECT_NEAR(law.end_time(), 0.5 + tc, 1e-14);
  EXPECT_NEAR(law.end_time(), 2.344395, 1e-6);
  EXPECT_NEAR(law.value(0.25), M_PI / 3 + 0.03125, 1e-14);
  EXPECT_NEAR(law.value(10.0), M_PI / 2, 1e-14);
  const auto ph = law.phases();
  ASSERT_EQ(ph.size(), 3u);
  EXPECT_EQ(ph[1].name, "constant");
  EXPECT_NEAR(ph[1].t0, 0.25, 1e-15);
  EXPECT_NEAR(ph[1].t1, 0.25 + tc, 1e-14);
}

TEST(TimeLaws, DerivativesMatchCentralDifferencesAwayFromKinks) {
  TrapezoidLaw trap(1.0, 0.2, 2.0, 0.5, 0.1);
  RampLaw ramp(0.0, 4000 * 2 * M_PI / 60, 0.01);
  Table1D tab({0, 0.1, 0.25, 0.4, 0.6}, {0, 1, -0.5, 0.2, 2.0});
  TabulatedLaw tl(tab);
  const TimeLaw* laws[] = {&trap, &ramp, &tl};
  const double times[] = {0.05, 0.2, 0.33, 0.45, 0.52};
  for (const TimeLaw* l : laws)
    for (double t : times) {
      double s, sd, sdd, sp, sdp, sddp, sm, sdm, sddm;
      const double h = 1e-6;
      l->eval(t, s, sd, sdd);
      l->eval(t + h, sp, sdp, sddp);
      l->eval(t - h, sm, sdm, sddm);
      EXPECT_NEAR(sd, (sp - sm) / (2 * h), 1e-6 * std::max(1.0, std::abs(sd))) << "t = " << t;
      EXPECT_NEAR(sdd, (sdp - sdm) / (2 * h), 1e-4 * std::max(1.0, std::abs(sdd))) << "t = " << t;
    }
}

TEST(Table1D, CubicSplineReproducesLinearDataAndIsPeriodic) {
  Table1D t({0, 1, 3, 4}, {1, 3, 7, 9});  // y = 2x + 1
  double v, d1, d2;
  t.eval(2.5, v, d1, d2);
  EXPECT_NEAR(v, 6.0, 1e-14);
  EXPECT_NEAR(d1, 2.0, 1e-14);
  EXPECT_NEAR(d2, 0.0, 1e-14);
  Table1D p({0, 1, 2}, {0, 5, 0}, Table1D::Interp::kLinear, 2.0);
  EXPECT_NEAR(p.value(2.5), p.value(0.5), 1e-14);
  EXPECT_NEAR(p.value(-1.5), p.value(0.5), 1e-14);
}

TEST(Table1D, ReadsCsvWithHeaderCommentsAndScales) {
  const std::string p = testing::TempDir() + "law.csv";
  {
    std::FILE* f = std::fopen(p.c_str(), "w");
    std::fputs("time_ms,angle_deg  # header\n0,0\n# a comment line\n10, 90\n20;180\n", f);
    std::fclose(f);
  }
  const Table1D t = Table1D::read_csv(p, Table1D::Interp::kLinear, 0, 1e-3, M_PI / 180);
  EXPECT_NEAR(t.value(0.015), 0.75 * M_PI, 1e-14);
  EXPECT_NEAR(t.x_max(), 0.02, 1e-16);
}
