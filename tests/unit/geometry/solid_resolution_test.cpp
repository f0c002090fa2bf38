// The resolution of solid designs (geometry/solid_resolution.hpp) against closed forms:
//   - two circular through-holes (r = 10 mm) 6 mm apart in a 200 × 50 × 2.5 mm plate of 5 mm
//     bricks: the ligament, 6 mm, is unresolved (two cells across it: 10 mm); the holes' edge
//     ligaments, 15 mm, and widths, 20 mm, are resolved; one piece, of the plate's volume less
//     the holes' (π r² t each) to the sampling's accuracy;
//   - a pocket's floor in a 10 mm block of 2.5 mm layers is judged across the layers: 1.5 mm
//     is unresolved (threshold 2 × 2.5 mm), 6 mm resolved although under two 5 mm cell lengths;
//   - a slot through the plate's whole height cuts it into two pieces of 97 × 50 × 2.5 mm each.
//   - a hole inside another bounds no void and is not judged; equal round holes have equal
//     thresholds (the cell's thinnest extent across them); a hole that breaks through one face
//     (a notch) keeps its 7 mm flange to another face judged.
#include "lsmbs/geometry/solid_resolution.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "support/frames.hpp"

using namespace lsmbs;
using lsmbs::test::frame;

namespace {

ParamBinding var(int k) { return {0, 1, k}; }
ParamBinding constant(double v) { return {v, 0, -1}; }

const SolidMesh& plate() {
  static const SolidMesh m = SolidMesh::box(Vec3::Zero(), Vec3(0.2, 0.05, 0.0025), {40, 10, 1});
  return m;
}

const NarrowPart* part(const ResolutionReport& R, const std::string& first,
                       const std::string& second) {
  for (const auto& p : R.parts)
    if (p.first == first && p.second == second) return &p;
  return nullptr;
}

}  // namespace

TEST(SolidResolution, ThroughHolesInAPlate) {
  const Frame3 f = frame(Vec3::Zero(), Vec3::UnitZ(), Vec3::UnitX());
  const LevelSet3 ls(
      {Feature3("A", Feature3::Type::kThroughHole, {var(0), constant(0.025), constant(0.01)}, true,
                f, Feature::Type::kCircle),
       Feature3("B", Feature3::Type::kThroughHole, {var(1), constant(0.025), constant(0.01)}, true,
                f, Feature::Type::kCircle)},
      LevelSetNode::all_of(2), 2);
  const Vec p = (Vec(2) << 0.06, 0.086).finished();
  const ResolutionReport R = judge_solid_resolution(plate(), ls, 2, p);
  EXPECT_TRUE(R.solid);
  EXPECT_NEAR(R.element_size, 0.005, 1e-15);
  EXPECT_NEAR(R.threshold, 0.01, 1e-15);
  const NarrowPart* lig = part(R, "A", "B");
  ASSERT_NE(lig, nullptr);
  EXPECT_NEAR(lig->width, 0.006, R.spacing);
  // two 5 mm cells along x (the narrowest sample lies 0.625 mm off the line of centres, so the
  // direction across it leans by a few degrees: the cell's extent along it grows by up to 5 %)
  EXPECT_NEAR(lig->threshold, 0.01, 5e-4);
  EXPECT_TRUE(lig->unresolved);
  ASSERT_EQ(lig->at.size(), 3);
  EXPECT_NEAR(lig->at[0], 0.073, R.spacing);  // midway
  const NarrowPart* edge = part(R, "A", "surface");
  ASSERT_NE(edge, nullptr);
  EXPECT_NEAR(edge->width, 0.015, R.spacing);
  EXPECT_FALSE(edge->unresolved);
  const NarrowPart* hole = part(R, "B", "");
  ASSERT_NE(hole, nullptr);
  EXPECT_NEAR(hole->width, 0.02, 1e-12);
  EXPECT_FALSE(hole->unresolved);
  ASSERT_EQ(R.flags().size(), 1u);
  EXPECT_NE(R.flags()[0].find("between feature 'A' and feature 'B' is 6"), std::string::npos)
      << R.flags()[0];
  ASSERT_EQ(R.pieces.size(), 1u);
  const double V = 0.2 * 0.05 * 0.0025 - 2 * std::numbers::pi * 0.01 * 0.01 * 0.0025;
  EXPECT_NEAR(R.pieces[0] / V, 1, 0.01);
  EXPECT_TRUE(R.pieces_flag().empty());
}

TEST(SolidResolution, APocketsFloorIsJudgedAcrossTheLayers) {
  const SolidMesh block = SolidMesh::box(Vec3::Zero(), Vec3(0.06, 0.04, 0.01), {12, 8, 4});
  const Frame3 top = frame(Vec3(0, 0, 0.01), -Vec3::UnitZ(), Vec3::UnitX());
  const LevelSet3 ls({Feature3("P", Feature3::Type::kPocket,
                               {constant(0.03), constant(-0.02), constant(0.008), var(0)}, true,
                               top, Feature::Type::kCircle)},
                     LevelSetNode::all_of(1), 1);
  for (const double depth : {0.0085, 0.004}) {
    const ResolutionReport R = judge_solid_resolution(block, ls, 1, Vec::Constant(1, depth));
    const NarrowPart* floor = part(R, "P", "surface");
    ASSERT_NE(floor, nullptr) << depth;
    EXPECT_NEAR(floor->width, 0.01 - depth, 1e-3 * R.threshold) << depth;
    EXPECT_NEAR(floor->threshold, 2 * 0.0025, 1e-12) << "across the 2.5 mm layers";
    EXPECT_EQ(floor->unresolved, depth > 0.005) << depth;
    EXPECT_NEAR(floor->at[2], 0, 1e-12) << "on the bottom face";
  }
}

TEST(SolidResolution, ASlotThroughThePlateLeavesTwoPieces) {
  const Frame3 f = frame(Vec3::Zero(), Vec3::UnitZ(), Vec3::UnitX());
  const LevelSet3 ls({Feature3("slot", Feature3::Type::kThroughHole,
                               {constant(0.1), constant(0.025), var(0), constant(0.1), constant(8),
                                constant(8), constant(0)},
                               true, f, Feature::Type::kSuperEllipse)},
                     LevelSetNode::all_of(1), 1);
  const ResolutionReport R = judge_solid_resolution(plate(), ls, 1, Vec::Constant(1, 0.003));
  ASSERT_EQ(R.pieces.size(), 2u);
  for (double v : R.pieces) EXPECT_NEAR(v / (0.097 * 0.05 * 0.0025), 1, 0.01);
  EXPECT_NE(R.pieces_flag().find("2 pieces (volumes"), std::string::npos) << R.pieces_flag();
}

TEST(SolidResolution, OnlyFeaturesThatBoundVoidAreJudgedAndANotchKeepsItsFlanges) {
  // in the plate of 5 mm bricks: A (r = 10 mm) at (60, 25) mm with B (r = 3 mm) inside it, which
  // bounds no void; D (r = 10 mm) at (110, 25) mm, as wide as A; C (r = 8 mm) at (185, 46) mm,
  // which breaks through the top face (a notch) and leaves 7 mm to the end face x = 200 mm
  const Frame3 f = frame(Vec3::Zero(), Vec3::UnitZ(), Vec3::UnitX());
  auto circle = [&](const char* name, double cx, double cy, double r) {
    return Feature3(name, Feature3::Type::kThroughHole, {constant(cx), constant(cy), constant(r)},
                    true, f, Feature::Type::kCircle);
  };
  const LevelSet3 ls({circle("A", 0.06, 0.025, 0.01), circle("B", 0.06, 0.025, 0.003),
                      circle("C", 0.185, 0.046, 0.008), circle("D", 0.11, 0.025, 0.01)},
                     LevelSetNode::all_of(4), 0);
  const ResolutionReport R = judge_solid_resolution(plate(), ls, 4, Vec());
  for (const auto& q : R.parts) EXPECT_TRUE(q.first != "B" && q.second != "B") << "B is in A";
  const NarrowPart* a = part(R, "A", "");
  const NarrowPart* d = part(R, "D", "");
  ASSERT_TRUE(a && d);
  EXPECT_NEAR(a->threshold, 0.01, 1e-12);  // round holes: the cell's thinnest extent across
  EXPECT_NEAR(d->threshold, 0.01, 1e-12);
  const NarrowPart* flange = nullptr;
  for (const auto& q : R.parts)
    if (q.first == "C" && q.second == "surface" && q.at[0] > 0.199) flange = &q;
  ASSERT_NE(flange, nullptr) << "the notch hides no flange";
  EXPECT_NEAR(flange->width, 0.007, 2e-5);      // samples off the foot: (0.625 mm)²/(2 · 15 mm)
  EXPECT_NEAR(flange->threshold, 0.01, 1e-12);  // across the end face: two 5 mm cells
  EXPECT_TRUE(flange->unresolved);
}
