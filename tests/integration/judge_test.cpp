// The judgement of optimized designs (runs/judge.hpp) on the robot arm (robot_arm_holes.json,
// h = 0.01 s) at two final designs of `optimize --starts 4 --seed 1` at commit 04aacf0
// (tests/data/judge/robot_arm_multistart_04aacf0.json; paper_results/robot_arm_multistart holds
// the current code's run):
//   - start 3 (101.035 g, ranked first before the judgement existed): feature LS4 with
//     b = 29.9 mm > the plate's 25 mm half-height cuts the plate in two at x = 575 mm; the slit
//     is 2 a₄ = 9.79 mm wide (the largest disc of a ξ = 5 super-ellipse with a < b has radius a),
//     under two 5 mm elements; the tip's part hangs on ersatz material, so the tip deviation
//     grows many times when that material is made 1000× weaker;
//   - start 1 (146.0 g, the paper's kind of layout): one piece, and its responses barely move
//     with the weaker void (the void's share of the stiffness is of order μ_min): a structure
//     (its ligaments of 7 to 10 mm, under two elements, are reported as unresolved).
// The mass with the weaker void against its closed form (eqs. 3, 5): m' − m = −ρ t μ_min (1 − f)
// Σ_e A_e (1 − H_e), with Σ_e A_e (1 − H_e) the void area the mapping gives.
#include "lsmbs/runs/judge.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

#include "lsmbs/design/design.hpp"
#include "lsmbs/io/optimization_spec.hpp"
#include "support/test_models.hpp"

using namespace lsmbs;
using json = nlohmann::json;

namespace {

struct Arm {
  Case cs;
  OptimizationSpec spec;
  Arm() : cs(test::make_case(document())), spec(parse_optimization(cs)) {}
  static json document() {
    json c = json::parse(
        std::ifstream(std::string(LSMBS_SOURCE_DIR) + "/data/robot_arm/robot_arm_holes.json"));
    c["simulation"]["h"] = 0.01;
    c["output"]["vtu_stride"] = 0;
    return c;
  }
  // the final design of a start of that run
  Vec final_design(int start) const {
    const json S = json::parse(std::ifstream(
        std::string(LSMBS_SOURCE_DIR) + "/tests/data/judge/robot_arm_multistart_04aacf0.json"));
    const json& design = S["starts"][std::to_string(start)]["design"];
    const Design& d = *cs.design;
    Vec p(d.size());
    for (int i = 0; i < d.size(); ++i) p[i] = design[d.variables[i].name];
    return p;
  }
  DesignJudgement judge(const Vec& p) const {
    return judge_design(conditions_of(cs), spec, p, thread_executor(2));
  }
};

const DesignJudgement::Response* response(const DesignJudgement& J, const std::string& name) {
  for (const auto& r : J.responses)
    if (r.name == name) return &r;
  return nullptr;
}

// Σ_e A_e (1 − H_e) of the plate at p, H_e = (μ_e − μ_min)/(1 − μ_min)
double void_area(const Case& cs, const Vec& p) {
  const BodyDesign& b = cs.design->bodies.front();
  Vec mu;
  b.map->map(p, mu);
  const double m = b.map->options().mu_min;
  double a = 0;
  for (Eigen::Index e = 0; e < mu.size(); ++e)
    a += b.map->element_areas()[static_cast<size_t>(e)] * (1 - (mu[e] - m) / (1 - m));
  return a;
}

}  // namespace

TEST(Judge, ASlitThatCutsTheArmsPlateIsFlaggedTwice) {
  const Arm arm;
  const Vec p = arm.final_design(3);
  const DesignJudgement J = arm.judge(p);
  for (const auto& f : J.flags()) std::printf("flag: %s\n", f.c_str());
  EXPECT_EQ(J.verdict(), DesignJudgement::Verdict::kNotAStructure);
  ASSERT_EQ(J.bodies.size(), 1u);
  const ResolutionReport& R = J.bodies[0].resolution;
  EXPECT_EQ(R.pieces.size(), 2u) << "LS4 cuts the plate in two";
  const NarrowPart* slit = nullptr;
  for (const auto& q : R.parts)
    if (q.kind == NarrowPart::Kind::kHole && q.first == "LS4") slit = &q;
  ASSERT_NE(slit, nullptr);
  const double a4 = p[arm.cs.design->variable_index("a4")];
  EXPECT_NEAR(slit->width, 2 * a4, R.spacing);
  EXPECT_TRUE(slit->unresolved);
  // the load path: the tip's part hangs on the void
  const auto* dev = response(J, "average_tip_deviation");
  ASSERT_NE(dev, nullptr);
  std::printf("average_tip_deviation %.6g m -> %.6g m (change %.3g)\n", dev->value, dev->weak,
              dev->change);
  EXPECT_TRUE(dev->flagged);
  EXPECT_GT(dev->change, 1.0) << "many times the deviation, not a fraction of it";
}

TEST(Judge, ThePaperKindOfLayoutRestsOnMaterial) {
  const Arm arm;
  const Vec p = arm.final_design(1);
  const DesignJudgement J = arm.judge(p);
  for (const auto& f : J.flags()) std::printf("flag: %s\n", f.c_str());
  ASSERT_EQ(J.bodies.size(), 1u);
  EXPECT_EQ(J.bodies[0].resolution.pieces.size(), 1u);
  // a structure; its ligaments of 7 to 10 mm are under two 5 mm elements (unresolved)
  EXPECT_TRUE(J.structure_flags.empty());
  EXPECT_NE(J.verdict(), DesignJudgement::Verdict::kNotAStructure);
  const auto* dev = response(J, "average_tip_deviation");
  ASSERT_NE(dev, nullptr);
  std::printf("average_tip_deviation %.9g m -> %.9g m (change %.3g)\n", dev->value, dev->weak,
              dev->change);
  EXPECT_FALSE(dev->flagged);
  EXPECT_LT(dev->change, arm.spec.judge.ersatz_tolerance);
  // the mass with the weaker void against its closed form
  const auto* mass = response(J, "plate_mass");
  ASSERT_NE(mass, nullptr);
  const double rho = 2700, t = 0.0025, mu_min = 1e-3, f = arm.spec.judge.ersatz_factor;
  const double expected = -rho * t * mu_min * (1 - f) * void_area(arm.cs, p);
  EXPECT_NEAR(mass->weak - mass->value, expected, 1e-12 * mass->value);
  EXPECT_FALSE(mass->flagged);
}

// Solid designs (data/spatial/solid_arm.json, 20 ms of its motion): the drilled and pocketed
// plate rests on material (one piece; its responses barely move with the weaker void; the mass
// change against the closed form −ρ μ_min (1 − f) Σ_e V_e (1 − H_e)); with hole2 made a slot
// (a ξ = 8 super-ellipse 2·r2 = 60 mm wide, holding two of the plate's 20 mm bricks whole, and
// 120 mm tall, through its 80 mm height) the payload's part hangs on ersatz material: two pieces,
// and over the 20 ms the tip falls much farther with the weaker void (0.39 to 0.67 mm: free fall
// is ½ g t² = 2 mm at the end). A narrower slot also leaves two pieces, but the bricks it cuts
// keep material (a 12 mm slot leaves them 40 % full, a 40 mm one the logistic's tails): the mapped
// model carries the load through them, which the resolution check flags as a hole narrower than
// two bricks.
namespace {

struct SolidArm {
  Case cs;
  OptimizationSpec spec;
  explicit SolidArm(bool slot)
      : cs(test::make_case(document(slot))), spec(parse_optimization(cs)) {}
  static json document(bool slot) {
    json c =
        json::parse(std::ifstream(std::string(LSMBS_SOURCE_DIR) + "/data/spatial/solid_arm.json"));
    c["simulation"]["t_end"] = 0.02;
    c["optimization"] = {
        {"objective", "plate_mass"},
        {"constraints", json::array({{{"response", "mean_tip_z"}, {"upper", 1e-4}}})}};
    if (slot)
      c["design"]["geometry"][0]["features"][1] = {{"name", "hole2"}, {"type", "through_hole"},
                                                   {"face", "ymax"},  {"profile", "super_ellipse"},
                                                   {"cx", 0.2},       {"cy", 0},
                                                   {"a", "r2"},       {"b", 0.06},
                                                   {"xi", 8},         {"eta", 8},
                                                   {"angle", 0}};
    return c;
  }
  DesignJudgement judge(const Vec& p) const {
    return judge_design(conditions_of(cs), spec, p, thread_executor(2));
  }
};

}  // namespace

TEST(Judge, ASolidPlateRestsOnMaterialAndASlotCutsIt) {
  const SolidArm arm(false);
  const Vec p = arm.cs.design->initial();
  const DesignJudgement J = arm.judge(p);
  for (const auto& f : J.flags()) std::printf("flag: %s\n", f.c_str());
  ASSERT_EQ(J.bodies.size(), 1u);
  const ResolutionReport& R = J.bodies[0].resolution;
  EXPECT_TRUE(R.solid);
  EXPECT_EQ(R.pieces.size(), 1u);
  EXPECT_TRUE(J.structure_flags.empty());
  const auto* tip = response(J, "mean_tip_z");
  ASSERT_NE(tip, nullptr);
  std::printf("mean_tip_z %.9g m -> %.9g m (change %.3g)\n", tip->value, tip->weak, tip->change);
  EXPECT_FALSE(tip->flagged);
  const auto* mass = response(J, "plate_mass");
  ASSERT_NE(mass, nullptr);
  const SolidBodyDesign& b = arm.cs.design->solid_bodies.front();
  Vec mu;
  b.map->map(p, mu);
  const double m = b.map->options().mu_min, f = arm.spec.judge.ersatz_factor;
  double void_volume = 0;
  for (Eigen::Index e = 0; e < mu.size(); ++e)
    void_volume += b.map->element_volumes()[static_cast<size_t>(e)] * (1 - (mu[e] - m) / (1 - m));
  EXPECT_NEAR(mass->weak - mass->value, -2700 * m * (1 - f) * void_volume, 1e-12 * mass->value);

  const SolidArm cut(true);
  const Vec q = (Vec(3) << 0.02, 0.03, 0.004).finished();
  const DesignJudgement K = cut.judge(q);
  for (const auto& x : K.flags()) std::printf("flag: %s\n", x.c_str());
  EXPECT_EQ(K.verdict(), DesignJudgement::Verdict::kNotAStructure);
  ASSERT_EQ(K.bodies.size(), 1u);
  ASSERT_EQ(K.bodies[0].resolution.pieces.size(), 2u) << "the slot cuts the plate in two";
  // the hub's piece: x < 170 mm of the 10 × 80 mm section, less hole1 (r1 = 20 mm)
  const double hub_piece = (0.17 * 0.01 * 0.08 - std::acos(-1.0) * 0.02 * 0.02 * 0.01);
  EXPECT_NEAR(K.bodies[0].resolution.pieces[0] / hub_piece, 1, 0.01);
  const auto* sag = response(K, "mean_tip_z");
  ASSERT_NE(sag, nullptr);
  std::printf("slotted: mean_tip_z %.9g m -> %.9g m (change %.3g)\n", sag->value, sag->weak,
              sag->change);
  EXPECT_TRUE(sag->flagged);
  EXPECT_GT(sag->change, 0.5) << "the fall grows by more than half, not by a fraction of μ_min";
}
