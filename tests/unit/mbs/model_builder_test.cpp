// ModelBuilder: models built in code, checked against closed forms rather than against the JSON
// loader: the mass matrix of a rigid body with an offset centre of mass, the default ground point
// of a revolute joint, a spring's default free length, the body-frame offsets of a rigid
// connection, the kinetic energy of given initial velocity fields; errors that name the entity and
// the argument; and a model built in code against the same model read from JSON (identical
// residuals: the builder is the loader's only way to make a model).
#include "lsmbs/mbs/model_builder.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "lsmbs/integrators/generalized_alpha.hpp"
#include "support/test_models.hpp"

using namespace lsmbs;

namespace {

/// ẑ × r: the velocity of a point at r from the axis of a unit angular velocity.
Vec2 perp(const Vec2& r) { return {-r.y(), r.x()}; }

// A rigid pendulum: mass m, inertia J about the centre of mass at body-frame offset c, reference
// point at x0 with angle th0, pinned at its body-frame point (−l, 0) to the ground point where
// that point is at t = 0 (the revolute joint's default).
struct Pendulum {
  double m = 2.0, J = 0.05, l = 0.8, th0 = 0.3;
  Vec2 x0{0.5, -0.2}, c{0.1, 0.02};
  Vec2 pin0() const { return x0 + rotation(th0) * Vec2(-l, 0); }  // p_a(0) = x0 + R(θ0)(−l, 0)
  void add(ModelBuilder& b) const {
    b.rigid_body("bob", {.mass = m, .inertia = J, .position = x0, .angle = th0, .com = c});
    b.revolute("pin", Point::at("bob", {-l, 0}));
  }
};

template <class F>
ModelError error_of(F&& call) {
  try {
    call();
  } catch (const ModelError& e) {
    return e;
  }
  ADD_FAILURE() << "no ModelError";
  return ModelError("", "", "");
}

}  // namespace

TEST(ModelBuilder, RigidBodyIsThreeUnknownsAndItsInertiaAboutTheReferencePoint) {
  const Pendulum p;
  ModelBuilder b;
  p.add(b);
  const auto model = b.build();
  ASSERT_EQ(model->nq(), 3);
  ASSERT_EQ(model->nc(), 2);
  EXPECT_EQ(model->parameter_names(), (std::vector<std::string>{"bob.mass", "bob.inertia"}));
  EXPECT_EQ(model->params().scalars, (std::vector<double>{p.m, p.J}));
  EXPECT_EQ(b.angle_dof("bob"), 2);
  const State& s = b.initial_state();
  EXPECT_EQ(s.q, Eigen::Vector3d(p.x0.x(), p.x0.y(), p.th0));
  EXPECT_EQ(s.v, Eigen::Vector3d::Zero());
  // M about the reference point: [m I, m R′(θ)c; m (R′(θ)c)ᵀ, J_c + m |c|²] with R′(θ)c = ẑ × R(θ)c
  const Mat M = test::dense_mass_matrix(*model, s);
  const Vec2 Rpc = perp(rotation(p.th0) * p.c);
  Mat expected(3, 3);
  expected << p.m, 0, p.m * Rpc.x(), 0, p.m, p.m * Rpc.y(), p.m * Rpc.x(), p.m * Rpc.y(),
      p.J + p.m * p.c.squaredNorm();
  EXPECT_LT((M - expected).lpNorm<Eigen::Infinity>(), 1e-14) << M;
}

TEST(ModelBuilder, RevoluteJointDefaultsToTheGroundPointWhereAIsInitially) {
  const Pendulum p;
  ModelBuilder b;
  p.add(b);
  EXPECT_LT((b.initial_position(Point::at("bob", {-p.l, 0})) - p.pin0()).norm(), 1e-15);
  const auto model = b.build();
  EXPECT_EQ(b.joint_rows("pin"), (std::vector<int>{0, 1}));
  // Φ = p_a − p_b with p_b fixed at p_a(0): zero at t = 0, the translation itself after a
  // translation, and x0 + R(θ0 + Δ)(−l, 0) − p_a(0) after a rotation Δ about the reference point
  Vec phi;
  model->constraints(0, b.initial_state().q, model->params(), phi);
  EXPECT_LT(phi.norm(), 1e-15);
  Vec q = b.initial_state().q;
  q[0] += 0.01, q[1] -= 0.02;
  model->constraints(0, q, model->params(), phi);
  EXPECT_NEAR(phi[0], 0.01, 1e-15);
  EXPECT_NEAR(phi[1], -0.02, 1e-15);
  q = b.initial_state().q;
  q[2] += 0.1;
  model->constraints(0, q, model->params(), phi);
  const Vec2 moved = p.x0 + rotation(p.th0 + 0.1) * Vec2(-p.l, 0) - p.pin0();
  EXPECT_NEAR(phi[0], moved.x(), 1e-15);
  EXPECT_NEAR(phi[1], moved.y(), 1e-15);
}

TEST(ModelBuilder, SpringFreeLengthDefaultsToTheInitialDistance) {
  const Pendulum p;
  ModelBuilder b;
  p.add(b);
  const Vec2 ground(2, 1), offset(0.2, 0.1);
  b.spring_damper("relaxed", Point::at("bob", offset), Point::ground(ground),
                  {.stiffness = 1e3, .damping = 5});
  b.spring_damper("preloaded", Point::at("bob", offset), Point::ground(ground),
                  {.stiffness = 1e3, .free_length = 0.5});
  const auto model = b.build();
  const Vec2 a0 = p.x0 + rotation(p.th0) * offset;
  const double L = (ground - a0).norm();
  const auto& par = model->params().scalars;
  EXPECT_NEAR(par[b.parameter("relaxed.free_length")], L, 1e-15 * L);
  EXPECT_EQ(par[b.parameter("relaxed.damping")], 5);
  EXPECT_EQ(par[b.parameter("preloaded.damping")], 0);
  ASSERT_EQ(b.force_owner(1), "relaxed");
  ASSERT_EQ(b.force_owner(2), "preloaded");
  // at t = 0 at rest: no force from the relaxed spring; the preloaded one pulls with k (L − 0.5)
  // along the line of its end points (residual r_A = −F_A = T (a − b) / L on the body's x, y)
  LocalVec r;
  model->element_residual(1, b.initial_state(), model->params(), r);
  EXPECT_LT(r.norm(), 1e-12);
  model->element_residual(2, b.initial_state(), model->params(), r);
  const Vec2 expected = 1e3 * (L - 0.5) * (a0 - ground) / L;
  EXPECT_NEAR(r[0], expected.x(), 1e-10);
  EXPECT_NEAR(r[1], expected.y(), 1e-10);
}

TEST(ModelBuilder, RigidConnectionIsOneCoincidencePerNodeWithTheNodesOffsetInTheRigidFrame) {
  ModelBuilder b;
  const Vec2 hub0(0.1, 0.2), origin(0.15, 0.25);
  const double th0 = 0.4, alpha = 0.7;
  b.rigid_body("hub", {.mass = 1, .inertia = 0.01, .position = hub0, .angle = th0});
  const Mesh2D mesh = Mesh2D::rectangle(0, -0.01, 0.1, 0.02, 4, 2);
  const std::vector<int> left = mesh.node_sets.at("left");
  ASSERT_EQ(left.size(), 3u);
  b.flexible_body(
      "plate", mesh,
      {.E = 1e7, .nu = 0.3, .rho = 1000, .thickness = 0.005, .origin = origin, .angle = alpha});
  b.rigid_connection("weld", "hub", "plate", "left");
  b.clamp("wall", "plate", "right");
  EXPECT_EQ(b.joint_equations("weld"), 6);
  const auto model = b.build();
  ASSERT_EQ(model->constraints().size(), 6u);  // 3 nodes of "left", 3 of "right"
  for (const auto& c : model->constraints()) EXPECT_EQ(c->size(), 2);
  EXPECT_EQ(b.joint_rows("weld"), (std::vector<int>{0, 1, 2, 3, 4, 5}));
  EXPECT_EQ(b.joint_rows("wall"), (std::vector<int>{6, 7, 8, 9, 10, 11}));
  // The hub rotated by Δ about its reference point, the nodes where they were: equation k is
  // x_k − (x_hub + R(θ0 + Δ) d_k) with the node's initial offset d_k = R(θ0)ᵀ (x_k − x_hub).
  Vec q = b.initial_state().q;
  q[2] += 0.2;
  Vec phi;
  model->constraints(0, q, model->params(), phi);
  for (size_t k = 0; k < left.size(); ++k) {
    const Vec2 xk = origin + rotation(alpha) * mesh.nodes[left[k]];
    const Vec2 dk = rotation(th0).transpose() * (xk - hub0);
    const Vec2 expected = xk - (hub0 + rotation(th0 + 0.2) * dk);
    EXPECT_NEAR(phi[2 * k], expected.x(), 1e-15);
    EXPECT_NEAR(phi[2 * k + 1], expected.y(), 1e-15);
  }
  EXPECT_LT(phi.tail(6).norm(), 1e-15);  // the clamp: nodes at their initial positions
}

TEST(ModelBuilder, InitialVelocitiesGiveTheKineticEnergyOfTheirFields) {
  // a rigid body: ½ J_c ω² + ½ m |v_G|², v_G = v + ω ẑ × R(θ0) c (velocity of the centre of mass)
  const double m = 1.5, J = 0.02, th0 = -0.6, w = 3.0;
  const Vec2 c(0.05, -0.03), v(0.4, -0.7);
  ModelBuilder rigid;
  rigid.rigid_body(
      "body",
      {.mass = m, .inertia = J, .angle = th0, .com = c, .velocity = v, .angular_velocity = w});
  const auto mr = rigid.build();
  const Vec2 vG = v + w * perp(rotation(th0) * c);
  const double e_rigid = 0.5 * J * w * w + 0.5 * m * vG.squaredNorm();
  EXPECT_NEAR(mr->kinetic_energy(rigid.initial_state(), mr->params()), e_rigid, 1e-14 * e_rigid);

  // a flexible rectangle [x0, x1] × [y0, y1] (mesh frame) placed at origin O with angle α and the
  // rigid field v + ω ẑ × (x − O): the consistent mass integrates this bilinear field exactly,
  // ½ ρ t [A |v|² + 2 ω v · (ẑ × R(α) ∫X dA) + ω² ∫|X|² dA]
  const double x0 = -0.1, y0 = 0.02, a = 0.3, h = 0.05, rho = 2700, t = 0.004, alpha = 0.9;
  const Vec2 O(0.2, -0.1);
  ModelBuilder flex;
  flex.flexible_body("plate", Mesh2D::rectangle(x0, y0, a, h, 6, 2),
                     {.E = 7e10,
                      .nu = 0.3,
                      .rho = rho,
                      .thickness = t,
                      .origin = O,
                      .angle = alpha,
                      .velocity = v,
                      .angular_velocity = w});
  const auto mf = flex.build();
  const double x1 = x0 + a, y1 = y0 + h, A = a * h;
  const Vec2 int_X = A * Vec2(x0 + a / 2, y0 + h / 2);
  const double int_X2 =
      h * (x1 * x1 * x1 - x0 * x0 * x0) / 3 + a * (y1 * y1 * y1 - y0 * y0 * y0) / 3;
  const double e_flex =
      0.5 * rho * t *
      (A * v.squaredNorm() + 2 * w * v.dot(perp(rotation(alpha) * int_X)) + w * w * int_X2);
  EXPECT_NEAR(mf->kinetic_energy(flex.initial_state(), mf->params()), e_flex, 1e-12 * e_flex);

  // which velocities were given: the integrators' initial projection keeps exactly those
  EXPECT_EQ(rigid.held_velocities(), (std::vector<char>{1, 1, 1}));
  EXPECT_EQ(flex.held_velocities(), std::vector<char>(mf->nq(), 1));
  ModelBuilder spin;
  spin.rigid_body("crank", {.mass = 1, .inertia = 0.1, .angular_velocity = 2.0});
  spin.rigid_body("rod", {.mass = 1, .inertia = 0.1});
  const auto ms = spin.build();
  EXPECT_EQ(spin.held_velocities(), (std::vector<char>{0, 0, 1, 0, 0, 0}));
  ASSERT_EQ(spin.given_velocities().size(), 1u);
  EXPECT_EQ(spin.given_velocities()[0].body, "crank");
  EXPECT_EQ(spin.given_velocities()[0].field, "angular_velocity");
  EXPECT_EQ(spin.initial_state().v, (Vec(6) << 0, 0, 2, 0, 0, 0).finished());
}

TEST(ModelBuilder, PointsByName) {
  ModelBuilder b;
  b.rigid_body("arm", {.mass = 1, .inertia = 0.1, .position = {1, 2}, .angle = 0.5});
  b.flexible_body(
      "plate", Mesh2D::rectangle(0, 0, 1, 0.5, 2, 1),
      {.E = 1e9, .nu = 0.3, .rho = 1000, .thickness = 0.01, .origin = {3, 0}, .angle = 0.2});
  EXPECT_EQ(b.body_kind("arm"), ModelBuilder::BodyKind::kRigid);
  EXPECT_EQ(b.body_kind("plate"), ModelBuilder::BodyKind::kFlexible);
  EXPECT_EQ(b.body_kind("ground"), ModelBuilder::BodyKind::kNone);
  // a rigid-body point given by its position at t = 0 has that position
  const Vec2 x(1.3, 2.4);
  EXPECT_LT((b.initial_position(Point::at_global("arm", x)) - x).norm(), 1e-15);
  const PointRef r = b.resolve(Point::at("arm", {0.1, 0}));
  EXPECT_EQ(r.kind, PointRef::Kind::kBody);
  EXPECT_EQ(r.dof0, 0);
  // nodes: dof 3 + 2 i; the nearest node to a mesh-frame point; the placed node position
  const PointRef n = b.resolve(Point::nearest("plate", {0.9, 0.45}));
  EXPECT_EQ(n.kind, PointRef::Kind::kNode);
  EXPECT_EQ(n.dof0, 3 + 2 * 5);  // nodes row by row: (0,0) (0.5,0) (1,0) (0,0.5) (0.5,0.5) (1,0.5)
  EXPECT_LT(
      (b.initial_position(Point::node("plate", 5)) - (Vec2(3, 0) + rotation(0.2) * Vec2(1, 0.5)))
          .norm(),
      1e-15);
}

TEST(ModelBuilder, ErrorsNameTheEntityAndTheArgument) {
  const Pendulum p;
  ModelBuilder b;
  p.add(b);
  b.flexible_body("plate", Mesh2D::rectangle(0, 0, 1, 0.1, 2, 1),
                  {.E = 1e9, .nu = 0.3, .rho = 1000, .thickness = 0.01});

  ModelError e = error_of([&] { b.revolute("pivot", Point::at("crnk")); });
  EXPECT_EQ(e.entity(), "joint 'pivot'");
  EXPECT_EQ(e.field(), "a/body");
  EXPECT_EQ(e.message(), "unknown body 'crnk'");
  EXPECT_STREQ(e.what(), "joint 'pivot', a/body: unknown body 'crnk'");

  e = error_of([&] { b.rigid_body("pin", {.mass = 1}); });
  EXPECT_STREQ(
      e.what(),
      "rigid body 'pin', name: duplicate name 'pin' (bodies, joints and forces need unique names)");
  e = error_of([&] { b.rigid_body("ground", {.mass = 1}); });
  EXPECT_STREQ(e.what(), "rigid body 'ground', name: 'ground' is reserved");
  const Point pin = Point::at("bob", {-p.l, 0});
  e = error_of([&] {
    b.spring_damper("s1", pin, Point::ground(b.initial_position(pin)), {.stiffness = 1});
  });
  EXPECT_STREQ(e.what(),
               "spring 's1': the spring's end points coincide initially (direction undefined)");
  e = error_of([&] { b.torque("motor", "plate", 1.0); });
  EXPECT_STREQ(e.what(),
               "torque 'motor', body: 'plate' is a flexible body; a rigid body is expected here");
  e = error_of([&] { b.clamp("wall", "plate", "middle"); });
  EXPECT_STREQ(e.what(),
               "joint 'wall', node_set: body 'plate' has no node set 'middle' (available: bottom, "
               "left, right, top)");
  e = error_of([&] { b.revolute("hinge", Point::node("plate", 99), Point::at("bob")); });
  EXPECT_STREQ(e.what(),
               "joint 'hinge', a/node: node index 99 out of range (body 'plate' has 6 nodes)");
  e = error_of(
      [&] { b.rotation_driver("motor", "bob", std::make_shared<ConstantLaw>(0.0), "bob"); });
  EXPECT_STREQ(e.what(), "joint 'motor', relative_to: a body cannot be driven relative to itself");
  e = error_of([&] { b.joint_equations("nope"); });
  EXPECT_STREQ(e.what(), "unknown joint 'nope'");

  // the refused calls changed nothing: the names are free, no parameter or element was added
  const int nq = b.model().nq();
  const size_t np = b.model().parameter_names().size(), nf = b.model().forces().size();
  b.spring_damper("s1", Point::at("bob"), Point::ground({3, 0}), {.stiffness = 1});
  b.revolute("pivot", Point::node("plate", 0));
  EXPECT_EQ(b.model().nq(), nq);
  EXPECT_EQ(b.model().parameter_names().size(), np + 3);
  EXPECT_EQ(b.model().forces().size(), nf + 1);

  ModelBuilder lone;  // a body without mass, inertia or joint: its motion is not determined
  lone.rigid_body("free", {});
  e = error_of([&] { lone.build(); });
  EXPECT_STREQ(e.what(),
               "rigid body 'free': rigid body 'free' has no mass and no joint: its motion is not "
               "determined");
}

// The same model built in code and read from a JSON case: every element type the builder makes,
// identical parameters, unknowns, constraint rows and residuals at one state.
TEST(ModelBuilder, CodeAndJsonGiveTheSameModel) {
  const auto j = R"({
    "name": "every_entity", "gravity": [0.2, -9.81],
    "bodies": [
      {"name": "crank", "type": "rigid", "position": [0, 0], "angle": 0.3, "mass": 1.2, "inertia": 0.01,
       "com": [0.02, 0.01], "angular_velocity": 5},
      {"name": "link", "type": "rigid", "position": [0.1, 0.05], "angle": -0.2, "mass": 0.8, "inertia": 0.004},
      {"name": "slider", "type": "rigid", "position": [0.3, 0], "mass": 0.5, "inertia": 0.001},
      {"name": "plate", "type": "flexible",
       "mesh": {"type": "rectangle", "origin": [0, -0.01], "size": [0.1, 0.02], "elements": [4, 2]},
       "placement": {"origin": [0.3, 0.1], "angle": 0.4}, "material": {"E": 1e7, "nu": 0.3, "rho": 1000},
       "thickness": 0.005, "node_sets": {"tip": {"line_x": 0.1}}, "velocity": [0.1, 0]},
      {"name": "rod", "type": "rigid", "position": [0.3, 0.1], "angle": 0.4, "mass": 0.1, "inertia": 0.001}
    ],
    "joints": [
      {"name": "bearing", "type": "revolute", "a": {"body": "crank", "at": [0, 0]}, "b": "ground"},
      {"name": "crank_pin", "type": "revolute", "a": {"body": "crank", "at": [0.1, 0]},
       "b": {"body": "link", "at_global": [0.1, 0.03]}},
      {"name": "slide", "type": "prismatic", "a": {"body": "slider", "at": [0.02, 0.01]}, "direction": [1, 0.2]},
      {"name": "drive", "type": "rotation_driver", "body": "link", "relative_to": "crank",
       "law": {"type": "ramp", "from": 0.3, "speed": 4, "ramp_time": 0.2}},
      {"name": "push", "type": "translation_driver", "point": {"body": "slider"}, "direction": [0, 1],
       "law": {"type": "constant", "value": 0.01}},
      {"name": "weld", "type": "rigid_connection", "rigid": "rod", "flexible": "plate", "node_set": "left"},
      {"name": "tip_fix", "type": "clamp", "flexible": "plate", "node_set": "tip"}
    ],
    "forces": [
      {"name": "m_node", "type": "point_mass", "mass": 0.2, "point": {"body": "plate", "nearest": [0.05, 0]}},
      {"name": "m_body", "type": "point_mass", "mass": 0.3, "point": {"body": "link", "at": [0.03, 0.01]}},
      {"name": "f", "type": "point_force", "point": {"body": "plate", "node": 3}, "force": [3, -2], "scale": 2},
      {"name": "spring", "type": "spring_damper", "a": {"body": "crank", "at": [0.02, 0]}, "b": {"ground": [0.5, 0.5]},
       "stiffness": 1e3, "damping": 5},
      {"name": "motor", "type": "torque", "body": "crank", "torque": 0.5},
      {"name": "coil", "type": "rotational_spring_damper", "a": "link", "b": "ground", "stiffness": 20, "damping": 0.1},
      {"name": "gas", "type": "pressure", "point": {"body": "slider"}, "direction": [-1, 0], "area": 1e-3,
       "table": {"points": [[0, 1e5], [3, 2e5]], "period": 6.283185307179586, "interpolation": "linear"},
       "argument": {"angle_of": "crank", "offset": 0.1}}
    ],
    "simulation": {"t_end": 0.01, "h": 0.001, "check_constraints": false, "project_initial": false}
  })"_json;
  const Case cs = test::make_case(j);

  ModelBuilder b;
  b.set_gravity({0.2, -9.81});
  b.rigid_body(
      "crank",
      {.mass = 1.2, .inertia = 0.01, .angle = 0.3, .com = {0.02, 0.01}, .angular_velocity = 5.0});
  b.rigid_body("link", {.mass = 0.8, .inertia = 0.004, .position = {0.1, 0.05}, .angle = -0.2});
  b.rigid_body("slider", {.mass = 0.5, .inertia = 0.001, .position = {0.3, 0}});
  Mesh2D mesh = Mesh2D::rectangle(0, -0.01, 0.1, 0.02, 4, 2);
  mesh.node_sets["tip"] = mesh.nodes_on_line_x(0.1);
  b.flexible_body("plate", mesh,
                  {.E = 1e7,
                   .nu = 0.3,
                   .rho = 1000,
                   .thickness = 0.005,
                   .origin = {0.3, 0.1},
                   .angle = 0.4,
                   .velocity = Vec2(0.1, 0)});
  b.rigid_body("rod", {.mass = 0.1, .inertia = 0.001, .position = {0.3, 0.1}, .angle = 0.4});
  b.revolute("bearing", Point::at("crank"));
  b.revolute("crank_pin", Point::at("crank", {0.1, 0}), Point::at_global("link", {0.1, 0.03}));
  b.prismatic("slide", Point::at("slider", {0.02, 0.01}), {1, 0.2});
  b.rotation_driver("drive", "link", std::make_shared<RampLaw>(0.3, 4, 0.2, 0), "crank");
  b.translation_driver("push", Point::at("slider"), {0, 1}, std::make_shared<ConstantLaw>(0.01));
  b.rigid_connection("weld", "rod", "plate", "left");
  b.clamp("tip_fix", "plate", "tip");
  b.point_mass("m_node", Point::nearest("plate", {0.05, 0}), 0.2);
  b.point_mass("m_body", Point::at("link", {0.03, 0.01}), 0.3);
  b.point_force("f", Point::node("plate", 3), Vec2(3, -2), 2);
  b.spring_damper("spring", Point::at("crank", {0.02, 0}), Point::ground({0.5, 0.5}),
                  {.stiffness = 1e3, .damping = 5});
  b.torque("motor", "crank", 0.5);
  b.rotational_spring_damper("coil", "link", "ground", {.stiffness = 20, .damping = 0.1});
  const double period = 6.283185307179586;
  b.pressure("gas", Point::at("slider"), {-1, 0}, 1e-3,
             Table1D({0, 3}, {1e5, 2e5}, Table1D::Interp::kLinear, period),
             {.angle_of = "crank", .offset = 0.1});
  const auto model = b.build();

  const Model& from_json = *cs.model;
  ASSERT_EQ(model->nq(), from_json.nq());
  ASSERT_EQ(model->nc(), from_json.nc());
  EXPECT_EQ(model->parameter_names(), from_json.parameter_names());
  EXPECT_EQ(model->params().scalars, from_json.params().scalars);
  EXPECT_EQ(b.joint_rows(), cs.joint_rows);
  EXPECT_EQ(b.initial_state().q, cs.initial.q);
  EXPECT_EQ(b.initial_state().v,
            cs.initial.v);  // project_initial false: the given velocities as they are
  // the residual (eq. 7) at the initial state with some accelerations and multipliers
  State s = b.initial_state();
  s.t = 0.05;
  s.a = Vec::LinSpaced(model->nq(), -1, 1);
  s.lambda = Vec::LinSpaced(model->nc(), 0.5, 2);
  Vec r_code, r_json;
  model->residual(s, model->params(), 1.7, 0.3, r_code);
  from_json.residual(s, from_json.params(), 1.7, 0.3, r_json);
  EXPECT_EQ(r_code, r_json);
  std::vector<double> s_code, s_json;
  const Coefficients co{3.0, 0.5, 1.0};
  model->iteration_matrix(s, model->params(), co, 1.7, 0.3, s_code);
  from_json.iteration_matrix(s, from_json.params(), co, 1.7, 0.3, s_json);
  EXPECT_EQ(s_code, s_json);
}

// The example of docs/library.md (steps 1–7), run: the pendulum with a spring conserves its total
// energy ½ q̇ᵀMq̇ + m g y + ½ k (l − l0)², zero at t = 0 (at rest at y = 0, the spring unloaded),
// up to the generalized-α dissipation, O((ωh)³) per period at ωh ≈ 0.01.
TEST(ModelBuilder, DocumentationExample) {
  ModelBuilder b;
  b.set_gravity({0, -9.81});
  b.rigid_body("bob", {.mass = 1.0, .inertia = 0.01, .position = {1.0, 0.0}});
  b.revolute("pin", Point::at("bob", {-1.0, 0.0}));
  b.spring_damper("spring", Point::at("bob"), Point::ground({1.0, 1.0}), {.stiffness = 50.0});
  std::unique_ptr<Model> model = b.build();
  model->params().scalars[b.parameter("spring.stiffness")] = 80.0;
  GeneralizedAlphaOptions o;
  o.h = 1e-3;
  o.t_end = 1.0;
  State end;
  const IntegratorSummary run =
      GeneralizedAlpha(o).run(*model, model->params(), b.initial_state(), {}, &end);
  ASSERT_TRUE(run.ok) << run.message;
  EXPECT_EQ(run.steps, 1000);
  const PointRef bob = b.resolve(Point::at("bob"));
  const Vec2 x(end.q[bob.dof0], end.q[bob.dof0 + 1]);
  EXPECT_NEAR(x.norm(), 1.0, 1e-10);  // on the circle of the pin
  EXPECT_LT(x.y(), -0.1);             // it has swung down
  const double spring = 0.5 * 80.0 * std::pow((Vec2(1, 1) - x).norm() - 1.0, 2);
  const double energy = model->kinetic_energy(end, model->params()) + 9.81 * x.y() + spring;
  EXPECT_LT(std::abs(energy), 1e-3) << energy;
}
