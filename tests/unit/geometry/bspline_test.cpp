// The closed cubic B-spline feature (ClosedBSpline): its signed distance against the distance to
// a 200 000-point polygon of the curve with the sign of the polygon's winding number, its
// derivatives with respect to the control points against central differences, and the checks
// that refuse curves that are not simple closed curves.
#include "lsmbs/geometry/bspline.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "lsmbs/geometry/level_set.hpp"

using namespace lsmbs;

namespace {

// 10 control points of a dented loop (a shape with concave parts), clockwise if `cw`.
std::vector<double> dented(bool cw = false) {
  std::vector<double> th;
  for (int i = 0; i < 10; ++i) {
    const double t = 2 * M_PI * i / 10 * (cw ? -1 : 1);
    const double r = 0.03 * (1 + 0.35 * std::cos(3 * t));
    th.push_back(0.1 + r * std::cos(t));
    th.push_back(0.02 + 0.6 * r * std::sin(t));
  }
  return th;
}

double polygon_distance(const Vec2& x, const std::vector<Vec2>& P) {
  double best = 1e300;
  for (size_t k = 0; k < P.size(); ++k) {
    const Vec2 a = P[k], e = P[(k + 1) % P.size()] - a;
    const double t = std::clamp((x - a).dot(e) / e.squaredNorm(), 0.0, 1.0);
    best = std::min(best, (a + t * e - x).norm());
  }
  return best;
}

bool polygon_contains(const Vec2& x, const std::vector<Vec2>& P) {  // crossing number
  bool in = false;
  for (size_t k = 0, j = P.size() - 1; k < P.size(); j = k++)
    if ((P[k].y() > x.y()) != (P[j].y() > x.y()) &&
        x.x() < (P[j].x() - P[k].x()) * (x.y() - P[k].y()) / (P[j].y() - P[k].y()) + P[k].x())
      in = !in;
  return in;
}

}  // namespace

TEST(ClosedBSpline, SignedDistanceIsTheDistanceToTheCurveWithItsInsideNegative) {
  for (bool cw : {false, true}) {
    const auto th = dented(cw);
    const ClosedBSpline c(th.data(), 10);
    ASSERT_EQ(c.check(), "");
    EXPECT_EQ(c.counter_clockwise(), !cw);
    const auto P = c.polygon(20000);  // chords within ~1e-11 m of the curve
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> ux(0.03, 0.17), uy(-0.03, 0.07);
    int inside = 0;
    for (int s = 0; s < 400; ++s) {
      const Vec2 x(ux(rng), uy(rng));
      const auto foot = c.closest(x);
      const bool in = polygon_contains(x, P);
      inside += in;
      const double ref = (in ? -1 : 1) * polygon_distance(x, P);
      EXPECT_NEAR(foot.distance, ref, 1e-9) << "x = " << x.transpose() << (cw ? " (cw)" : "");
      EXPECT_NEAR((c.point(foot.t) - x).norm(), std::abs(ref), 1e-9);
      // the normal at the foot points from the curve to x (outside) or away from it (inside)
      if (std::abs(ref) > 1e-6)
        EXPECT_NEAR((x - c.point(foot.t)).normalized().dot(foot.normal), in ? -1 : 1, 1e-6);
    }
    EXPECT_GT(inside, 40);
    EXPECT_LT(inside, 360);
  }
}

// ∂D/∂θ of the feature (LevelSet::feature_distance, the mapping's path) against central
// differences of the distance, for every control-point coordinate, as a hole and as a solid.
TEST(ClosedBSpline, DistanceDerivativesMatchCentralDifferencesAndTouchFourPoints) {
  const auto th0 = dented();
  for (bool hole : {true, false}) {
    std::vector<ParamBinding> ps;
    for (int k = 0; k < 20; ++k) ps.push_back(ParamBinding{0, 1, k});
    const LevelSet ls({Feature("b", Feature::Type::kBSpline, ps, hole)}, LevelSetNode::all_of(1),
                      20);
    Vec p = Eigen::Map<const Vec>(th0.data(), 20);
    // points 4 mm inside and outside the curve along its normals (a unique closest point: off
    // the medial axis, where the distance has kinks), and one far outside
    const ClosedBSpline curve(th0.data(), 10);
    std::vector<Vec2> xs = {Vec2(0.2, 0.0)};
    for (double t : {0.3, 2.7, 4.5, 6.1, 8.9}) {
      const auto foot = curve.closest(curve.point(t) + Vec2(1e-9, 0));
      for (double s : {-0.004, 0.004}) xs.push_back(curve.point(t) + s * foot.normal);
    }
    for (const Vec2& x : xs) {
      LevelSet::Gradient g;
      const double D = ls.evaluate(x, ls.values(p), &g);
      EXPECT_LE(g.size(), 8u);
      Vec dense = Vec::Zero(20);
      for (const auto& [k, v] : g) dense[k] += v;
      for (int k = 0; k < 20; ++k) {
        const double h = 1e-7;
        Vec pp = p, pm = p;
        pp[k] += h, pm[k] -= h;
        const double fd =
            (ls.evaluate(x, ls.values(pp), nullptr) - ls.evaluate(x, ls.values(pm), nullptr)) /
            (2 * h);
        EXPECT_NEAR(dense[k], fd, 1e-6) << "x = " << x.transpose() << ", θ_" << k;
      }
      EXPECT_NE(D, 0);
    }
  }
}

TEST(ClosedBSpline, CurvesThatCrossThemselvesOrHaveCuspsAreRefused) {
  // a figure eight: control points alternating sides
  const std::vector<double> eight = {0, 0, 1, 1, 2, 0, 1, -1, 0, 0.01, -1, 1, -2, 0, -1, -1};
  EXPECT_NE(ClosedBSpline(eight.data(), 8).check().find("crosses itself"), std::string::npos);
  // three coincident control points: the curve passes through them with zero speed (a cusp)
  const std::vector<double> cusp = {0, 0, 1, 0, 1, 0, 1, 0, 1, 1, 0, 1};
  EXPECT_NE(ClosedBSpline(cusp.data(), 6).check().find("cusp"), std::string::npos);
  const std::vector<double> square = {0, 0, 1, 0, 1, 1, 0, 1};
  EXPECT_EQ(ClosedBSpline(square.data(), 4).check(), "");
  Feature f("b", Feature::Type::kBSpline, std::vector<ParamBinding>(6), true);
  EXPECT_NE(f.check({0, 0, 1, 0, 1, 1}).find("at least 4"), std::string::npos);
}
