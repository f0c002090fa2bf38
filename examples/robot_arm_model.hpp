// The robot arm of Tromme et al. (section 6) built in code, the model of
// data/robot_arm/robot_arm_holes.json; used by the examples robot_arm_gradients.cpp and
// design_loop.cpp. Arm 1 is rigid and massless; arm 2 is a rigid massless rod (0-0.2 m), a
// flexible aluminium plate (0.2-0.8 m, 0.6 × 0.05 m, 2.5 mm) and a rigid massless rod (0.8-1 m)
// carrying a 5 kg end effector. Both joint angles follow the same trapezoidal law from 60° to
// 90°. The plate carries five super-ellipse holes (eq. 43, ξ = η = 5) on its axis, each with its
// centre c_x and half-axes a, b as design variables (15 variables, starting from Table 5's
// initial design). The responses are the plate's mass and the average and maximum deviation of
// the end effector from its rigid-body path during the constant-speed phase (eq. 44).
#pragma once
#include <cmath>
#include <memory>
#include <string>

#include "lsmbs/mbs/model_builder.hpp"
#include "lsmbs/sensitivity/study.hpp"

namespace example {

using namespace lsmbs;

/// nx × ny elements on the plate (the paper's mesh is 120 × 10).
inline Study robot_arm(int nx, int ny) {
  const double pi = std::acos(-1.0), th0 = pi / 3, th1 = pi / 2;

  // 1. Bodies at t = 0: arm 1 at 60° from the ground, arm 2 at 60° relative to arm 1.
  ModelBuilder b;
  const Vec2 elbow(std::cos(th0), std::sin(th0));
  const double a2 = 2 * th0;  // absolute angle of arm 2
  const Vec2 u2(std::cos(a2), std::sin(a2));
  b.rigid_body("arm1", {.angle = th0});
  b.rigid_body("rod_root", {.position = elbow, .angle = a2});
  b.flexible_body(
      "plate", Mesh2D::rectangle(0.2, -0.025, 0.6, 0.05, nx, ny),
      {.E = 72e9, .nu = 0.3, .rho = 2700, .thickness = 0.0025, .origin = elbow, .angle = a2});
  b.rigid_body("rod_tip", {.position = elbow + 0.8 * u2, .angle = a2});

  // 2. Joints: the base and elbow hinges, the two driven angles, and the plate's ends glued to the
  //    rods (every node of the rectangle's left and right sides).
  b.revolute("base", Point::at("arm1"), Point::ground({0, 0}));
  b.revolute("elbow", Point::at("arm1", {1, 0}), Point::at("rod_root"));
  auto law = std::make_shared<TrapezoidLaw>(th0, th1, 1.0, 0.25);
  b.rotation_driver("theta1", "arm1", law);
  b.rotation_driver("theta2", "rod_root", law, "arm1");
  b.rigid_connection("root_connection", "rod_root", "plate", "left");
  b.rigid_connection("tip_connection", "rod_tip", "plate", "right");
  b.point_mass("effector", Point::at("rod_tip", {0.2, 0}), 5.0);

  // 3. The study: 2.5 s with h = 5 ms (the paper's).
  GeneralizedAlphaOptions ga;
  ga.t_end = 2.5;
  ga.h = 0.005;
  ga.rho_inf = 0.8;
  std::unique_ptr<Model> model = b.build();  // then the initial state is known
  Study s(std::move(model), b.initial_state(), ga);

  // 4. Measures and responses; the deviation is measured from the rigid two-link chain that the
  //    drivers prescribe, and averaged over the constant-speed phase of arm 1's law.
  const PointRef tip = b.resolve(Point::at("rod_tip", {0.2, 0}));
  ChainPath path;
  path.links = {{b.driver("theta1")->law, false, 1.0}, {b.driver("theta2")->law, true, 1.0}};
  s.add_measure(std::make_unique<PathDeviationMeasure>("tip_deviation", tip, path));
  s.add_measure(std::make_unique<FlexibleMassMeasure>("plate_mass", &b.flexible("plate")));
  double t0 = 0, t1 = 0;
  for (const auto& ph : law->phases())
    if (ph.name == "constant") t0 = ph.t0, t1 = ph.t1;
  s.add_response("plate_mass", "plate_mass", ResponseSpec::Kind::kFinal);
  s.add_response("average_tip_deviation", "tip_deviation", ResponseSpec::Kind::kAverage, t0, t1);
  s.add_response("max_tip_deviation", "tip_deviation", ResponseSpec::Kind::kMax, t0, t1);

  // 5. The design: five holes LS1..LS5 with c_x in [0.25, 0.75] m and a, b in [0.1, 40] mm,
  //    starting as Table 5's initial design (small holes spread along the plate).
  auto d = std::make_unique<Design>();
  std::vector<Feature> holes;
  for (int k = 1; k <= 5; ++k) {
    const std::string i = std::to_string(k);
    d->add_variable("cx" + i, 0.14 + 0.12 * k, 0.25, 0.75);
    d->add_variable("a" + i, 0.01, 1e-4, 0.04);
    d->add_variable("b" + i, 0.01, 1e-4, 0.04);
    holes.emplace_back(
        "LS" + i, Feature::Type::kSuperEllipse,
        std::vector<ParamBinding>{d->variable("cx" + i), Design::constant(0), d->variable("a" + i),
                                  d->variable("b" + i), Design::constant(5), Design::constant(5),
                                  Design::constant(0)},
        /*hole=*/true);
  }
  d->add_geometry(b.flexible("plate"), std::move(holes));
  s.set_design(std::move(d));
  return s;
}

}  // namespace example
