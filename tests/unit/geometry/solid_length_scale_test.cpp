// Length-scale constraints of solid bodies (geometry/solid_length_scale.hpp) against closed forms
// and central differences. Each value lies within [true − error_bound, true + the sampling error]
// (the KS aggregate lies below the minimum by at most the error bound; sampling off the nearest
// points adds at most about d²/2 · (1/R₁ + 1/R₂) for an offset d of half a sample diagonal):
//   - two spheres: ligament |c₁ − c₂| − r₁ − r₂; a sphere's edge ligament: the distance from its
//     surface to the nearest face; its member size 2r;
//   - a capped cylinder and a sphere off its rim: the exact distance to the rim's corner circle
//     (the capped cylinder's distance is √(d_r² + d_z²) there, not the max of the two);
//   - super-ellipse through-holes in a plate: the gap between their flat sides, the edge ligament
//     to the plate's long side (the faces the holes pass through are not edges), and the same
//     values as the planar measures of the same design on the plate's section;
//   - pockets: the floor under a pocket is its edge ligament (t − depth), the web between two
//     pockets from opposite faces is their ligament (t − depth₁ − depth₂);
//   - a sphere in a box of tetrahedra (each brick split in six) as in one of bricks;
//   - every gradient against central differences of the value (h = 1e-7 m);
//   - no_cut is refused on a solid body.
#include "lsmbs/geometry/solid_length_scale.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "lsmbs/core/error.hpp"
#include "support/frames.hpp"

using namespace lsmbs;
using lsmbs::test::frame;

namespace {

ParamBinding var(int k) { return {0, 1, k}; }
ParamBinding constant(double v) { return {v, 0, -1}; }

const LengthScaleConstraint& find(const std::vector<LengthScaleConstraint>& c,
                                  const std::string& name) {
  for (const auto& x : c)
    if (x.name() == name) return x;
  throw std::runtime_error("no constraint " + name);
}

// value within [exact − error_bound, exact + above]
void expect_bracket(const LengthScaleConstraint& c, double exact, double above) {
  EXPECT_LE(c.value, exact + above) << c.name();
  EXPECT_GE(c.value, exact - c.error_bound - 1e-12) << c.name();
}

void check_gradients(const LengthScaleMeasures& L, const Vec& p) {
  const auto c0 = L.evaluate(p);
  const double h = 1e-7;
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

// a 60 × 40 × 30 mm box of 5 mm bricks (sampling 1.25 mm)
const SolidMesh& box() {
  static const SolidMesh m = SolidMesh::box(Vec3::Zero(), Vec3(0.06, 0.04, 0.03), {12, 8, 6});
  return m;
}

// the box with each brick split into six tetrahedra about its diagonal 0–6
SolidMesh tetrahedral(const SolidMesh& hexes) {
  SolidMesh m;
  m.nodes = hexes.nodes;
  constexpr int kSplit[6][4] = {{0, 1, 2, 6}, {0, 2, 3, 6}, {0, 3, 7, 6},
                                {0, 7, 4, 6}, {0, 4, 5, 6}, {0, 5, 1, 6}};
  for (const auto& c : hexes.cells)
    for (const auto& t : kSplit)
      m.cells.push_back({c[static_cast<size_t>(t[0])], c[static_cast<size_t>(t[1])],
                         c[static_cast<size_t>(t[2])], c[static_cast<size_t>(t[3])]});
  return m;
}

// p = (c1x, r1, c2x, r2): spheres A and B on the line y = 20, z = 15 mm
LevelSet3 spheres() {
  return LevelSet3({Feature3("A", Feature3::Type::kSphere,
                             {var(0), constant(0.02), constant(0.015), var(1)}, true),
                    Feature3("B", Feature3::Type::kSphere,
                             {var(2), constant(0.02), constant(0.015), var(3)}, true)},
                   LevelSetNode::all_of(2), 4);
}

}  // namespace

TEST(SolidLengthScale, SpheresLigamentEdgeAndMember) {
  const LevelSet3 ls = spheres();
  LengthScaleOptions o;
  o.min_ligament = o.min_edge = o.min_member = 0.005;
  const SolidLengthScale L(box(), ls, 2, o);
  EXPECT_DOUBLE_EQ(L.spacing(), 0.00125);
  EXPECT_EQ(L.num_volume_samples(), 12 * 8 * 6 * 64);
  EXPECT_EQ(L.num_boundary_samples(), 2 * (12 * 8 + 12 * 6 + 8 * 6) * 25);
  const Vec p = (Vec(4) << 0.02, 0.008, 0.042, 0.006).finished();
  const auto c = L.evaluate(p);
  ASSERT_EQ(c.size(), 5u);  // ligament, edge A, edge B, member A, member B
  // samples lie within (√2/2)·0.625 mm of the line of centres: 0.11 mm above the gap at most
  expect_bracket(find(c, "ligament.A.B"), 0.042 - 0.02 - 0.008 - 0.006, 1.2e-4);
  EXPECT_NEAR(find(c, "ligament.A.B").gradient[2], 1, 1e-2);
  EXPECT_NEAR(find(c, "ligament.A.B").gradient[1], -1, 3e-2);
  // A's nearest face is z = 0 (15 − 8 = 7 mm); B's too (15 − 6 = 9 mm); face samples lie within
  // 0.88 mm of the foot: 0.03 mm above
  expect_bracket(find(c, "edge.A"), 0.007, 3e-5);
  expect_bracket(find(c, "edge.B"), 0.009, 3e-5);
  EXPECT_NEAR(find(c, "edge.A").gradient[1], -1, 1e-3);
  EXPECT_DOUBLE_EQ(find(c, "member.A").value, 0.016);
  EXPECT_DOUBLE_EQ(find(c, "member.B").gradient[3], 2);
  ASSERT_EQ(find(c, "member.A").at.size(), 3);
  EXPECT_DOUBLE_EQ(find(c, "member.A").at[2], 0.015);
  check_gradients(L, p);
  // overlapping spheres: a negative ligament
  const Vec q = (Vec(4) << 0.02, 0.008, 0.03, 0.006).finished();
  EXPECT_LT(L.evaluate(q)[0].value, -0.003);
}

TEST(SolidLengthScale, TetrahedraSampleLikeBricks) {
  const SolidMesh tets = tetrahedral(box());
  const LevelSet3 ls = spheres();
  LengthScaleOptions o;
  o.min_ligament = o.min_edge = 0.005;
  const SolidLengthScale L(tets, ls, 2, o);
  // the tetrahedra's longest edges are the bricks' diagonals (8.66 mm): a quarter of them
  EXPECT_NEAR(L.spacing(), std::sqrt(3.0) * 0.005 / 4, 1e-15);
  const Vec p = (Vec(4) << 0.02, 0.008, 0.042, 0.006).finished();
  const auto c = L.evaluate(p);
  expect_bracket(find(c, "ligament.A.B"), 0.008, 3e-4);
  expect_bracket(find(c, "edge.A"), 0.007, 1e-4);
  expect_bracket(find(c, "edge.B"), 0.009, 1e-4);
  check_gradients(L, p);
}

TEST(SolidLengthScale, CappedCylinderRimIsARoundCorner) {
  // cylinder along z: r = 5 mm, length 10 mm (p0), centre (20, 20, 15) mm; a sphere of radius
  // p1 off its rim at (20 + 5 + 3, 20, 15 + 5 + 4) mm: 5 mm from the rim, gap 5 mm − r
  const Frame3 f = frame(Vec3::Zero(), Vec3::UnitZ(), Vec3::UnitX());
  const LevelSet3 ls(
      {Feature3("C", Feature3::Type::kCylinder,
                {constant(0.02), constant(0.02), constant(0.015), constant(0.005), var(0)}, true,
                f),
       Feature3("S", Feature3::Type::kSphere,
                {constant(0.028), constant(0.02), constant(0.024), var(1)}, true)},
      LevelSetNode::all_of(2), 2);
  LengthScaleOptions o;
  o.min_ligament = o.min_member = 0.004;
  const SolidLengthScale L(box(), ls, 2, o);
  const Vec p = (Vec(2) << 0.01, 0.002).finished();
  const auto c = L.evaluate(p);
  // (the max of the two distances, the lower bound, would give 4 mm − 2 mm = 2 mm)
  expect_bracket(find(c, "ligament.C.S"), 0.003, 3e-4);
  // member: the KS minimum of 2r = 10 mm and L = 10 mm, below both by at most the error bound
  expect_bracket(find(c, "member.C"), 0.01, 0);
  EXPECT_GT(find(c, "member.C").error_bound, 0);
  check_gradients(L, p);
}

TEST(SolidLengthScale, ThroughHolesMatchThePlanarMeasures) {
  // a 200 × 50 × 2.5 mm plate of 5 mm bricks and its section; super-ellipses S (p = cx, cy, a,
  // b; ξ = η = 5) and a fixed T at (150, 25) mm, 10 mm half-sides, through the thickness
  const SolidMesh plate = SolidMesh::box(Vec3::Zero(), Vec3(0.2, 0.05, 0.0025), {40, 10, 1});
  const Mesh2D section = Mesh2D::rectangle(0, 0, 0.2, 0.05, 40, 10);
  const std::vector<ParamBinding> ps = {var(0),      var(1),      var(2),     var(3),
                                        constant(5), constant(5), constant(0)};
  const std::vector<ParamBinding> pt = {constant(0.15), constant(0.025), constant(0.01),
                                        constant(0.01), constant(5),     constant(5),
                                        constant(0)};
  const Frame3 through = frame(Vec3::Zero(), Vec3::UnitZ(), Vec3::UnitX());
  const LevelSet3 ls3(
      {Feature3("S", Feature3::Type::kThroughHole, ps, true, through, Feature::Type::kSuperEllipse),
       Feature3("T", Feature3::Type::kThroughHole, pt, true, through,
                Feature::Type::kSuperEllipse)},
      LevelSetNode::all_of(2), 4);
  const LevelSet ls2({Feature("S", Feature::Type::kSuperEllipse, ps, true),
                      Feature("T", Feature::Type::kSuperEllipse, pt, true)},
                     LevelSetNode::all_of(2), 4);
  LengthScaleOptions o;
  o.min_ligament = o.min_edge = o.min_member = 0.01;
  const SolidLengthScale L3(plate, ls3, 2, o);
  const LengthScale L2(section, ls2, 2, o);
  const Vec p = (Vec(4) << 0.11, 0.025, 0.012, 0.016).finished();
  const auto c3 = L3.evaluate(p), c2 = L2.evaluate(p);
  ASSERT_EQ(L3.names(),
            (std::vector<std::string>{"ligament.S.T", "edge.S", "edge.T", "member.S", "member.T"}));
  expect_bracket(find(c3, "ligament.S.T"), (0.15 - 0.01) - (0.11 + 0.012), 1e-6);
  // the top and bottom faces, which the holes pass through, are not edges
  expect_bracket(find(c3, "edge.S"), 0.025 - 0.016, 1e-6);
  EXPECT_NEAR(find(c3, "edge.S").gradient[3], -1, 5e-3);
  for (const auto& name : {"ligament.S.T", "edge.S", "edge.T", "member.S"})
    EXPECT_NEAR(find(c3, name).value, find(c2, name).value,
                find(c3, name).error_bound + find(c2, name).error_bound)
        << name;
  check_gradients(L3, p);
  const Vec q = (Vec(4) << 0.09, 0.021, 0.014, 0.011).finished();
  check_gradients(L3, q);
}

TEST(SolidLengthScale, PocketFloorsAndWebs) {
  // a 60 × 40 × 10 mm block of 5 × 5 × 2.5 mm bricks; circular pockets (r = 8 mm at the centre)
  // P from the top face (depth p0) and Q from the bottom face (depth p1)
  const SolidMesh block = SolidMesh::box(Vec3::Zero(), Vec3(0.06, 0.04, 0.01), {12, 8, 4});
  const Frame3 top = frame(Vec3(0, 0, 0.01), -Vec3::UnitZ(), Vec3::UnitX());
  const Frame3 bottom = frame(Vec3::Zero(), Vec3::UnitZ(), Vec3::UnitX());
  // top's frame has v = w × u = −y: the centre (30, 20) mm is (u, v) = (30, −20) mm
  const LevelSet3 ls({Feature3("P", Feature3::Type::kPocket,
                               {constant(0.03), constant(-0.02), constant(0.008), var(0)}, true,
                               top, Feature::Type::kCircle),
                      Feature3("Q", Feature3::Type::kPocket,
                               {constant(0.03), constant(0.02), constant(0.008), var(1)}, true,
                               bottom, Feature::Type::kCircle)},
                     LevelSetNode::all_of(2), 2);
  LengthScaleOptions o;
  o.min_ligament = o.min_edge = 0.003;  // (measures above 3δ are reported as 3δ)
  const SolidLengthScale L(block, ls, 2, o);
  const Vec p = (Vec(2) << 0.004, 0.003).finished();
  const auto c = L.evaluate(p);
  // P's floor is the bottom face 10 − 4 = 6 mm away, but Q's entry face is open to Q only:
  // edge.P is min(6 mm to the bottom, 12 mm to the sides)
  expect_bracket(find(c, "edge.P"), 0.006, 1e-9);
  expect_bracket(find(c, "edge.Q"), 0.007, 1e-9);
  EXPECT_NEAR(find(c, "edge.P").gradient[0], -1, 1e-3);
  expect_bracket(find(c, "ligament.P.Q"), 0.01 - 0.004 - 0.003, 1e-9);
  EXPECT_NEAR(find(c, "ligament.P.Q").gradient[0], -1, 3e-2);
  EXPECT_NEAR(find(c, "ligament.P.Q").gradient[1], -1, 3e-2);
  check_gradients(L, p);
  // pockets that meet: the web is negative
  const Vec q = (Vec(2) << 0.006, 0.005).finished();
  EXPECT_LT(find(L.evaluate(q), "ligament.P.Q").value, -5e-4);
}

TEST(SolidLengthScale, NoCutIsRefused) {
  const LevelSet3 ls = spheres();
  LengthScaleOptions o;
  o.no_cut = 0.005;
  EXPECT_THROW(SolidLengthScale(box(), ls, 2, o), lsmbs::Error);
}

namespace {

// the least distance from an infinite cylinder (axis through c along unit a, radius r) to the
// rectangle {o + s·e1 + t·e2 : s, t ∈ [0, 1]}, by a 600 × 600 grid of it
double cylinder_to_rectangle(const Vec3& c, const Vec3& a, double r, const Vec3& o, const Vec3& e1,
                             const Vec3& e2) {
  double best = INFINITY;
  for (int i = 0; i <= 600; ++i)
    for (int j = 0; j <= 600; ++j) {
      const Vec3 d = o + (i / 600.0) * e1 + (j / 600.0) * e2 - c;
      best = std::min(best, (d - d.dot(a) * a).norm() - r);
    }
  return best;
}

}  // namespace

TEST(SolidLengthScale, ATiltedThroughHoleOpensTheFacesItsAxisLeavesThrough) {
  // a 100 × 60 × 60 mm box of 5 mm bricks; a cylinder of r = 5 mm through it (length 0), its
  // axis 40° from z in the x-z plane, centred at (cx, 30, 30) mm: the axis leaves through the
  // z faces for cx ≥ 25.2 mm, and they are not edges
  const SolidMesh m = SolidMesh::box(Vec3::Zero(), Vec3(0.1, 0.06, 0.06), {20, 12, 12});
  const double t = 40 * std::acos(-1.0) / 180;
  const Vec3 a(std::sin(t), 0, std::cos(t));
  const LevelSet3 ls(
      {Feature3("C", Feature3::Type::kCylinder,
                {var(0), constant(0.03), constant(0.03), constant(0.005), constant(0)}, true,
                frame(Vec3::Zero(), a, Vec3::UnitY()))},
      LevelSetNode::all_of(1), 1);
  LengthScaleOptions o;
  o.min_edge = 0.006;
  const SolidLengthScale L(m, ls, 1, o);
  // centred: the nearest lateral face (x = 100 mm, near the top) by brute force, 14 mm
  const double cx = 0.05;
  double ref = INFINITY;
  const Vec3 c(cx, 0.03, 0.03);
  const Vec3 X(0.1, 0, 0), Y(0, 0.06, 0), Z(0, 0, 0.06);
  const Vec3 O = Vec3::Zero();
  const std::vector<std::pair<Vec3, Vec3>> lateral = {{O, Y}, {X, Y}, {O, X}, {Y, X}};
  for (const auto& [origin, e1] : lateral)
    ref = std::min(ref, cylinder_to_rectangle(c, a, 0.005, origin, e1, Z));
  EXPECT_NEAR(ref, 0.014, 1e-3);
  const auto e = L.evaluate(Vec::Constant(1, cx))[0];
  expect_bracket(e, ref, 1e-4);
  check_gradients(L, Vec::Constant(1, cx));
  // at cx = 28 mm the axis still leaves through the bottom face (at x = 2.8 mm), but the
  // cylinder's wall breaks through the face x = 0 beside it: a negative edge ligament
  EXPECT_LT(L.evaluate(Vec::Constant(1, 0.028))[0].value, -0.0025);  // −2.9 mm at (0, 30, 0)
}

TEST(SolidLengthScale, SuperEllipsoidDistanceIsExactOutside) {
  // a ξ = 4 super-ellipsoid (a, b, c = 30, 10, 8 mm) at the centre of a 100 mm cube of 10 mm
  // bricks and a sphere of r = 5 mm at z = 30 mm above it: ligament 30 − 8 − 5 = 17 mm; edge
  // 50 − 30 = 20 mm (the first-order estimate gives 5.6 and 12.4 mm)
  const SolidMesh cube = SolidMesh::box(Vec3::Constant(-0.05), Vec3::Constant(0.1), {10, 10, 10});
  const LevelSet3 ls({Feature3("E", Feature3::Type::kSuperEllipsoid,
                               {constant(0), constant(0), constant(0), var(0), constant(0.01),
                                constant(0.008), constant(4)},
                               true),
                      Feature3("S", Feature3::Type::kSphere,
                               {constant(0), constant(0), constant(0.03), var(1)}, true)},
                     LevelSetNode::all_of(2), 2);
  LengthScaleOptions o;
  o.min_ligament = o.min_edge = 0.01;
  const SolidLengthScale L(cube, ls, 2, o);
  const Vec p = (Vec(2) << 0.03, 0.005).finished();
  const auto c = L.evaluate(p);
  expect_bracket(find(c, "ligament.E.S"), 0.017, 1e-4);
  expect_bracket(find(c, "edge.E"), 0.02, 1e-4);
  check_gradients(L, p);
  // off the axes: against the least distance to 2000 × 1000 points of its surface
  // (x, y, z) = (a cη^(1/2) cω^(1/2), b cη^(1/2) sω^(1/2), c sη^(1/2)) with signed powers
  const auto theta = ls.values(p);
  auto spow = [](double v) { return std::copysign(std::sqrt(std::abs(v)), v); };
  for (const Vec3& x : {Vec3(0.04, 0.02, 0.01), Vec3(0.01, 0.03, -0.02), Vec3(0.032, 0.0, 0.009)}) {
    double best = INFINITY;
    for (int i = 0; i <= 1000; ++i) {
      const double eta = std::acos(-1.0) * (i / 1000.0 - 0.5);
      for (int j = 0; j < 2000; ++j) {
        const double om = 2 * std::acos(-1.0) * j / 2000.0;
        const Vec3 y(0.03 * spow(std::cos(eta)) * spow(std::cos(om)),
                     0.01 * spow(std::cos(eta)) * spow(std::sin(om)), 0.008 * spow(std::sin(eta)));
        best = std::min(best, (x - y).norm());
      }
    }
    EXPECT_NEAR(L.shape_distance(0, x, theta), best, 2e-6) << x.transpose();
  }
}

TEST(SolidLengthScale, OverlappingFeaturesAndNegatedOnesBoundNoLigament) {
  // a counterbore: a through-hole (r = 10 mm) and a concentric pocket (r = 20 mm, 4 mm deep)
  // in a 100 × 100 × 10 mm plate overlap by design: their ligament (−10 mm, never positive) is
  // left out; a sphere under a NOT is material, not void: no ligament or edge of its own
  const SolidMesh m = SolidMesh::box(Vec3::Zero(), Vec3(0.1, 0.1, 0.01), {10, 10, 2});
  const Frame3 bottom = frame(Vec3::Zero(), Vec3::UnitZ(), Vec3::UnitX());
  LevelSetNode root = LevelSetNode::all_of(2);
  LevelSetNode core;  // AND(hole, bore, NOT(core))
  core.op = LevelSetNode::Op::kNot;
  core.children.push_back(LevelSetNode{LevelSetNode::Op::kFeature, 2, 0, {}});
  root.children.push_back(core);
  const LevelSet3 ls(
      {Feature3("hole", Feature3::Type::kThroughHole, {constant(0.05), constant(0.05), var(0)},
                true, bottom, Feature::Type::kCircle),
       Feature3("bore", Feature3::Type::kPocket,
                {constant(0.05), constant(0.05), constant(0.02), constant(0.004)}, true, bottom,
                Feature::Type::kCircle),
       Feature3("core", Feature3::Type::kSphere,
                {constant(0.02), constant(0.02), constant(0.005), constant(0.003)}, true)},
      root, 1);
  LengthScaleOptions o;
  o.min_ligament = o.min_edge = 0.003;
  SolidLengthScale L(m, ls, 3, o);
  EXPECT_EQ(L.names(), (std::vector<std::string>{"ligament.hole.bore", "edge.hole", "edge.bore"}));
  const Vec p = Vec::Constant(1, 0.01);
  EXPECT_LT(find(L.evaluate(p), "ligament.hole.bore").value, -0.009);
  EXPECT_EQ(L.leave_out_overlaps(p), std::vector<std::string>{"ligament.hole.bore"});
  EXPECT_EQ(L.names(), (std::vector<std::string>{"edge.hole", "edge.bore"}));
  ASSERT_EQ(L.evaluate(p).size(), 2u);
  expect_bracket(L.evaluate(p)[1], 0.006, 1e-9);  // the bore's floor: 10 − 4 mm
}
