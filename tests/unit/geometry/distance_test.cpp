// Feature distances (geometry/feature.hpp) against brute force: the Euclidean distance from a
// point to a densely sampled boundary (the minimum over the segments of a polygon with 4·10⁵
// vertices, uniform in polar angle), signed negative inside. Points lie on the normals of
// boundary points at offsets that cover the three zones of the super-ellipse's distance:
// refined (|D₀| ≤ r/2: three Newton projections onto φ = 0; error ∝ |d|³ or better), blend
// (r/2 … r: between the refined distance and D₀) and plain D₀ = φ/|∇φ| beyond r, which for a
// convex φ never exceeds the signed distance. The circle's φ is a signed distance, so every zone
// is exact. (The ellipse's exact distance is tested in design_map_test.cpp.)
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <map>
#include <numbers>
#include <random>

#include "lsmbs/geometry/feature.hpp"

using namespace lsmbs;

namespace {

constexpr double kPi = std::numbers::pi;

ParamBinding constant(double v) { return {v, 0, -1}; }

// Boundary r(ψ) (polar, feature frame) → polygon in the global frame.
struct Polygon {
  std::vector<Vec2> v;
  double distance(const Vec2& x) const {
    double best = 1e300;
    for (size_t i = 0; i < v.size(); ++i) {
      const Vec2 a = v[i], b = v[(i + 1) % v.size()], ab = b - a;
      const double t = std::clamp((x - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0);
      best = std::min(best, (x - a - t * ab).norm());
    }
    return best;
  }
};

Polygon polygon(const std::function<double(double)>& r, const Vec2& c, double rot, int n) {
  Polygon p;
  for (int i = 0; i < n; ++i) {
    const double psi = 2 * kPi * i / n, rr = r(psi);
    const Vec2 u(rr * std::cos(psi), rr * std::sin(psi));
    p.v.emplace_back(c + Vec2(std::cos(rot) * u.x() - std::sin(rot) * u.y(),
                              std::sin(rot) * u.x() + std::cos(rot) * u.y()));
  }
  return p;
}

}  // namespace

TEST(FeatureDistance, CircleIsExactInEveryZone) {
  const double cx = 0.1, cy = -0.02, R = 0.01, rw = 3e-3;
  Feature f("C", Feature::Type::kCircle, {constant(cx), constant(cy), constant(R)}, true);
  const double th[3] = {cx, cy, R};
  // brute-force resolution: the polygon's sag R (1 − cos(π/n)) ≈ 3e-12 m for n = 4·10⁵
  const Polygon poly = polygon([&](double) { return R; }, Vec2(cx, cy), 0, 400000);
  double worst = 0;
  for (int k = 0; k < 16; ++k) {
    const double psi = 0.37 + 2 * kPi * k / 16;
    const Vec2 n(std::cos(psi), std::sin(psi));
    for (const double s :
         {-8e-3, -2e-3, -1.2e-3, -2e-4, 1e-5, 3e-4, 1.2e-3, 2e-3, 2.9e-3, 5e-3, 2e-2}) {
      const Vec2 x = Vec2(cx, cy) + (R + s) * n;
      const double d = (s < 0 ? -1 : 1) * poly.distance(x);
      for (const double refine : {0.0, rw}) {
        const double D = f.distance<double>(x, th, refine);
        EXPECT_EQ(D < 0, s < 0);
        EXPECT_NEAR(D, s, 1e-15) << "the closed form |x − c| − R";
        worst = std::max(worst, std::abs(D - d));
      }
    }
  }
  std::printf("circle: largest |D − brute force| = %.2e m (polygon sag 3e-12 m)\n", worst);
  EXPECT_LT(worst, 1e-11);
}

// At a feature's centre ∇φ vanishes: the distance there is the closed form, not φ/|∇φ| = −1e13
TEST(FeatureDistance, CentresHaveTheirClosedFormDistance) {
  const double cx = 0.15, cy = 0.0, R = 0.01;
  Feature c("C", Feature::Type::kCircle, {constant(cx), constant(cy), constant(R)}, true);
  const double tc[3] = {cx, cy, R};
  for (const double refine : {0.0, 0.02}) {
    EXPECT_NEAR(c.distance<double>(Vec2(cx, cy), tc, refine), -R, 1e-15);
    // d/dr of the distance at the centre is −1 (the Dual's derivative along θ = r)
    const Dual t[3] = {Dual(cx), Dual(cy), Dual::variable(R, 2)};
    const Dual D = c.distance<Dual>(Vec2(cx, cy), t, refine);
    EXPECT_NEAR(D.v, -R, 1e-15);
    EXPECT_NEAR(D.d[2], -1.0, 1e-12);
  }
  // super-ellipses with ξ, η ≥ 2: the nearest boundary points from the centre are the vertices
  // on the shorter axis, at distance min(a, b)
  for (const double xi : {2.0, 5.0}) {
    const double a = 0.02, b = 0.008;
    Feature s("S", Feature::Type::kSuperEllipse,
              {constant(cx), constant(cy), constant(a), constant(b), constant(xi), constant(xi),
               constant(0.4)},
              true);
    const double ts[7] = {cx, cy, a, b, xi, xi, 0.4};
    for (const double refine : {0.0, 0.02})
      EXPECT_NEAR(s.distance<double>(Vec2(cx, cy), ts, refine), -b, 1e-15) << "xi " << xi;
  }
}

TEST(FeatureDistance, SuperEllipseAgainstBruteForceInTheRefinedBlendAndPlainZones) {
  // ξ = η = 5 super-ellipse as on the robot arm (eq. 43): a = 20 mm, b = 10 mm, rotated;
  // refinement radius r = 3 mm (the mapping uses 12 bands: ε = 0.25 mm here).
  const double cx = 0.1, cy = 0.02, a = 0.02, b = 0.01, xi = 5, rot = 0.3, rw = 3e-3;
  Feature f("S", Feature::Type::kSuperEllipse,
            {constant(cx), constant(cy), constant(a), constant(b), constant(xi), constant(xi),
             constant(rot)},
            true);
  const double th[7] = {cx, cy, a, b, xi, xi, rot};
  auto r = [&](double psi) {
    return std::pow(
        std::pow(std::abs(std::cos(psi) / a), xi) + std::pow(std::abs(std::sin(psi) / b), xi),
        -1 / xi);
  };
  // polygon sag κ Δ²/8 ≤ 500 m⁻¹ (3e-7 m)² / 8 ≈ 1e-11 m at the corners
  const Polygon poly = polygon(r, Vec2(cx, cy), rot, 400000);
  const Vec2 c(cx, cy);
  auto to_global = [&](const Vec2& u) -> Vec2 {
    return c + Vec2(std::cos(rot) * u.x() - std::sin(rot) * u.y(),
                    std::sin(rot) * u.x() + std::cos(rot) * u.y());
  };
  const std::vector<double> offsets = {-4e-3,    -2.5e-3, -1.5e-3, -1e-3, -5e-4, -2.5e-4,
                                       -1.25e-4, 1.25e-4, 2.5e-4,  5e-4,  1e-3,  1.5e-3,
                                       2e-3,     2.5e-3,  2.9e-3,  4e-3,  6e-3};
  double worst_refined = 0, worst_k = 0, worst_order = 1e300, near = 0;
  int n_refined = 0, n_blend = 0, n_plain = 0;
  for (int k = 0; k < 24; ++k) {
    // boundary point and its outward normal ∇φ/|∇φ| in the feature frame
    const double psi = 0.05 + 2 * kPi * k / 24, rr = r(psi);
    const Vec2 y(rr * std::cos(psi), rr * std::sin(psi));
    Vec2 n(xi * std::pow(std::abs(y.x() / a), xi - 1) / a * (y.x() < 0 ? -1 : 1),
           xi * std::pow(std::abs(y.y() / b), xi - 1) / b * (y.y() < 0 ? -1 : 1));
    n.normalize();
    std::map<double, double> err;  // offset → |D − d| in the refined zone
    for (const double s : offsets) {
      const Vec2 x = to_global(y + s * n);
      const double d = (s < 0 ? -1 : 1) * poly.distance(x);
      const double D = f.distance<double>(x, th, rw), D0 = f.distance<double>(x, th, 0);
      const double Dr = f.distance<double>(x, th, 1e300);  // the refined distance everywhere
      ASSERT_EQ(D < 0, s < 0) << "sign at psi " << psi << ", s " << s << ": D = " << D
                              << ", d = " << d;
      // φ is convex (ξ, η ≥ 1), so D₀ = φ/|∇φ| never exceeds the signed distance: outside,
      // 0 = φ(y*) ≥ φ(x) + ∇φ(x)·(y* − x) gives φ ≤ |∇φ| d; inside, following ∇φ to the boundary
      // gives |φ|/|∇φ| ≥ d.
      EXPECT_LE(D0, d + 1e-11) << psi << " " << s;
      const double e = std::abs(D - d), ad = std::abs(D0);
      if (ad <= rw / 2) {  // refined: three Newton projections, third order in d
        ++n_refined;
        worst_refined = std::max(worst_refined, e);
        worst_k = std::max(worst_k, e / std::pow(std::abs(d), 3));
        if (std::abs(d) <= 5e-4) near = std::max(near, e);
        err[s] = e;
      } else if (ad < rw) {  // blend: a convex combination of the refined distance and D₀
        ++n_blend;
        EXPECT_GE(D, std::min(Dr, D0) - 1e-15) << psi << " " << s;
        EXPECT_LE(D, std::max(Dr, D0) + 1e-15) << psi << " " << s;
      } else {  // plain: D₀ itself
        ++n_plain;
        EXPECT_EQ(D, D0);
      }
    }
    // order: the error of the refined distance falls at least eightfold when the offset halves
    // (where it is above the brute force's resolution)
    for (const double s : {2.5e-4, 5e-4, -2.5e-4, -5e-4})
      if (err.count(s) && err.count(2 * s) && err[2 * s] > 1e-10)
        worst_order = std::min(worst_order, std::log2(err[2 * s] / std::max(err[s], 1e-12)));
  }
  std::printf(
      "super-ellipse ξ = 5, a = 20 mm, b = 10 mm, refinement radius 3 mm: refined zone (%d points) "
      "|D − d| ≤ %.2e m (≤ %.3g |d|³; ≤ %.2e m within 0.5 mm), observed order ≥ %.2f; %d blend, %d "
      "plain points\n",
      n_refined, worst_refined, worst_k, near, worst_order, n_blend, n_plain);
  EXPECT_GT(n_refined, 150);
  EXPECT_GT(n_blend, 20);
  EXPECT_GT(n_plain, 20);
  // measured 1.9e3 |d|³ (8.3e-6 m at |d| = 1.5 mm, near a corner), 8.9e-8 m within 0.5 mm = 2
  // bands, where the logistic's slope is largest; orders ≥ 3
  EXPECT_LT(worst_k, 4e3);
  EXPECT_LT(near, 2e-7);
  EXPECT_GE(worst_order, 3.0);
}

TEST(FeatureDistance, SuperEllipseFarBoundHoldsOverItsDisc) {
  // Feature::far_bound against D₀ sampled densely over the disc (it lets the mapping freeze far
  // super-ellipses): never larger than |D₀| nor of the other sign, and not trivial far away.
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> U(0, 1);
  int checked = 0, far_discs = 0, far_bounded = 0;
  double tightest = 1e300;
  for (int trial = 0; trial < 400; ++trial) {
    const double a = 0.005 + 0.03 * U(rng), b = 0.005 + 0.03 * U(rng);
    const double xi = 1 + 9 * U(rng), eta = 1 + 9 * U(rng), rot = 6.3 * U(rng);
    const bool hole = trial % 2 == 0;
    const std::vector<double> th = {0.1, 0.05, a, b, xi, eta, rot};
    Feature f("S", Feature::Type::kSuperEllipse,
              {constant(th[0]), constant(th[1]), constant(a), constant(b), constant(xi),
               constant(eta), constant(rot)},
              hole);
    const double ang = 6.3 * U(rng), dist = 0.2 * U(rng), rho = 0.001 + 0.004 * U(rng);
    const Vec2 c(th[0] + dist * std::cos(ang), th[1] + dist * std::sin(ang));
    const double L = f.far_bound(c, rho, th);
    double dmin = 1e300;
    bool sign_ok = true;
    for (int i = 0; i <= 40; ++i)
      for (int j = 0; j < 48; ++j) {
        const double r = rho * i / 40, t = 2 * kPi * j / 48;
        const Vec2 x = c + r * Vec2(std::cos(t), std::sin(t));
        const double D0 = f.distance<double>(x, th.data(), 0);
        dmin = std::min(dmin, std::abs(D0));
        if (L != 0 && (D0 > 0) != (L > 0)) sign_ok = false;
      }
    ++checked;
    EXPECT_TRUE(sign_ok) << "trial " << trial;
    EXPECT_LE(std::abs(L), dmin * (1 + 1e-12)) << "trial " << trial;
    if (L != 0) tightest = std::min(tightest, dmin / std::abs(L));
    if (f.distance<double>(c, th.data(), 0) * (hole ? 1 : -1) > 3 * rho) {
      ++far_discs;
      far_bounded += L != 0;
    }
  }
  std::printf("far_bound: %d discs, %d of %d far outside bounded, best min|D0|/|L| = %.3f\n",
              checked, far_bounded, far_discs, tightest);
  EXPECT_GT(far_discs, 100);
  EXPECT_EQ(far_bounded, far_discs);  // outside by three radii (D₀ ≤ d): φ > 0 over the disc
}
