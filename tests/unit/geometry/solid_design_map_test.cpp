// 3D level-set features mapped onto fixed hexahedral and tetrahedral meshes (geometry/
// level_set_3d.hpp, solid_design_map.hpp): material volumes and their gradients against closed
// forms (sphere, cylinder, super-ellipsoid, pockets), the sub-cell integration's convergence, and
// ∂μ/∂p against central differences of the mapping.
#include "lsmbs/geometry/solid_design_map.hpp"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstdio>
#include <map>

#include "lsmbs/fem/mesh.hpp"
#include "lsmbs/geometry/design_map.hpp"
#include "support/frames.hpp"

using namespace lsmbs;
using lsmbs::test::frame;

namespace {

ParamBinding constant(double v) { return {v, 0, -1}; }
ParamBinding var(int k, double scale = 1, double offset = 0) { return {offset, scale, k}; }

// Each hexahedron of a box split into six tetrahedra around its diagonal 0–6 (Kuhn).
SolidMesh kuhn_tets(const SolidMesh& hexes) {
  SolidMesh m;
  m.nodes = hexes.nodes;
  m.node_sets = hexes.node_sets;
  // the corner index of (i, j, k) bits in the hexahedron's node order
  const int at[2][2][2] = {{{0, 4}, {3, 7}}, {{1, 5}, {2, 6}}};
  const int perms[6][3] = {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}};
  for (const auto& h : hexes.cells)
    for (const auto& p : perms) {
      int b[3] = {0, 0, 0};
      std::vector<int> t = {h[static_cast<size_t>(at[0][0][0])]};
      for (int s = 0; s < 3; ++s) {
        b[p[s]] = 1;
        t.push_back(h[static_cast<size_t>(at[b[0]][b[1]][b[2]])]);
      }
      Mat3 J;
      for (int k = 0; k < 3; ++k)
        J.col(k) = m.nodes[static_cast<size_t>(t[k + 1])] - m.nodes[static_cast<size_t>(t[0])];
      if (J.determinant() < 0) std::swap(t[2], t[3]);
      m.cells.push_back(t);
    }
  return m;
}

struct Mapped {
  double volume;
  Vec grad;
  double eps;  // the logistic band ε
};

Mapped removed(const SolidMesh& mesh, const std::vector<Feature3>& f, const Vec& p,
               int subgrid = 8) {
  MappingOptions o;
  o.subgrid = subgrid;
  SolidDesignMap map(
      mesh,
      LevelSet3(f, LevelSetNode::all_of(static_cast<int>(f.size())), static_cast<int>(p.size())),
      o);
  Vec mu;
  SpMat dmu;
  map.map(p, mu, &dmu);
  Vec g;
  double total = 0;
  for (double v : map.element_volumes()) total += v;
  const double V = map.material_volume(mu, &dmu, &g);
  return {total - V, -g, map.epsilon()};
}

const SolidMesh& unit_cube(int n) {
  static std::map<int, SolidMesh> cache;
  auto it = cache.find(n);
  if (it == cache.end())
    it = cache.emplace(n, SolidMesh::box(Vec3::Zero(), Vec3::Ones(), {n, n, n})).first;
  return it->second;
}

}  // namespace

// A spherical hole r = 0.3 in the unit cube, on hexahedra and on tetrahedra. The logistic band
// ε smooths the boundary; over a sphere the smoothed volume has a closed form,
//   ∫ 4πρ² (1 − H*((ρ − r)/ε)) dρ = 4/3 π r³ + 4/3 π³ r ε²   (to e^(−r/ε)),
// (the band's first moment ∫ s (H(−s) − H*(−s/ε)) ds = π²ε²/6 on a curved surface), so the
// mapping is checked against it, ∂V/∂r = 4π r² + 4/3 π³ ε² included, and the bias against the
// sharp sphere is π² ε²/r² (relative): 4.3e-3 on 10³ hexahedra with 8³ sub-cells.
TEST(SolidDesignMap, SphereVolumeAndGradientAgainstClosedForm) {
  const double r = 0.3;
  std::vector<Feature3> f = {Feature3("ball", Feature3::Type::kSphere,
                                      {var(0), constant(0.5), constant(0.5), var(1)}, true)};
  Vec p(2);
  p << 0.5, r;
  const auto check = [&](const char* what, const Mapped& m, double tol) {
    const double e2 = m.eps * m.eps, pi3 = M_PI * M_PI * M_PI;
    const double V = 4 * M_PI * r * r * r / 3 + 4 * pi3 * r * e2 / 3;
    const double dV = 4 * M_PI * r * r + 4 * pi3 * e2 / 3;
    std::printf(
        "%s: eps %.3e; V %.6e against smoothed %.6e (rel %.1e; sharp sphere %+.2e), dV/dr rel "
        "%.1e, dV/dcx %.1e\n",
        what, m.eps, m.volume, V, m.volume / V - 1, m.volume / (4 * M_PI * r * r * r / 3) - 1,
        m.grad[1] / dV - 1, m.grad[0]);
    EXPECT_NEAR(m.volume / V, 1, tol);
    EXPECT_NEAR(m.grad[1] / dV, 1, tol);
    EXPECT_NEAR(m.grad[0], 0, tol * dV);
  };
  // the hexahedra's uniform sub-cells integrate the smooth band to 3e-6; the tetrahedra's
  // collapsed-cube sub-cells are uneven (they crowd towards the apex), a midpoint rule of
  // O(1/n²) that is not symmetric about the sphere: 4e-4
  check("hexes 10^3", removed(unit_cube(10), f, p), 1e-5);
  check("hexes 20^3", removed(unit_cube(20), f, p), 1e-5);
  check("tets 6x10^3", removed(kuhn_tets(unit_cube(10)), f, p), 1e-3);
}

// Cylinders: a hole through the cube along x (V = π r² · 1, smoothed as the sphere) and a capped
// one of length L along the cube's diagonal (V = π r² L whatever the axis; ∂V/∂r = 2π r L,
// ∂V/∂L = π r²), within the smoothing's bias: π² ε²/(3 r²) = 3.5e-3 from the curved side alone.
TEST(SolidDesignMap, CylindersAgainstClosedForm) {
  const SolidMesh& mesh = unit_cube(16);
  {
    std::vector<Feature3> f = {Feature3("bore", Feature3::Type::kCylinder,
                                        {constant(0.5), var(0), constant(0.5), var(1), constant(0)},
                                        true, frame(Vec3::Zero(), Vec3::UnitX(), Vec3::UnitY()))};
    Vec p(2);
    p << 0.45, 0.25;
    const Mapped m = removed(mesh, f, p);
    // the smoothed disc: π r² + π³ ε²/3 (as the sphere's), its derivative 2π r exactly
    const double V = M_PI * 0.25 * 0.25 + std::pow(M_PI, 3) * m.eps * m.eps / 3,
                 dV = 2 * M_PI * 0.25;
    std::printf("bore: V rel %.2e, dV/dr rel %.2e, dV/dcy %.1e\n", m.volume / V - 1,
                m.grad[1] / dV - 1, m.grad[0]);
    EXPECT_NEAR(m.volume / V, 1, 3e-4);
    EXPECT_NEAR(m.grad[1] / dV, 1, 3e-4);
    EXPECT_NEAR(m.grad[0], 0, 3e-4 * dV);
  }
  const double r = 0.12, L = 0.6;
  std::vector<Feature3> f = {Feature3("slot", Feature3::Type::kCylinder,
                                      {constant(0.5), constant(0.5), constant(0.5), var(0), var(1)},
                                      true, frame(Vec3::Zero(), Vec3(1, 1, 1), Vec3(1, -1, 0)))};
  Vec p(2);
  p << r, L;
  const Mapped m = removed(mesh, f, p);
  const double V = M_PI * r * r * L;
  std::printf("capped: V rel %.2e, dV/dr rel %.2e, dV/dL rel %.2e\n", m.volume / V - 1,
              m.grad[0] / (2 * M_PI * r * L) - 1, m.grad[1] / (M_PI * r * r) - 1);
  EXPECT_NEAR(m.volume / V, 1, 1e-2);
  EXPECT_NEAR(m.grad[0] / (2 * M_PI * r * L), 1, 1e-2);
  EXPECT_NEAR(m.grad[1] / (M_PI * r * r), 1, 1e-2);
}

// A super-ellipsoid ξ = 4 (a rounded box): V = 8abc Γ(1 + 1/ξ)³ / Γ(1 + 3/ξ), ∂V/∂a = V/a, and
// ∂V/∂ξ against its closed form's derivative (central difference of the closed form).
TEST(SolidDesignMap, SuperEllipsoidAgainstClosedForm) {
  const auto volume = [](double a, double b, double c, double xi) {
    return 8 * a * b * c * std::pow(std::tgamma(1 + 1 / xi), 3) / std::tgamma(1 + 3 / xi);
  };
  const double a = 0.3, b = 0.2, c = 0.25, xi = 4;
  std::vector<Feature3> f = {Feature3(
      "box", Feature3::Type::kSuperEllipsoid,
      {constant(0.5), constant(0.5), constant(0.5), var(0), constant(b), constant(c), var(1)}, true,
      frame(Vec3::Zero(), Vec3(0, 0.3, 1), Vec3(1, 0, 0)))};
  Vec p(2);
  p << a, xi;
  const Mapped m = removed(unit_cube(16), f, p);
  const double V = volume(a, b, c, xi);
  const double dVdxi = (volume(a, b, c, xi + 1e-5) - volume(a, b, c, xi - 1e-5)) / 2e-5;
  std::printf("super-ellipsoid: V rel %.2e, dV/da rel %.2e, dV/dxi rel %.2e\n", m.volume / V - 1,
              m.grad[0] / (V / a) - 1, m.grad[1] / dVdxi - 1);
  EXPECT_NEAR(m.volume / V, 1, 5e-3);
  EXPECT_NEAR(m.grad[0] / (V / a), 1, 1e-2);
  EXPECT_NEAR(m.grad[1] / dVdxi, 1, 3e-2);
}

// Pockets machined into the face z = 1: a circle of radius r to depth d (V = π r² d, ∂V/∂r =
// 2π r d, ∂V/∂d = π r²) and a super-ellipse profile (V = depth × its area), and a through-hole.
TEST(SolidDesignMap, PocketsAndThroughHolesAgainstClosedForm) {
  const SolidMesh& mesh = unit_cube(16);
  const Frame3 top = frame(Vec3(0, 0, 1), -Vec3::UnitZ(), Vec3::UnitX());  // w into the part
  const double r = 0.3, d = 0.4;
  {
    std::vector<Feature3> f = {Feature3("pocket", Feature3::Type::kPocket,
                                        {constant(0.5), constant(-0.5), var(0), var(1)}, true, top,
                                        Feature::Type::kCircle)};
    Vec p(2);
    p << r, d;
    const Mapped m = removed(mesh, f, p);
    const double V = M_PI * r * r * d;
    std::printf("circular pocket: V rel %.2e, dV/dr rel %.2e, dV/dd rel %.2e\n", m.volume / V - 1,
                m.grad[0] / (2 * M_PI * r * d) - 1, m.grad[1] / (M_PI * r * r) - 1);
    EXPECT_NEAR(m.volume / V, 1, 3e-3);
    EXPECT_NEAR(m.grad[0] / (2 * M_PI * r * d), 1, 1e-2);
    EXPECT_NEAR(m.grad[1] / (M_PI * r * r), 1, 1e-2);
  }
  {
    // (u, v) = (x, −y) on this face: the profile's centre (0.5, −0.5) is the face's centre
    const double A = 0.3, B = 0.2, X = 4, Y = 6;
    std::vector<Feature3> f = {Feature3("rounded", Feature3::Type::kPocket,
                                        {constant(0.5), constant(-0.5), constant(A), constant(B),
                                         constant(X), constant(Y), constant(0.3), var(0)},
                                        true, top, Feature::Type::kSuperEllipse)};
    Vec p(1);
    p << d;
    const Mapped m = removed(mesh, f, p);
    const double area = 4 * A * B * std::tgamma(1 + 1 / X) * std::tgamma(1 + 1 / Y) /
                        std::tgamma(1 + 1 / X + 1 / Y);
    std::printf("super-elliptic pocket: V rel %.2e, dV/dd rel %.2e\n", m.volume / (area * d) - 1,
                m.grad[0] / area - 1);
    EXPECT_NEAR(m.volume / (area * d), 1, 3e-3);
    EXPECT_NEAR(m.grad[0] / area, 1, 1e-2);
  }
  {
    std::vector<Feature3> f = {Feature3("through", Feature3::Type::kThroughHole,
                                        {constant(0.5), constant(-0.5), var(0)}, true, top,
                                        Feature::Type::kCircle)};
    Vec p(1);
    p << r;
    const Mapped m = removed(mesh, f, p);
    std::printf("through-hole: V rel %.2e, dV/dr rel %.2e\n", m.volume / (M_PI * r * r) - 1,
                m.grad[0] / (2 * M_PI * r) - 1);
    EXPECT_NEAR(m.volume / (M_PI * r * r), 1, 2e-3);
    EXPECT_NEAR(m.grad[0] / (2 * M_PI * r), 1, 5e-3);
  }
}

// The sub-cell integration converges: the sphere's volume error shrinks as the sub-grid is
// refined on a fixed mesh (the smoothing band ε shrinks with it).
TEST(SolidDesignMap, SubcellIntegrationConverges) {
  const double r = 0.3;
  std::vector<Feature3> f = {Feature3("ball", Feature3::Type::kSphere,
                                      {constant(0.5), constant(0.5), constant(0.5), var(0)}, true)};
  Vec p(1);
  p << r;
  const double V = 4 * M_PI * r * r * r / 3;
  double previous = 1;
  for (int n : {2, 4, 8}) {
    const double err = std::abs(removed(unit_cube(10), f, p, n).volume / V - 1);
    std::printf("subgrid %d: |V rel| %.2e\n", n, err);
    EXPECT_LT(err, previous);
    previous = err;
  }
}

// ∂μ_e/∂p against central differences of the mapping for every element, on a design with
// Booleans: a sphere and a pocket united into one void by a KS-smoothed OR of the holes
// (= AND of the material), a cylinder, and a non-design solid sphere OR-ed back.
TEST(SolidDesignMap, DerivativesAgainstCentralDifferences) {
  const Frame3 side = frame(Vec3(1, 0, 0), -Vec3::UnitX(), Vec3::UnitY());
  std::vector<Feature3> f = {
      Feature3("ball", Feature3::Type::kSphere, {var(0), var(1), constant(0.4), var(2)}, true),
      Feature3("pocket", Feature3::Type::kPocket,
               {var(3), constant(0.5), constant(0.2), constant(0.15), constant(1.2), constant(0.4),
                var(4)},
               true, side, Feature::Type::kEllipse),
      Feature3("bore", Feature3::Type::kCylinder,
               {constant(0.3), constant(0.7), var(5), constant(0.1), constant(0.5)}, true,
               frame(Vec3::Zero(), Vec3(0, 1, 1), Vec3(1, 0, 0))),
      Feature3("boss", Feature3::Type::kSphere,
               {constant(0.45), constant(0.5), constant(0.4), constant(0.08)}, false)};
  LevelSetNode root;
  root.op = LevelSetNode::Op::kOr;  // the boss kept whatever the holes do
  LevelSetNode holes = LevelSetNode::all_of(3);
  holes.ks = 200;
  LevelSetNode boss;
  boss.feature = 3;
  root.children = {holes, boss};
  MappingOptions o;
  o.subgrid = 4;
  const SolidMesh& mesh = unit_cube(8);
  SolidDesignMap map(mesh, LevelSet3(f, root, 6), o);
  Vec p(6);
  p << 0.45, 0.52, 0.22, 0.5, 0.35, 0.65;
  Vec mu;
  SpMat dmu;
  map.map(p, mu, &dmu);
  const Mat D(dmu);
  double worst = 0, scale = 0;
  for (int k = 0; k < 6; ++k) {
    const double h = 1e-6;
    Vec pp = p, pm = p, mp, mm;
    pp[k] += h, pm[k] -= h;
    map.map(pp, mp);
    map.map(pm, mm);
    const Vec fd = (mp - mm) / (2 * h);
    worst = std::max(worst, (fd - D.col(k)).cwiseAbs().maxCoeff());
    scale = std::max(scale, fd.cwiseAbs().maxCoeff());
  }
  std::printf("dmu/dp against fd-central: max |diff| %.2e of max |dmu/dp| %.2e\n", worst, scale);
  EXPECT_GT(scale, 1);
  EXPECT_LT(worst, 1e-6 * scale);
  for (int e = 0; e < mu.size(); ++e) {
    EXPECT_GE(mu[e], o.mu_min);
    EXPECT_LE(mu[e], 1.0);
  }
}

// Elements the level set's bound calls uniform are uniform: H*(D) at each of their corners equals
// the μ they were given to 1e-12 (a super-ellipsoid, whose first-order D is not a distance).
TEST(SolidDesignMap, UniformElementsAreUniform) {
  std::vector<Feature3> f = {Feature3("blob", Feature3::Type::kSuperEllipsoid,
                                      {constant(0.5), constant(0.5), constant(0.5), constant(0.35),
                                       constant(0.15), constant(0.25), constant(6)},
                                      true,
                                      frame(Vec3::Zero(), Vec3(1, 2, 0.5), Vec3(0, -0.25, 1)))};
  MappingOptions o;
  o.subgrid = 4;
  const SolidMesh& mesh = unit_cube(12);
  SolidDesignMap map(mesh, LevelSet3(f, LevelSetNode::all_of(1), 0), o);
  Vec mu;
  MapCounts counts;
  map.map(Vec(0), mu, nullptr, &counts);
  EXPECT_LT(counts.band, mesh.num_elements());
  // integrate every element: the sub-cells' mean of H*(D) for the skipped ones
  const LevelSet3& ls = map.level_set();
  const auto theta = ls.values(Vec(0));
  double worst = 0;
  int skipped = 0;
  for (int e = 0; e < mesh.num_elements(); ++e) {
    if (mu[e] != 1.0 && mu[e] != o.mu_min) continue;
    ++skipped;
    double lo = 1, hi = 0;
    for (int k : mesh.cells[static_cast<size_t>(e)]) {
      const double h =
          1 / (1 + std::exp(-ls.evaluate(mesh.nodes[static_cast<size_t>(k)], theta, nullptr) /
                            map.epsilon()));
      lo = std::min(lo, h), hi = std::max(hi, h);
    }
    const double m = o.mu_min + (1 - o.mu_min) * 0.5 * (lo + hi);
    worst = std::max(worst, std::abs(m - mu[e]));
  }
  std::printf("%d uniform elements, worst corner H* against their mu %.1e\n", skipped, worst);
  EXPECT_GT(skipped, 0);
  EXPECT_LT(worst, 1e-12);
}

// A through-hole of a super-ellipse profile in one layer of bricks is the planar hole extruded:
// its μ_e are the planar mapping's on the same quadrilaterals (design_map.cpp, its own code for
// skipping far elements), to round-off, with a band of half a sub-cell and elements whose edges
// touch the hole (the robot arm's Table 5 holes, a = b = 10 mm centred on 10 mm elements). The
// super-ellipse's D₀ grows without bound towards its centre, so a bound() that took it for a
// distance called the elements at the centre uniform void (μ_min instead of the band's 0.041).
TEST(SolidDesignMap, ASuperEllipseThroughHoleIsThePlanarHoleExtruded) {
  MappingOptions o;
  o.subgrid = 8;
  o.band = 0.5;
  const std::vector<double> th = {0.62, 0.0, 0.01, 0.01, 5, 5, 0};
  std::vector<ParamBinding> ps;
  for (double v : th) ps.push_back(constant(v));
  const Mesh2D quads = Mesh2D::rectangle(0.2, -0.025, 0.6, 0.05, 60, 5);
  DesignMap planar(
      quads,
      LevelSet({Feature("h", Feature::Type::kSuperEllipse, ps, true)}, LevelSetNode::all_of(1), 0),
      o);
  const SolidMesh bricks =
      SolidMesh::box(Vec3(0.2, -0.025, -0.00125), Vec3(0.6, 0.05, 0.0025), {60, 5, 1});
  Frame3 face;  // (u, v) = (x, y), w = z
  SolidDesignMap solid(bricks,
                       LevelSet3({Feature3("h", Feature3::Type::kThroughHole, ps, true, face,
                                           Feature::Type::kSuperEllipse)},
                                 LevelSetNode::all_of(1), 0),
                       o);
  Vec mu2, mu3;
  planar.map(Vec(0), mu2);
  solid.map(Vec(0), mu3);
  ASSERT_EQ(mu2.size(), mu3.size());
  double worst = 0, centre = 0;
  for (int e = 0; e < mu2.size(); ++e) {
    worst = std::max(worst, std::abs(mu2[e] - mu3[e]));
    if (std::abs(quads.centroid(e).x() - 0.625) < 1e-9 && std::abs(quads.centroid(e).y()) < 1e-9)
      centre = mu3[e];
  }
  std::printf("through-hole against the planar hole: worst |mu3 - mu2| %.1e, centre element %.4f\n",
              worst, centre);
  EXPECT_LT(worst, 1e-12);
  EXPECT_NEAR(centre, 0.0409, 1e-3);
}
