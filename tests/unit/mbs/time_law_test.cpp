// Driver laws against closed forms and their derivatives against central differences.
#include "lsmbs/mbs/time_law.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "lsmbs/core/error.hpp"

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

namespace {

// Largest errors of a table's value, first and second derivatives against cos over [0, 2π]
// (10001 points), and the jumps of value, first and second derivative across the period
// boundary: |f⁽ᵏ⁾(x0 + δ) − f⁽ᵏ⁾(x0 + P − δ)| with δ = 1e-12. For a C² function these are
// 2δ|f⁽ᵏ⁺¹⁾| + round-off: at most 2e-12 for cos.
struct CosErrors {
  double value = 0, d1 = 0, d2 = 0, jump0 = 0, jump1 = 0, jump2 = 0;
};
CosErrors cos_errors(const Table1D& t) {
  CosErrors e;
  for (int i = 0; i <= 10000; ++i) {
    const double x = 2 * M_PI * i / 10000;
    double v, d1, d2;
    t.eval(x, v, d1, d2);
    e.value = std::max(e.value, std::abs(v - std::cos(x)));
    e.d1 = std::max(e.d1, std::abs(d1 + std::sin(x)));
    e.d2 = std::max(e.d2, std::abs(d2 + std::cos(x)));
  }
  const double delta = 1e-12;
  double vr, d1r, d2r, vl, d1l, d2l;
  t.eval(delta, vr, d1r, d2r);
  t.eval(2 * M_PI - delta, vl, d1l, d2l);
  e.jump0 = std::abs(vr - vl);
  e.jump1 = std::abs(d1r - d1l);
  e.jump2 = std::abs(d2r - d2l);
  return e;
}

std::vector<double> linspace(double a, double b, int n) {
  std::vector<double> x(n);
  for (int i = 0; i < n; ++i) x[i] = a + (b - a) * i / (n - 1);
  x.back() = b;
  return x;
}

}  // namespace

TEST(Table1D, PeriodicCubicSplineOfACosineIsC2AcrossThePeriodAndBeatsTheNaturalSpline) {
  // cos sampled on 33 points over [0, 2π] (h = π/16), first and last values equal.
  const std::vector<double> x = linspace(0, 2 * M_PI, 33);
  std::vector<double> y;
  for (double xi : x) y.push_back(std::cos(xi));
  y.back() = y.front();
  const Table1D periodic(x, y, Table1D::Interp::kCubic, 2 * M_PI);
  // What a periodic table was before: the natural spline through the same points, wrapped (on
  // [0, 2π] the same values as this unwrapped table; the jumps compare its two ends).
  const Table1D natural(x, y, Table1D::Interp::kCubic);
  const CosErrors p = cos_errors(periodic), n = cos_errors(natural);
  std::printf(
      "cos on 33 points: periodic spline |e| %.2e, |e'| %.2e, |e''| %.2e, jumps %.1e %.1e %.1e; "
      "natural spline |e| %.2e, |e'| %.2e, |e''| %.2e, jumps %.1e %.1e %.1e\n",
      p.value, p.d1, p.d2, p.jump0, p.jump1, p.jump2, n.value, n.d1, n.d2, n.jump0, n.jump1,
      n.jump2);
  // Interpolation error of a cubic spline with exact end conditions: (5/384) h⁴ max|f⁗| = 1.2e-5
  // for the value, (1/24) h³ max|f⁗| = 3.1e-4 for the derivative (Hall & Meyer 1976).
  const double h = M_PI / 16;
  EXPECT_LT(p.value, 5.0 / 384 * std::pow(h, 4));
  EXPECT_LT(p.d1, 1.0 / 24 * std::pow(h, 3));
  EXPECT_LT(p.jump0, 1e-14);
  EXPECT_LT(p.jump1, 3e-12);
  EXPECT_LT(p.jump2, 1e-12);
  // the natural spline forces s'' = 0 at the ends where cos'' = −1: its s' jumps at the boundary
  // and its errors near the ends are O(h²) instead of O(h⁴)
  EXPECT_GT(n.jump1, 0.05);
  EXPECT_GT(n.d2, 0.9);
  EXPECT_GT(n.value, 100 * p.value);
  EXPECT_GT(n.d1, 100 * p.d1);
}

TEST(Table1D, PeriodicCubicSplineConvergesAtFourthOrder) {
  // Errors against sin(x) + 0.3 cos(2x) for 17, 33, 65 points: ratio 2⁴ = 16 per halving of h.
  auto f = [](double x) { return std::sin(x) + 0.3 * std::cos(2 * x); };
  double prev = 0;
  for (int n : {17, 33, 65}) {
    const std::vector<double> x = linspace(0, 2 * M_PI, n);
    std::vector<double> y;
    for (double xi : x) y.push_back(f(xi));
    y.back() = y.front();
    const Table1D t(x, y, Table1D::Interp::kCubic, 2 * M_PI);
    double err = 0;
    for (int i = 0; i <= 4000; ++i) {
      const double xx = -3 + 12 * M_PI * i / 4000;  // several periods, negative arguments included
      err = std::max(err, std::abs(t.value(xx) - f(xx)));
    }
    if (prev > 0) {
      std::printf("periodic spline, %d points: error %.3e, ratio %.2f\n", n, err, prev / err);
      EXPECT_NEAR(prev / err, 16.0, 2.0);
    }
    prev = err;
  }
}

TEST(Table1D, PeriodicTableWithoutItsClosingPointAndWithFewPoints) {
  // Without the point at x0 + period, (x0 + period, y0) is implied.
  const std::vector<double> x = linspace(0, 2 * M_PI, 33);
  std::vector<double> y;
  for (double xi : x) y.push_back(std::cos(xi));
  const Table1D full(x, y, Table1D::Interp::kCubic, 2 * M_PI);
  const Table1D open(std::vector<double>(x.begin(), x.end() - 1),
                     std::vector<double>(y.begin(), y.end() - 1), Table1D::Interp::kCubic,
                     2 * M_PI);
  for (double xx : {0.1, 3.0, 6.2, 6.28, -0.05})
    EXPECT_NEAR(open.value(xx), full.value(xx), 1e-15) << xx;
  // Three points (a 2 × 2 cyclic system): through (0, 1), (π, −1), (2π, 1) the periodic spline
  // has second derivatives m0 = −m1 with (2π/3 − π/3) m0 = −4/π, i.e. s''(0) = −12/π²,
  // s''(π) = 12/π², and s'(0) = −2/π + (π/3)(12/π²) − (π/6)(12/π²) = 0.
  const Table1D three({0, M_PI, 2 * M_PI}, {1, -1, 1}, Table1D::Interp::kCubic, 2 * M_PI);
  double v, d1, d2, vp, d1p, d2p;
  three.eval(0, v, d1, d2);
  three.eval(M_PI, vp, d1p, d2p);
  EXPECT_NEAR(v, 1, 1e-15);
  EXPECT_NEAR(d1, 0, 1e-15);
  EXPECT_NEAR(d2, -12 / (M_PI * M_PI), 1e-15);
  EXPECT_NEAR(d2p, 12 / (M_PI * M_PI), 1e-15);
  // Four points (the smallest Sherman–Morrison case): C² across the period boundary.
  const Table1D four({0, 1, 2.5, 4}, {1e5, 3e5, 2e5, 1e5}, Table1D::Interp::kCubic, 4);
  four.eval(1e-12, v, d1, d2);
  four.eval(4 - 1e-12, vp, d1p, d2p);
  EXPECT_NEAR(d1, d1p, 1e-6);  // values of 1e5: round-off of the derivative ~1e5 ε / h
  EXPECT_NEAR(d2, d2p, 1e-5);
}

TEST(Table1D, PeriodicTableInputErrors) {
  auto error_of = [](std::vector<double> x, std::vector<double> y, double period) {
    try {
      Table1D(std::move(x), std::move(y), Table1D::Interp::kCubic, period);
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(
      error_of({0, 1, 2}, {0, 5, 1}, 2).find("a periodic table must end with its first value"),
      std::string::npos);
  EXPECT_NE(error_of({0, 1, 3}, {0, 5, 0}, 2).find("more than the period"), std::string::npos);
  EXPECT_EQ(error_of({0, 1, 2}, {0, 5, 0}, 2), "");
}

namespace {

// The message of Table1D::read_csv on a file with `text` (empty when it reads).
std::string table_error(const std::string& name, const std::string& text) {
  const std::string p = testing::TempDir() + name;
  {
    std::FILE* f = std::fopen(p.c_str(), "wb");
    std::fwrite(text.data(), 1, text.size(), f);
    std::fclose(f);
  }
  try {
    Table1D::read_csv(p, Table1D::Interp::kLinear);
  } catch (const Error& e) {
    return e.what();
  }
  return {};
}

}  // namespace

// A field is a number only if all of it is: the reader took "1.2x", "1.2rad" and "1 2" as 1.2,
// 1.2 and 1, stopped a number at a NUL byte, and ignored a third column, without a word. Each is
// refused with the file, the line and what was expected.
TEST(Table1D, ReadCsvRefusesFieldsThatAreNotWholeNumbers) {
  const std::string dir = testing::TempDir();
  struct Bad {
    std::string text, message;
  };
  const Bad bad[] = {
      {"0,0\n1,1.2x\n",
       "t.csv: line 2: y: expected a finite number, got '1.2x' (the whole field must be a number: "
       "no units)"},
      {"0,0\n1,1.2rad\n", "t.csv: line 2: y: expected a finite number, got '1.2rad'"},
      {"0,0\n1,1 2\n", "t.csv: line 2: y: expected a finite number, got '1 2'"},
      {"0,0\n1 2 3\n",
       "t.csv: line 2: expected two numbers x, y (separated by a comma, semicolon, tab or spaces), "
       "got 3 fields: '1', '2', '3'"},
      {std::string("0,0\n1,1\0"
                   "5\n",
                   10),
       "t.csv: line 2: y: expected a finite number, got '1\\x005'"},
      {"0,0,5\n1,1,7\n",
       "t.csv: line 1: expected two numbers x, y (separated by a comma, semicolon, "
       "tab or spaces), got 3 fields: '0', '0', '5'"},
      {"0;1,5\n1;2\n",
       "t.csv: line 1: expected two numbers x, y (separated by a comma, semicolon, "
       "tab or spaces), got 3 fields: '0', '1', '5'"},
      {"0\t\t1\n1\t2\n",  // an empty TSV cell is a field
       "t.csv: line 1: expected two numbers x, y (separated by a comma, semicolon, tab or spaces), "
       "got 3 fields: '0', '', '1'"},
      {"0,0\n1\n",
       "t.csv: line 2: expected two numbers x, y (separated by a comma, semicolon, tab "
       "or spaces), got 1 field: '1'"},
      {"0,0\nt,s\n1,1\n", "t.csv: line 2: x: expected a finite number, got 't'"},  // header: line 1
      {"1x,0\n2,1\n", "t.csv: line 1: x: expected a finite number, got '1x'"},     // not a header
      {"0,0\n1,1e999\n", "t.csv: line 2: y: expected a finite number, got '1e999'"},
      {"0,0\n1,nan\n", "t.csv: line 2: y: expected a finite number, got 'nan'"},
      {"0,0\n0x1,1\n", "t.csv: line 2: x: expected a finite number, got '0x1'"},
      {"0,0\n2,1\n1,2\n",
       "t.csv: line 3: x values must be strictly increasing: '1' does not exceed the x of line 2"},
  };
  for (const auto& b : bad) {
    const std::string msg = table_error("t.csv", b.text);
    EXPECT_NE(msg.find(dir + b.message), std::string::npos)
        << "file " << ::testing::PrintToString(b.text) << "\n  message: " << msg
        << "\n  expected: " << b.message;
  }
}

// What stays allowed reads exactly: a header on line 1 (also after a UTF-8 BOM), comments, blank
// lines, commas, semicolons, tabs or spaces, blanks around a separator, empty trailing fields.
TEST(Table1D, ReadCsvAcceptsEveryDocumentedLayout) {
  const std::string p = testing::TempDir() + "layouts.csv";
  {
    std::FILE* f = std::fopen(p.c_str(), "wb");
    std::fputs(
        "\xEF\xBB\xBFt [s];angle\r\n# a comment\n\n0;0\r\n1 , 2.5\n2\t-3e-1\n3  4 # note\n+4,5,\n",
        f);
    std::fclose(f);
  }
  const Table1D t = Table1D::read_csv(p, Table1D::Interp::kLinear);
  const double x[] = {0, 1, 2, 3, 4}, y[] = {0, 2.5, -0.3, 4, 5};
  EXPECT_EQ(t.x_min(), 0.0);
  EXPECT_EQ(t.x_max(), 4.0);
  for (int i = 0; i < 5; ++i) EXPECT_EQ(t.value(x[i]), y[i]) << "x = " << x[i];
}

// Every law at the time it starts and at each switch: the derivatives are those of the motion that
// follows (right-sided), against closed forms. They give a run's initial velocities and
// accelerations: a linear table from (0, 0) to (10 s, 1500 rad) is 150 rad/s from t = 0 (it
// was 0, and a crank driven by it started at rest and rang: 0, 297, 10.8, 278.6 rad/s).
TEST(TimeLaws, DerivativesAtTheStartAndAtEverySwitchAreThoseOfTheMotionThatFollows) {
  struct Expect {
    const char* what;
    const TimeLaw* law;
    double t, s, sd, sdd;
  };
  const TabulatedLaw linear(Table1D({0, 10}, {0, 1500}, Table1D::Interp::kLinear));
  const TabulatedLaw linear_kink(Table1D({0, 1, 2}, {0, 1, 3}, Table1D::Interp::kLinear));
  const TabulatedLaw cubic_line(Table1D({0, 1, 3, 4}, {1, 3, 7, 9}));  // y = 2x + 1 exactly
  // natural cubic spline through (0, 0), (1, 1), (2, 0): m1 = −3 (the one interior equation
  // 4 m1 = 6 (0 − 2·1 + 0)), so on [0, 1] y = 1.5 x − 0.5 x³: y'(0) = 1.5, y''(0) = 0;
  // on [1, 2] y'(1) = 0, y''(1) = −3
  const TabulatedLaw cubic_arc(Table1D({0, 1, 2}, {0, 1, 0}));
  const TabulatedLaw late(Table1D({0.5, 1.5}, {2, 4}, Table1D::Interp::kLinear));
  const RampLaw ramp(0.3, 400, 0.01);            // s̈ = 400/0.01 = 4e4 from t = 0
  const RampLaw ramp_late(0.3, 400, 0.01, 0.2);  // at rest until 0.2 s
  const TrapezoidLaw trap(0, 1, 4, 1);           // t_a = 0.25, t_c = 0.75
  const TrapezoidLaw trap_down(1, 0, 4, 1, 0.1);
  const ConstantLaw constant(2.5);
  const Expect cases[] = {
      {"linear table at its first point", &linear, 0, 0, 150, 0},
      {"linear table at a knot", &linear_kink, 1, 1, 2, 0},
      {"linear table at its last point", &linear_kink, 2, 3, 0, 0},
      {"linear table before its first point", &late, 0, 2, 0, 0},
      {"linear table starting later, at its first point", &late, 0.5, 2, 2, 0},
      {"cubic table of a line at its first point", &cubic_line, 0, 1, 2, 0},
      {"natural cubic at its first point", &cubic_arc, 0, 0, 1.5, 0},
      {"natural cubic at a knot", &cubic_arc, 1, 1, 0, -3},
      {"ramp at t = 0", &ramp, 0, 0.3, 0, 4e4},
      {"ramp at the end of the ramp", &ramp, 0.01, 0.3 + 2, 400, 0},
      {"ramp before its start", &ramp_late, 0.1, 0.3, 0, 0},
      {"ramp at its start", &ramp_late, 0.2, 0.3, 0, 4e4},
      {"trapezoid at t = 0", &trap, 0, 0, 0, 4},
      {"trapezoid at the end of the acceleration", &trap, 0.25, 0.125, 1, 0},
      {"trapezoid at the start of the deceleration", &trap, 1.0, 0.875, 1, -4},
      {"trapezoid at its end", &trap, 1.25, 1, 0, 0},
      {"decreasing trapezoid at its start", &trap_down, 0.1, 1, 0, -4},
      {"constant", &constant, 0, 2.5, 0, 0},
  };
  for (const Expect& e : cases) {
    double s, sd, sdd;
    e.law->eval(e.t, s, sd, sdd);
    const double tol = 1e-12 * std::max({1.0, std::abs(e.s), std::abs(e.sd), std::abs(e.sdd)});
    EXPECT_NEAR(s, e.s, tol) << e.what;
    EXPECT_NEAR(sd, e.sd, tol) << e.what;
    EXPECT_NEAR(sdd, e.sdd, tol) << e.what;
    // and the one-sided difference quotient of the motion after t agrees
    const double h = 1e-7;
    double sp, sdp, sddp;
    e.law->eval(e.t + h, sp, sdp, sddp);
    EXPECT_NEAR((sp - s) / h, sd, 1e-5 * std::max(1.0, std::abs(sd)) + 0.6 * h * std::abs(sdd))
        << e.what;
  }
}
