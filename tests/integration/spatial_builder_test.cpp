// Spatial models built by name through the ModelBuilder (mbs/model_builder.hpp), against
// independent references:
//  - a crank driven at constant speed through its revolute joint's angle: the slider of a
//    spatial slider-crank (spherical and universal joints, slider line out of the crank's plane)
//    follows the closed-form loop closure y = y_pin + √(L² − Δx² − z_pin²);
//  - a body on a revolute joint with a torsional spring on the joint angle oscillates at
//    √(k / I_axis), with the principal axes of the body tilted against the global axes;
//  - a body hung on a spatial spring under a constant force: static offset F/k and frequency
//    √(k/m) along the spring;
//  - bad input names the entity and the field.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <numbers>

#include "lsmbs/integrators/generalized_alpha.hpp"
#include "lsmbs/integrators/initial_state.hpp"
#include "lsmbs/mbs/model_builder.hpp"
#include "support/spatial_models.hpp"

using namespace lsmbs;

namespace {

constexpr double kPi = std::numbers::pi;

SpatialBodyOptions body(double m, const Vec3& I, const Vec3& x, const Mat3& R = Mat3::Identity()) {
  SpatialBodyOptions o;
  o.mass = m, o.inertia = I, o.position = x, o.orientation = R;
  return o;
}

}  // namespace

TEST(SpatialBuilder, DrivenSliderCrankFollowsTheClosedFormLoopClosure) {
  const double crank = 0.1, rod = 0.3, offset = 0.2, omega = 50;
  const Vec3 P(0, crank, 0), S(offset, crank + std::sqrt(rod * rod - offset * offset), 0);
  const Vec3 dir = (S - P) / rod;
  Mat3 Rrod;
  Rrod << Vec3::UnitZ(), dir.cross(Vec3::UnitZ()), dir;
  ModelBuilder b;
  b.set_spatial_gravity(Vec3(0, 0, -9.81));
  b.spatial_body("crank", body(0.2, Vec3(1.67e-4, 1e-6, 1.67e-4), P / 2));
  b.spatial_body("rod", body(0.5, Vec3(3.75e-3, 3.75e-3, 1e-5), (P + S) / 2, Rrod));
  b.spatial_body("slider", body(0.3, Vec3(1e-4, 1e-4, 1e-4), S));
  using K = SpatialJointKind;
  b.spatial_joint("bearing", K::kRevolute, "ground", "crank", {Vec3::Zero(), Vec3::UnitX(), {}});
  b.spatial_joint("pin", K::kSpherical, "crank", "rod", {P, Vec3::UnitZ(), {}});
  b.spatial_joint("wrist", K::kUniversal, "slider", "rod",
                  {S, Vec3::UnitZ(), Vec3(dir.cross(Vec3::UnitZ()))});
  b.spatial_joint("slide", K::kPrismatic, "ground", "slider", {S, Vec3::UnitY(), {}});
  b.joint_rotation_driver("motor", "bearing", std::make_shared<RampLaw>(0.0, omega, 0.05));
  const int theta = b.spatial_joint_info("bearing").theta_dof, y = b.spatial("slider").dof0 + 1;
  const auto model = b.build();
  EXPECT_EQ(model->nq() - model->nc(), 0);  // driven: no freedom left
  double err = 0, turns = 0;
  const auto run = checks::integrate(b, *model, 5e-4, 0.3, [&](const State& s) {
    const double th = s.q[theta];
    const double y_ref = crank * std::cos(th) +
                         std::sqrt(rod * rod - offset * offset - std::pow(crank * std::sin(th), 2));
    err = std::max(err, std::abs(s.q[y] - y_ref));
    turns = th / (2 * kPi);
  });
  ASSERT_TRUE(run.ok) << run.message;
  EXPECT_GT(turns, 2.0);
  EXPECT_LT(err, 1e-10);
}

TEST(SpatialBuilder, TorsionSpringOnARevoluteAngleOscillatesAtItsFrequency) {
  // a body with tilted principal axes, pinned at its centre of mass about the axis n
  const Mat3 R = Eigen::AngleAxisd(0.6, Vec3(1, -2, 0.5).normalized()).toRotationMatrix();
  const Vec3 I(0.02, 0.03, 0.04), n = Vec3(0.3, 0.4, 1).normalized();
  const double I_axis = (R.transpose() * n).dot(I.cwiseProduct(R.transpose() * n));
  const double k = 5, th0 = 0.2;
  ModelBuilder b;
  b.spatial_body("wheel", body(1.5, I, Vec3(0.1, 0.2, 0.3), R));
  b.spatial_joint("axle", SpatialJointKind::kRevolute, "ground", "wheel",
                  {Vec3(0.1, 0.2, 0.3), n, {}});
  RotationalSpringOptions so;
  so.stiffness = k, so.free_angle = th0;  // released from θ = 0: θ(t) = θ0 (1 − cos ωt)
  b.joint_spring_damper("torsion", "axle", so);
  const int theta = b.spatial_joint_info("axle").theta_dof;
  const auto model = b.build();
  const double w = std::sqrt(k / I_axis);
  double err = 0;
  const auto run = checks::integrate(b, *model, 1e-3, 2.0, [&](const State& s) {
    err = std::max(err, std::abs(s.q[theta] - th0 * (1 - std::cos(w * s.t))));
  });
  ASSERT_TRUE(run.ok) << run.message;
  std::printf("torsion: ω = %.4f rad/s, max |θ − θ_ref| = %.2e rad of %.2f\n", w, err, th0);
  EXPECT_LT(err, 5e-3 * th0);
}

TEST(SpatialBuilder, MassOnASpatialSpringUnderAConstantForce) {
  const double m = 2, k = 800, F = 4;
  const Vec3 u = Vec3(1, 2, -2) / 3;  // the spring's direction
  ModelBuilder b;
  b.spatial_body("mass", body(m, Vec3(0.01, 0.01, 0.01), 0.5 * u));
  b.spatial_joint("guide", SpatialJointKind::kPrismatic, "ground", "mass", {0.5 * u, u, {}});
  SpringOptions so;
  so.stiffness = k;  // unloaded at t = 0 (free length 0.5)
  b.spatial_spring_damper("spring", "ground", Vec3::Zero(), "mass", 0.5 * u, so);
  const auto law = [](double v) { return std::make_shared<ConstantLaw>(v); };
  b.spatial_load("pull", SpatialLoad::Kind::kForce, "mass", 0.5 * u,
                 {law(F * u.x()), law(F * u.y()), law(F * u.z())}, SpatialLoad::Frame::kGround);
  const int r = b.spatial("mass").dof0;
  const auto model = b.build();
  const double w = std::sqrt(k / m), x_static = F / k;
  double err = 0;
  const auto run = checks::integrate(b, *model, 1e-4, 0.5, [&](const State& s) {
    const double x = u.dot(Vec3(s.q.segment<3>(r))) - 0.5;  // stretch
    err = std::max(err, std::abs(x - x_static * (1 - std::cos(w * s.t))));
  });
  ASSERT_TRUE(run.ok) << run.message;
  EXPECT_LT(err, 1e-3 * x_static);
}

TEST(SpatialBuilder, BadInputNamesTheEntityAndTheField) {
  const auto message = [](const std::function<void(ModelBuilder&)>& f) {
    ModelBuilder b;
    b.spatial_body("a", body(1, Vec3(1, 1, 1), Vec3::Zero()));
    try {
      f(b);
    } catch (const ModelError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  using K = SpatialJointKind;
  EXPECT_NE(message([](ModelBuilder& b) {
              b.spatial_body("b", body(1, Vec3(1, 1, 3), Vec3::Zero()));
            }).find("inertia: I3 exceeds"),
            std::string::npos);
  Mat3 skewed = Mat3::Identity();
  skewed(0, 1) = 0.1;
  EXPECT_NE(message([&](ModelBuilder& b) {
              b.spatial_body("b", body(1, Vec3(1, 1, 1), Vec3::Zero(), skewed));
            }).find("orientation"),
            std::string::npos);
  EXPECT_NE(message([](ModelBuilder& b) {
              b.spatial_joint("j", K::kRevolute, "a", "wheel", {Vec3::Zero(), Vec3::UnitZ(), {}});
            }).find("unknown spatial body 'wheel'"),
            std::string::npos);
  EXPECT_NE(message([](ModelBuilder& b) {
              b.spatial_joint("j", K::kUniversal, "a", "ground", {Vec3::Zero(), Vec3::UnitZ(), {}});
            }).find("axis_b"),
            std::string::npos);
  EXPECT_NE(message([](ModelBuilder& b) {
              b.spatial_joint("j", K::kSpherical, "a", "ground", {Vec3::Zero(), Vec3::UnitZ(), {}});
              b.joint_rotation_driver("d", "j", std::make_shared<ConstantLaw>(0.0));
            }).find("spherical joint has no rotation"),
            std::string::npos);
  EXPECT_NE(message([](ModelBuilder& b) {
              b.spatial_joint("j", K::kRevolute, "a", "ground", {Vec3::Zero(), Vec3::Zero(), {}});
            }).find("axis: expected a non-zero direction"),
            std::string::npos);
}
