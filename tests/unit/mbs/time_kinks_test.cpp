// Kinks of time laws and tables (TimeLaw::kinks, Table1D::kinks): the times where IDAS stops
// and restarts (idas_ggl.cpp). The expected times are written from the laws' definitions, and
// each reported time is checked to be a real jump of the law's smoothest discontinuous
// derivative, with no jump anywhere else on a fine sampling.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "lsmbs/mbs/table.hpp"
#include "lsmbs/mbs/time_law.hpp"

namespace lsmbs {
namespace {

std::vector<double> sorted_unique(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  v.erase(
      std::unique(v.begin(), v.end(), [](double a, double b) { return std::abs(a - b) < 1e-12; }),
      v.end());
  return v;
}

void expect_times(const std::vector<double>& got, const std::vector<double>& want) {
  ASSERT_EQ(got.size(), want.size());
  for (size_t i = 0; i < want.size(); ++i) EXPECT_NEAR(got[i], want[i], 1e-12) << i;
}

// Jump of f (a derivative of order `order` of the law) across t: |f(t+) − f(t−)|.
double jump(const TimeLaw& law, int order, double t, double e = 1e-9) {
  double s[2], sd[2], sdd[2];
  law.eval(t - e, s[0], sd[0], sdd[0]);
  law.eval(t + e, s[1], sd[1], sdd[1]);
  const double* f = order == 0 ? s : order == 1 ? sd : sdd;
  return std::abs(f[1] - f[0]);
}

// Every reported kink is a jump of s̈ (drivers) and no other sampled point is.
void expect_kinks_are_the_jumps(const TimeLaw& law, double t0, double t1, int order, double big) {
  std::vector<double> k;
  law.kinks(t0, t1, k);
  k = sorted_unique(k);
  for (double t : k) EXPECT_GT(jump(law, order, t), big) << "no jump at reported kink t = " << t;
  for (int i = 1; i < 4000; ++i) {
    const double t = t0 + (t1 - t0) * (i + 0.5) / 4000;
    const bool near_kink =
        std::any_of(k.begin(), k.end(), [&](double x) { return std::abs(x - t) < 1e-6; });
    if (!near_kink) EXPECT_LT(jump(law, order, t), 1e-6 * big) << "unreported jump at t = " << t;
  }
}

TEST(TimeKinks, TrapezoidPhaseBoundaries) {
  // s 0 → 1, a = 4, v = 1, start 0.1: t_a = v/a = 0.25, t_c = (1 − a t_a²)/v = 0.75
  TrapezoidLaw law(0, 1, 4, 1, 0.1);
  std::vector<double> k;
  law.kinks(0, 10, k);
  expect_times(sorted_unique(k), {0.1, 0.35, 1.1, 1.35});
  expect_kinks_are_the_jumps(law, 0, 2, 2, 1.0);
  k.clear();
  law.kinks(0.35, 1.2, k);  // open interval: the ends are excluded
  expect_times(sorted_unique(k), {1.1});
}

TEST(TimeKinks, TriangularTrapezoid) {
  // distance 0.04 < a (v/a)² = 0.25: triangular, t_a = sqrt(0.04/4) = 0.1
  TrapezoidLaw law(0, -0.04, 4, 1, 0.1);
  std::vector<double> k;
  law.kinks(0, 1, k);
  expect_times(sorted_unique(k), {0.1, 0.2, 0.3});
  expect_kinks_are_the_jumps(law, 0, 0.5, 2, 1.0);
}

TEST(TimeKinks, RampEndsItsRamp) {
  RampLaw law(0, 10, 0.2, 0.05);  // s̈ = 50 on (0.05, 0.25), 0 elsewhere
  std::vector<double> k;
  law.kinks(0, 1, k);
  expect_times(sorted_unique(k), {0.05, 0.25});
  expect_kinks_are_the_jumps(law, 0, 1, 2, 1.0);
}

TEST(TimeKinks, LinearTableKnotsAndEnds) {
  TabulatedLaw law(Table1D({0, 1, 2, 4}, {0, 1, 3, 2}, Table1D::Interp::kLinear));
  std::vector<double> k;
  law.kinks(-1, 5, k);
  expect_times(sorted_unique(k), {0, 1, 2, 4});
  expect_kinks_are_the_jumps(law, -1, 5, 1, 0.25);  // ṡ jumps at every knot (by 0.5 at least)
  k.clear();
  law.kinks(0.5, 3, k);
  expect_times(sorted_unique(k), {1, 2});
}

TEST(TimeKinks, PeriodicLinearTableRepeatsItsKnots) {
  // period 4: the point (4, 0) closes the period; knots at every integer
  TabulatedLaw law(
      Table1D({0, 1, 2, 3}, {0, 2, 3, -1}, Table1D::Interp::kLinear, 4));  // slopes 2, 1, −4, 1
  std::vector<double> k;
  law.kinks(0, 9, k);
  expect_times(sorted_unique(k), {1, 2, 3, 4, 5, 6, 7, 8});
  expect_kinks_are_the_jumps(law, 0.5, 8.5, 1, 0.5);
}

TEST(TimeKinks, CubicTablesOnlyAtTheHeldEnds) {
  TabulatedLaw open(Table1D({0, 1, 2, 3}, {0, 1, 0, 2}));
  std::vector<double> k;
  open.kinks(-1, 4, k);
  expect_times(sorted_unique(k), {0, 3});  // held constant beyond the ends: ṡ jumps
  expect_kinks_are_the_jumps(open, -1, 4, 1, 0.1);
  const double pi = std::acos(-1.0);
  std::vector<double> x, y;
  for (int i = 0; i < 16; ++i) x.push_back(2 * pi * i / 16), y.push_back(std::cos(x.back()));
  TabulatedLaw periodic(Table1D(x, y, Table1D::Interp::kCubic, 2 * pi));
  k.clear();
  periodic.kinks(-10, 30, k);
  EXPECT_TRUE(k.empty());  // the periodic spline is C² everywhere
}

}  // namespace
}  // namespace lsmbs
