// Length-scale constraints (geometry/length_scale.hpp) against closed forms and central
// differences, on a 200 × 50 mm plate of 5 mm elements (sampling 1.25 mm):
//   - the ligament between two circular holes of radii r₁, r₂ whose centres are L apart is
//     L − r₁ − r₂, and between two super-ellipses (ξ = η = 5) side by side the gap between their
//     flat sides; the KS value lies within [true − tolerance·δ, true + sampling error];
//   - a super-ellipse centred at mid-height has the edge ligament 25 mm − b;
//   - a notch (a hole centred on the top edge) keeps the bottom edge: no_cut is the bottom
//     ligament; a hole taller than the plate cuts it: no_cut is negative; a hole at mid-height
//     has no_cut equal to its farther edge ligament;
//   - a member's width is 2·min(a, b)·d for an ellipse;
//   - the exact super-ellipse distance against a polygon of 20 000 points of its boundary;
//   - every gradient against central differences of the value (h = 1e-6 m).
#include "lsmbs/geometry/length_scale.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

using namespace lsmbs;

namespace {

ParamBinding var(int k) { return {0, 1, k}; }
ParamBinding constant(double v) { return {v, 0, -1}; }

const Mesh2D& plate() {
  static const Mesh2D m = Mesh2D::rectangle(0, 0, 0.2, 0.05, 40, 10);
  return m;
}

// p = (cx1, r1, cx2, r2): two circles at mid-height
LevelSet circles() {
  std::vector<Feature> f = {
      Feature("A", Feature::Type::kCircle, {var(0), constant(0.025), var(1)}, true),
      Feature("B", Feature::Type::kCircle, {var(2), constant(0.025), var(3)}, true)};
  return LevelSet(std::move(f), LevelSetNode::all_of(2), 4);
}

// p = (cx, cy, a, b) of super-ellipse S (ξ = η = 5) and a fixed one T at (0.15, 0.025), 10 mm
LevelSet super_ellipses() {
  std::vector<Feature> f = {
      Feature("S", Feature::Type::kSuperEllipse,
              {var(0), var(1), var(2), var(3), constant(5), constant(5), constant(0)}, true),
      Feature("T", Feature::Type::kSuperEllipse,
              {constant(0.15), constant(0.025), constant(0.01), constant(0.01), constant(5),
               constant(5), constant(0)},
              true)};
  return LevelSet(std::move(f), LevelSetNode::all_of(2), 4);
}

const LengthScaleConstraint& find(const std::vector<LengthScaleConstraint>& c,
                                  const std::string& name) {
  for (const auto& x : c)
    if (x.name() == name) return x;
  throw std::runtime_error("no constraint " + name);
}

// the gradient of every constraint against central differences of its value
void check_gradients(const LengthScale& L, const Vec& p) {
  const auto c0 = L.evaluate(p);
  const double h = 1e-6;
  for (int k = 0; k < p.size(); ++k) {
    Vec pp = p, pm = p;
    pp[k] += h, pm[k] -= h;
    const auto cp = L.evaluate(pp), cm = L.evaluate(pm);
    for (size_t j = 0; j < c0.size(); ++j) {
      const double fd = (cp[j].value - cm[j].value) / (2 * h);
      EXPECT_NEAR(c0[j].gradient[k], fd, 1e-5 + 1e-5 * std::abs(fd))
          << c0[j].name() << " d/dp" << k;
    }
  }
}

}  // namespace

TEST(LengthScale, LigamentBetweenCirclesIsTheirGap) {
  const LevelSet ls = circles();
  LengthScaleOptions o;
  o.min_ligament = 0.01;
  const LengthScale L(plate(), ls, 2, o);
  const Vec p = (Vec(4) << 0.06, 0.012, 0.105, 0.015).finished();
  const auto c = L.evaluate(p);
  ASSERT_EQ(c.size(), 1u);
  const double exact = 0.105 - 0.06 - 0.012 - 0.015;  // 18 mm
  EXPECT_LE(c[0].value, exact + 1e-6);
  EXPECT_GE(c[0].value, exact - c[0].error_bound);
  EXPECT_NEAR(c[0].error_bound, 0.05 * 0.01, 1e-15);
  // moving B right by dx widens the gap by dx; growing A narrows it (the aggregate weighs samples
  // off the line of centres, where the sum grows by less: within 0.5 %)
  EXPECT_NEAR(c[0].gradient[2], 1, 5e-3);
  EXPECT_NEAR(c[0].gradient[1], -1, 5e-3);
  check_gradients(L, p);
  // overlapping holes: a negative ligament
  const Vec q = (Vec(4) << 0.06, 0.012, 0.07, 0.015).finished();
  EXPECT_LT(L.evaluate(q)[0].value, -0.01);
}

TEST(LengthScale, LigamentBetweenSuperEllipsesAndEdge) {
  const LevelSet ls = super_ellipses();
  LengthScaleOptions o;
  o.min_ligament = o.min_edge = 0.01;
  const LengthScale L(plate(), ls, 2, o);
  const Vec p = (Vec(4) << 0.11, 0.025, 0.012, 0.016).finished();
  const auto c = L.evaluate(p);
  const auto& lig = find(c, "ligament.S.T");
  const double gap = (0.15 - 0.01) - (0.11 + 0.012);  // flat sides: 18 mm
  EXPECT_LE(lig.value, gap + 1e-6);
  EXPECT_GE(lig.value, gap - lig.error_bound);
  const auto& edge = find(c, "edge.S");
  EXPECT_LE(edge.value, 0.025 - 0.016 + 1e-6);
  EXPECT_GE(edge.value, 0.025 - 0.016 - edge.error_bound);
  EXPECT_NEAR(edge.gradient[3], -1, 5e-3);  // ∂/∂b
  check_gradients(L, p);
  // rotated and off-centre
  const Vec q = (Vec(4) << 0.09, 0.021, 0.014, 0.011).finished();
  check_gradients(L, q);
}

TEST(LengthScale, NoCutAllowsANotchButNotACut) {
  std::vector<Feature> f = {
      Feature("N", Feature::Type::kEllipse,
              {constant(0.1), var(0), constant(0.01), var(1), constant(1), constant(0)}, true)};
  const LevelSet ls(std::move(f), LevelSetNode::all_of(1), 2);
  LengthScaleOptions o;
  o.no_cut = 0.01;
  const LengthScale L(plate(), ls, 1, o);
  // centred on the top edge, 15 mm deep: the bottom keeps 35 mm (above 3δ: reported as 3δ)
  EXPECT_NEAR(L.evaluate((Vec(2) << 0.05, 0.015).finished())[0].value, 0.03, 1e-12);
  // 40 mm deep: the bottom keeps 10 mm
  const Vec deep = (Vec(2) << 0.05, 0.04).finished();
  const auto c = L.evaluate(deep);
  EXPECT_LE(c[0].value, 0.01 + 1e-6);
  EXPECT_GE(c[0].value, 0.01 - c[0].error_bound);
  check_gradients(L, deep);
  // centred at mid-height and 60 mm tall: through both edges
  EXPECT_LT(L.evaluate((Vec(2) << 0.025, 0.03).finished())[0].value, -0.004);
  // at y = 20 mm, 12 mm tall: 8 mm below, 18 mm above
  const auto mid = L.evaluate((Vec(2) << 0.02, 0.012).finished());
  EXPECT_LE(mid[0].value, 0.018 + 1e-6);
  EXPECT_GE(mid[0].value, 0.018 - mid[0].error_bound);
}

TEST(LengthScale, MemberSizeOfAnEllipse) {
  std::vector<Feature> f = {
      Feature("E", Feature::Type::kEllipse,
              {constant(0.1), constant(0.025), var(0), var(1), var(2), constant(0.3)}, true)};
  const LevelSet ls(std::move(f), LevelSetNode::all_of(1), 3);
  LengthScaleOptions o;
  o.min_member = 0.01;
  const LengthScale L(plate(), ls, 1, o);
  const Vec p = (Vec(3) << 0.006, 0.012, 1.1).finished();
  const auto c = L.evaluate(p);
  ASSERT_EQ(c.size(), 1u);
  EXPECT_LE(c[0].value, 2 * 0.006 * 1.1);
  EXPECT_GE(c[0].value, 2 * 0.006 * 1.1 - c[0].error_bound);
  check_gradients(L, p);
}

TEST(LengthScale, SuperEllipseDistanceIsExact) {
  // the edge ligament of a hole near the top edge, rotated, against the least distance from the
  // edge's samples to a polygon of 20 000 boundary points
  std::vector<Feature> f = {Feature("S", Feature::Type::kSuperEllipse,
                                    {constant(0.1), constant(0.03), constant(0.012),
                                     constant(0.006), constant(3), constant(6), constant(0.4)},
                                    true)};
  const LevelSet ls(std::move(f), LevelSetNode::all_of(1), 0);
  LengthScaleOptions o;
  o.min_edge = 0.01;
  o.tolerance = 1e-3;
  o.spacing = 1e-4;  // the sampling error along the edge, s²/(8R), below 1e-6 for R ≥ 1.25 mm
  const LengthScale L(plate(), ls, 1, o);
  const auto c = L.evaluate(Vec());
  double best = 1e9;
  const int n = 20000;
  for (int k = 0; k < n; ++k) {
    const double t = 2 * std::numbers::pi * k / n, ct = std::cos(t), st = std::sin(t);
    const double u = 0.012 * std::copysign(std::pow(std::abs(ct), 2.0 / 3), ct);
    const double v = 0.006 * std::copysign(std::pow(std::abs(st), 2.0 / 6), st);
    const double y = 0.03 + std::sin(0.4) * u + std::cos(0.4) * v;
    best = std::min(best, 0.05 - y);  // the top edge y = 0.05 is the nearest
  }
  EXPECT_LE(c[0].value, best + 2e-6);
  EXPECT_GE(c[0].value, best - c[0].error_bound - 2e-6);
}

TEST(LengthScale, BSplineHoleLigamentsAgainstItsCurve) {
  // a closed B-spline hole (8 control points, 16 variables) beside a circle (cx, r variables):
  // its ligament to the circle and to the top edge against the curve sampled at 40 000 points
  // (uniform cubic B-spline, written out here), and every gradient against central differences
  const int n = 8;
  Vec p(n * 2 + 2);
  std::vector<ParamBinding> cps;
  for (int i = 0; i < n; ++i) {
    const double t = 2 * std::numbers::pi * i / n;
    p[2 * i] = 0.06 + 0.022 * std::cos(t) + 0.003 * std::sin(3 * t);
    p[2 * i + 1] = 0.025 + 0.014 * std::sin(t);
    cps.push_back(var(2 * i)), cps.push_back(var(2 * i + 1));
  }
  p[2 * n] = 0.11, p[2 * n + 1] = 0.012;
  std::vector<Feature> f = {
      Feature("F", Feature::Type::kBSpline, cps, true),
      Feature("C", Feature::Type::kCircle, {var(2 * n), constant(0.025), var(2 * n + 1)}, true)};
  const LevelSet ls(std::move(f), LevelSetNode::all_of(2), 2 * n + 2);
  LengthScaleOptions o;
  o.min_ligament = o.min_edge = 0.01;
  const LengthScale L(plate(), ls, 2, o);
  const auto c = L.evaluate(p);
  auto P = [&](int i) {
    const int k = (i % n + n) % n;
    return Vec2(p[2 * k], p[2 * k + 1]);
  };
  double to_circle = 1e9, top = 1e9;
  const int m = 5000;
  for (int i = 0; i < n; ++i)
    for (int s = 0; s < m; ++s) {
      const double t = double(s) / m, t2 = t * t, t3 = t2 * t;
      const Vec2 x = ((1 - t) * (1 - t) * (1 - t) * P(i - 1) + (3 * t3 - 6 * t2 + 4) * P(i) +
                      (-3 * t3 + 3 * t2 + 3 * t + 1) * P(i + 1) + t3 * P(i + 2)) /
                     6;
      to_circle = std::min(to_circle, (x - Vec2(0.11, 0.025)).norm() - 0.012);
      top = std::min(top, 0.05 - x.y());
    }
  const auto& lig = find(c, "ligament.F.C");
  const auto& edge = find(c, "edge.F");
  std::printf("B-spline hole: ligament %.6f mm (curve %.6f), edge %.6f mm (curve %.6f)\n",
              1e3 * lig.value, 1e3 * to_circle, 1e3 * edge.value, 1e3 * top);
  // the sampling adds at most s²/(8R) (s = 1.25 mm, R ≥ 12 mm: 1.6e-5 m)
  EXPECT_LE(lig.value, to_circle + 2e-5);
  EXPECT_GE(lig.value, to_circle - lig.error_bound);
  EXPECT_LE(edge.value, top + 2e-5);
  EXPECT_GE(edge.value, top - edge.error_bound);
  check_gradients(L, p);
}
