// Consistent initial velocities (integrators/initial_state.hpp, loaded by io/case_loader):
//  - the velocities a case gives are kept exactly and the others follow from the constraints —
//    the spring slider-crank's crank speed of 60 rad/s against the closed-form slider-crank
//    velocity kinematics (it started at 54.36 rad/s when all velocities were projected in one
//    Euclidean metric that mixed m/s and rad/s);
//  - given velocities that contradict the constraints are an input error naming the body;
//  - consistent over-specified velocities are accepted and kept;
//  - without given velocities the projection is the smallest change in the metric
//    Σ Δẋ² + L² Σ Δθ̇² (closed form on a pendulum).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>

#include "lsmbs/core/error.hpp"
#include "lsmbs/integrators/initial_state.hpp"
#include "support/test_models.hpp"

using namespace lsmbs;
using json = nlohmann::json;

namespace {

json spring_crank() {
  return json::parse(std::ifstream(std::string(LSMBS_SOURCE_DIR) +
                                   "/data/slider_crank_rigid/slider_crank_spring.json"));
}

// Slider-crank with the crank pinned at its reference point (origin), crank pin at radius r,
// rod of length l from the crank pin (the rod's reference point) to the piston on the x axis:
//   x_p = r cos θ + c,  c = sqrt(l² − r² sin² θ),   φ = −asin(r sin θ / l)
//   ẋ_p = −r ω sin θ (1 + r cos θ / c),  φ̇ = −r ω cos θ / c,  v_pin = r ω (−sin θ, cos θ).
struct CrankVelocities {
  double xp_dot, phi_dot;
  Vec2 pin;
};
CrankVelocities crank_kinematics(double r, double l, double th, double w) {
  const double c = std::sqrt(l * l - r * r * std::sin(th) * std::sin(th));
  return {-r * w * std::sin(th) * (1 + r * std::cos(th) / c), -r * w * std::cos(th) / c,
          r * w * Vec2(-std::sin(th), std::cos(th))};
}

}  // namespace

TEST(InitialVelocity, GivenCrankSpeedIsKeptAndTheRestFollowsTheClosedForm) {
  const Case cs = test::make_case(spring_crank());
  const Model& m = *cs.model;
  const auto& crank = *m.find_rigid("crank");
  const auto& rod = *m.find_rigid("rod");
  const auto& piston = *m.find_rigid("piston");
  const Vec& v = cs.initial.v;
  const auto k = crank_kinematics(0.045, 0.1356, 0.3, 60.0);
  std::printf(
      "crank %.15g rad/s; rod pin (%.12f, %.12f) m/s, rod %.12f rad/s, piston %.12f m/s "
      "(closed form: (%.12f, %.12f), %.12f, %.12f)\n",
      v[crank.dof0 + 2], v[rod.dof0], v[rod.dof0 + 1], v[rod.dof0 + 2], v[piston.dof0], k.pin.x(),
      k.pin.y(), k.phi_dot, k.xp_dot);
  EXPECT_EQ(v[crank.dof0 + 2], 60.0) << "the given crank speed is kept exactly";
  // the solve is one sparse LU of an O(1)-conditioned 15 × 15 system: round-off ~1e-15 of the
  // speeds (2.7 m/s, 20 rad/s)
  EXPECT_NEAR(v[crank.dof0], 0.0, 1e-14);
  EXPECT_NEAR(v[crank.dof0 + 1], 0.0, 1e-14);
  EXPECT_NEAR(v[rod.dof0], k.pin.x(), 1e-13);
  EXPECT_NEAR(v[rod.dof0 + 1], k.pin.y(), 1e-13);
  EXPECT_NEAR(v[rod.dof0 + 2], k.phi_dot, 1e-12);
  EXPECT_NEAR(v[piston.dof0], k.xp_dot, 1e-13);
  EXPECT_NEAR(v[piston.dof0 + 1], 0.0, 1e-14);
  EXPECT_NEAR(v[piston.dof0 + 2], 0.0, 1e-12);
  // the integrator's own projection (no velocities held) then has nothing left to correct
  State s = cs.initial;
  SparseLU lu;
  lu.analyze(m.pattern());
  ProjectionReport rep;
  ASSERT_TRUE(project_initial_state(m, m.params(), s, lu, 1e-13 * m.length_scale(), &rep).ok());
  EXPECT_LT(rep.vel_before, 1e-13);
  EXPECT_NEAR(s.v[crank.dof0 + 2], 60.0, 1e-12);
}

TEST(InitialVelocity, ConsistentVelocitiesGivenForMoreBodiesAreKept) {
  json j = spring_crank();
  const auto k = crank_kinematics(0.045, 0.1356, 0.3, 60.0);
  j["bodies"][1]["velocity"] = {k.pin.x(), k.pin.y()};
  j["bodies"][1]["angular_velocity"] = k.phi_dot;
  j["bodies"][2]["velocity"] = {k.xp_dot, 0.0};
  const Case cs = test::make_case(j);
  const Model& m = *cs.model;
  const auto& rod = *m.find_rigid("rod");
  const auto& piston = *m.find_rigid("piston");
  EXPECT_EQ(cs.initial.v[m.find_rigid("crank")->dof0 + 2], 60.0);
  EXPECT_EQ(cs.initial.v[rod.dof0 + 2], k.phi_dot);
  EXPECT_EQ(cs.initial.v[piston.dof0], k.xp_dot);
}

TEST(InitialVelocity, ContradictoryGivenVelocitiesAreAnInputErrorNamingTheBody) {
  json j = spring_crank();
  j["bodies"][2]["velocity"] = {1.0, 0.0};  // the crank speed requires −3.06 m/s
  try {
    test::make_case(j);
    FAIL() << "expected an input error";
  } catch (const Error& e) {
    const std::string msg = e.what();
    std::printf("%s\n", msg.c_str());
    EXPECT_NE(msg.find("contradict the constraints"), std::string::npos) << msg;
    EXPECT_TRUE(msg.find("/bodies/0/angular_velocity") != std::string::npos ||
                msg.find("/bodies/2/velocity") != std::string::npos)
        << msg;
  }
  // a driver that imposes a speed at t = 0 contradicts a body speed of zero given explicitly
  json d = spring_crank();
  d["bodies"][0]["angular_velocity"] = 0.0;
  d["joints"].push_back(
      {{"name", "motor"},
       {"type", "rotation_driver"},
       {"body", "crank"},
       {"law",
        {{"type", "table"}, {"points", {{-1, -10.0}, {1, 10.0}}}, {"interpolation", "linear"}}}});
  try {
    test::make_case(d);
    FAIL() << "expected an input error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("/bodies/0/angular_velocity"), std::string::npos)
        << e.what();
  }
}

TEST(InitialVelocity, UnheldProjectionIsTheSmallestChangeInTheUnitConsistentMetric) {
  // A body pinned to ground at its body point (−1, 0) at angle 0: the joint requires vx = 0 and
  // vy = ω. From the given (vx, vy, ω) = (0.3, 2, 5) the smallest change of
  // Δvx² + Δvy² + L² Δω² is vx = 0, vy = ω = (vy + L² ω)/(1 + L²).
  const Case cs = test::make_case(R"({
    "bodies": [{"name": "bar", "type": "rigid", "position": [1, 0], "mass": 1, "inertia": 0.1}],
    "joints": [{"name": "pin", "type": "revolute", "a": {"body": "bar", "at": [-1, 0]}, "b": "ground"}],
    "simulation": {"t_end": 0.1, "h": 0.01}
  })"_json);
  const Model& m = *cs.model;
  State s = cs.initial;
  s.v << 0.3, 2, 5;
  SparseLU lu;
  lu.analyze(m.pattern());
  ASSERT_TRUE(project_initial_state(m, m.params(), s, lu, 1e-13, nullptr).ok());
  const double L = m.length_scale(), w = (2 + L * L * 5) / (1 + L * L);
  std::printf("L = %g: projected (%.15g, %.15g, %.15g), closed form (0, %.15g, %.15g)\n", L, s.v[0],
              s.v[1], s.v[2], w, w);
  EXPECT_NEAR(s.v[0], 0, 1e-15);
  EXPECT_NEAR(s.v[1], w, 1e-14);
  EXPECT_NEAR(s.v[2], w, 1e-14);
}
