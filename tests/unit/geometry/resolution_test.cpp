// What the fixed mesh resolves of a design (geometry/resolution.hpp) against closed forms on a
// 200 × 50 mm plate of 5 mm elements (40 × 10; grid spacing 1.25 mm, threshold 10 mm):
//   - the ligament between two circular holes of radius r whose centres are L apart is L − 2r
//     wide, and a hole's ligament to the plate's edge is the edge's distance minus r;
//   - a hole meeting the edge at a right angle is a notch, not a ligament of width zero;
//   - an ellipse whose minor semi-axis is a is 2a wide (the largest disc it holds), and one longer
//     than the plate is high cuts it into two pieces whose areas are the rectangle's less the
//     ellipse's segment, A = a (c √(1 − c²/b²) + b asin(c/b)) per half within |y| ≤ c;
//   - a non-design ring around a hole: its outer edge lies in material and bounds nothing.
// Ligament widths are required within one grid spacing, a hole's within 0.1 %, areas within
// spacing × perimeter.
#include "lsmbs/geometry/resolution.hpp"

#include <gtest/gtest.h>

#include <cmath>

using namespace lsmbs;

namespace {

ParamBinding constant(double v) { return {v, 0, -1}; }

Feature circle(const std::string& name, double cx, double cy, double r, bool hole = true) {
  return Feature(name, Feature::Type::kCircle, {constant(cx), constant(cy), constant(r)}, hole);
}

Feature ellipse(const std::string& name, double cx, double cy, double a, double b) {
  return Feature(name, Feature::Type::kEllipse,
                 {constant(cx), constant(cy), constant(a), constant(b), constant(1), constant(0)},
                 true);
}

const Mesh2D& plate() {
  static const Mesh2D m = Mesh2D::rectangle(0, 0, 0.2, 0.05, 40, 10);
  return m;
}

ResolutionReport judge(std::vector<Feature> f) {
  const int n = static_cast<int>(f.size());
  LevelSet ls(std::move(f), LevelSetNode::all_of(n), 0);
  return judge_resolution(plate(), ls, ls.values(Vec()));
}

const NarrowPart* find(const ResolutionReport& R, const std::string& a, const std::string& b) {
  for (const NarrowPart& p : R.parts)
    if ((p.first == a && p.second == b) || (p.first == b && p.second == a)) return &p;
  return nullptr;
}

const NarrowPart* hole(const ResolutionReport& R, const std::string& a) {
  for (const NarrowPart& p : R.parts)
    if (p.kind == NarrowPart::Kind::kHole && p.first == a) return &p;
  return nullptr;
}

}  // namespace

TEST(Resolution, LigamentBetweenTwoCirclesIsTheirGap) {
  const double r = 0.01;
  for (double gap : {0.003, 0.006, 0.012}) {
    const auto R =
        judge({circle("h1", 0.06, 0.025, r), circle("h2", 0.06 + 2 * r + gap, 0.025, r)});
    EXPECT_NEAR(R.element_size, 0.005, 1e-12);
    EXPECT_NEAR(R.threshold, 0.010, 1e-12);
    const NarrowPart* p = find(R, "h1", "h2");
    ASSERT_NE(p, nullptr) << "gap " << gap;
    EXPECT_NEAR(p->width, gap, R.spacing) << "gap " << gap;
    EXPECT_EQ(p->unresolved, gap < R.threshold) << "gap " << gap;
    EXPECT_NEAR(p->at.y(), 0.025, R.spacing);  // on the line of centres
    // both holes 15 mm from the long edges: resolved
    const NarrowPart* e = find(R, "h1", "outer edge");
    ASSERT_NE(e, nullptr);
    EXPECT_NEAR(e->width, 0.015, R.spacing);
    EXPECT_FALSE(e->unresolved);
    EXPECT_EQ(R.pieces.size(), 1u);
    EXPECT_EQ(R.flags().size(), gap < R.threshold ? 1u : 0u);
  }
}

TEST(Resolution, FlangeBetweenAHoleAndTheEdge) {
  // a circle 2 mm below the top edge: a flange the mesh does not resolve
  const auto R = judge({circle("h", 0.1, 0.038, 0.01)});
  const NarrowPart* e = find(R, "h", "outer edge");
  ASSERT_NE(e, nullptr);
  EXPECT_NEAR(e->width, 0.002, R.spacing);
  EXPECT_TRUE(e->unresolved);
  EXPECT_NEAR(e->at.x(), 0.1, R.spacing);
  ASSERT_EQ(R.flags().size(), 1u);
  EXPECT_NE(R.flags()[0].find("feature 'h' and the outer edge"), std::string::npos) << R.flags()[0];
}

TEST(Resolution, ANotchIsNoLigament) {
  // centred on the top edge: it meets the edge at right angles; the material left below it is
  // 50 − 10 = 40 mm high
  const auto R = judge({circle("notch", 0.1, 0.05, 0.01)});
  const NarrowPart* e = find(R, "notch", "outer edge");
  ASSERT_NE(e, nullptr);
  EXPECT_NEAR(e->width, 0.040, R.spacing);
  EXPECT_TRUE(R.flags().empty()) << R.flags()[0];
}

TEST(Resolution, ASlitIsTwiceItsMinorSemiAxisAndCutsThePlateInTwo) {
  const double a = 0.002, b = 0.04, c = 0.025;  // longer than the plate's half-height
  const auto R = judge({ellipse("slit", 0.1, 0.025, a, b)});
  const NarrowPart* h = hole(R, "slit");
  ASSERT_NE(h, nullptr);
  // refined by the pattern search to the accuracy of the feature's distance 2 mm inside a 20:1
  // ellipse (measured 4.5e-6 m)
  EXPECT_NEAR(h->width, 2 * a, 1e-3 * 2 * a);
  EXPECT_TRUE(h->unresolved);
  ASSERT_EQ(R.pieces.size(), 2u);
  const double segment = a * (c * std::sqrt(1 - c * c / (b * b)) + b * std::asin(c / b));
  const double piece = 0.1 * 0.05 - segment;  // each side: half the plate less half the slit
  const double perimeter = 2 * (0.1 + 0.05);
  for (double A : R.pieces) EXPECT_NEAR(A, piece, R.spacing * perimeter);
  EXPECT_NE(R.pieces_flag().find("falls apart into 2 pieces"), std::string::npos)
      << R.pieces_flag();
}

TEST(Resolution, TheOuterEdgeOfANonDesignRingInMaterialBoundsNothing) {
  // material where the hole is not, or inside the ring (the ring OR-ed with the holes' AND)
  std::vector<Feature> f = {circle("hole", 0.1, 0.025, 0.01),
                            circle("ring", 0.1, 0.025, 0.012, false)};
  LevelSetNode holes = LevelSetNode::all_of(1), root;
  root.op = LevelSetNode::Op::kOr;
  LevelSetNode ring;
  ring.feature = 1;
  root.children = {holes, ring};
  LevelSet ls(std::move(f), root, 0);
  const auto R = judge_resolution(plate(), ls, ls.values(Vec()));
  EXPECT_EQ(find(R, "hole", "ring"), nullptr)
      << "the ring's 2 mm is no ligament: material surrounds it";
  EXPECT_TRUE(R.flags().empty());
  EXPECT_TRUE(R.pieces_flag().empty());
}
