// The angular_velocity and velocity measures: values against closed forms (a rigid body in a
// given state, and a rotor spinning at constant speed about a pin through a generalized-α run),
// and their partial derivatives ∂f/∂q, ∂f/∂q̇ (eq. 24) against central differences of the
// measure's own value.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

#include "support/test_models.hpp"

using namespace lsmbs;
using json = nlohmann::json;

namespace {

json spinning_case() {
  return R"({
    "name": "measures",
    "bodies": [
      {"name": "wheel", "type": "rigid", "position": [0.4, -0.1], "angle": 0.7, "mass": 2, "inertia": 0.05,
       "com": [0.1, 0.02], "angular_velocity": 3.0},
      {"name": "plate", "type": "flexible",
       "mesh": {"type": "rectangle", "origin": [0, 0], "size": [0.1, 0.02], "elements": [2, 1]},
       "placement": {"origin": [1, 0]}, "material": {"E": 1e7, "nu": 0.3, "rho": 1000}, "thickness": 0.005}
    ],
    "joints": [{"name": "axle", "type": "revolute", "a": {"body": "wheel", "at": [0, 0]}, "b": "ground"},
               {"name": "hold", "type": "clamp", "flexible": "plate", "node_set": "left"}],
    "simulation": {"t_end": 2.0, "h": 0.01, "tol_r": 1e-12},
    "output": {"measures": [
      {"name": "spin", "type": "angular_velocity", "body": "wheel"},
      {"name": "rim", "type": "velocity", "point": {"body": "wheel", "at": [0.2, 0.1]}},
      {"name": "hub", "type": "velocity", "point": {"body": "wheel"}},
      {"name": "corner", "type": "velocity", "point": {"body": "plate", "node": 5}},
      {"name": "still", "type": "velocity", "point": {"ground": [1, 2]}}
    ]}
  })"_json;
}

using test::measure;

}  // namespace

TEST(VelocityMeasures, ColumnsAndValuesMatchTheClosedForm) {
  const Case cs = test::make_case(spinning_case());
  const std::vector<std::string> cols = {"spin",     "rim.x",    "rim.y",   "hub.x",  "hub.y",
                                         "corner.x", "corner.y", "still.x", "still.y"};
  EXPECT_EQ(cs.measure_columns(), cols);
  const Model& m = *cs.model;
  const RigidBody& w = *m.find_rigid("wheel");
  State s = cs.initial;
  std::mt19937 g(3);
  std::uniform_real_distribution<double> u(-1, 1);
  s.q += Vec::NullaryExpr(m.nq(), [&] { return 0.1 * u(g); });
  s.v = Vec::NullaryExpr(m.nq(), [&] { return u(g); });
  const double th = s.q[w.dof0 + 2], om = s.v[w.dof0 + 2];
  const Vec2 d(0.2, 0.1);
  // ṗ = ẋ + ω ê_z × (R d) = (ẋ − ω (sin θ dx + cos θ dy), ẏ + ω (cos θ dx − sin θ dy))
  const Vec2 rim(s.v[w.dof0] - om * (std::sin(th) * d.x() + std::cos(th) * d.y()),
                 s.v[w.dof0 + 1] + om * (std::cos(th) * d.x() - std::sin(th) * d.y()));
  double out[2];
  measure(cs, "spin").evaluate(m, s, m.params(), out);
  EXPECT_EQ(out[0], om);
  measure(cs, "rim").evaluate(m, s, m.params(), out);
  EXPECT_NEAR(out[0], rim.x(), 1e-15);
  EXPECT_NEAR(out[1], rim.y(), 1e-15);
  measure(cs, "hub").evaluate(m, s, m.params(), out);
  EXPECT_EQ(out[0], s.v[w.dof0]);
  EXPECT_EQ(out[1], s.v[w.dof0 + 1]);
  const FlexibleBody& p = *m.find_flexible("plate");
  measure(cs, "corner").evaluate(m, s, m.params(), out);
  EXPECT_EQ(out[0], s.v[p.node_dof(5)]);
  EXPECT_EQ(out[1], s.v[p.node_dof(5) + 1]);
  measure(cs, "still").evaluate(m, s, m.params(), out);
  EXPECT_EQ(out[0], 0.0);
  EXPECT_EQ(out[1], 0.0);
}

TEST(VelocityMeasures, PartialDerivativesMatchCentralDifferences) {
  const Case cs = test::make_case(spinning_case());
  const Model& m = *cs.model;
  State s = cs.initial;
  std::mt19937 g(5);
  std::uniform_real_distribution<double> u(-1, 1);
  s.q += Vec::NullaryExpr(m.nq(), [&] { return 0.1 * u(g); });
  s.v = Vec::NullaryExpr(m.nq(), [&] { return 2 * u(g); });
  double worst = 0;
  for (const auto& ms : cs.measures) {
    const int nc = static_cast<int>(ms->components().size());
    for (int c = 0; c < nc; ++c) {
      MeasureGradient gr;
      ms->gradient(m, s, m.params(), c, gr);
      EXPECT_TRUE(gr.da.empty() && gr.dl.empty()) << ms->name();
      Vec dq = Vec::Zero(m.nq()), dv = Vec::Zero(m.nq());
      for (const auto& [i, v] : gr.dq) dq[i] += v;
      for (const auto& [i, v] : gr.dv) dv[i] += v;
      auto value = [&](const State& x) {
        std::vector<double> o(nc);
        ms->evaluate(m, x, m.params(), o.data());
        return o[c];
      };
      Vec fq(m.nq()), fv(m.nq());
      const double h = 1e-6;
      for (int i = 0; i < m.nq(); ++i) {
        State a = s, b = s;
        a.q[i] += h, b.q[i] -= h;
        fq[i] = (value(a) - value(b)) / (2 * h);
        a = s, b = s;
        a.v[i] += h, b.v[i] -= h;
        fv[i] = (value(a) - value(b)) / (2 * h);
      }
      const double e =
          std::max((dq - fq).lpNorm<Eigen::Infinity>(), (dv - fv).lpNorm<Eigen::Infinity>());
      EXPECT_LT(e, 1e-9) << ms->components()[c];
      worst = std::max(worst, e);
    }
  }
  std::printf(
      "velocity measures: ∂f/∂q, ∂f/∂q̇ vs central differences: worst absolute error %.2e (values "
      "O(1))\n",
      worst);
}

TEST(VelocityMeasures, SpinningWheelThroughAGeneralizedAlphaRun) {
  // No gravity, no torque: the wheel pinned at its reference point spins at ω0 = 3 rad/s, so
  // θ = 0.7 + ω0 t and the rim point at d = (0.2, 0.1) moves at ω0 R′(θ) d.
  Case cs = test::make_case(spinning_case());
  struct Watch : StepObserver {
    const Case* cs;
    double worst_spin = 0, worst_rim = 0;
    bool on_step(const StepInfo& i) override {
      const State& s = *i.state;
      double spin, rim[2];
      measure(*cs, "spin").evaluate(*cs->model, s, cs->model->params(), &spin);
      measure(*cs, "rim").evaluate(*cs->model, s, cs->model->params(), rim);
      const double th = 0.7 + 3.0 * s.t;
      const Vec2 ref = 3.0 * rotation_derivative(th) * Vec2(0.2, 0.1);
      worst_spin = std::max(worst_spin, std::abs(spin - 3.0));
      worst_rim = std::max(worst_rim, (Vec2(rim[0], rim[1]) - ref).norm());
      return true;
    }
  } w;
  w.cs = &cs;
  const auto r =
      GeneralizedAlpha(cs.simulation).run(*cs.model, cs.model->params(), cs.initial, {&w});
  ASSERT_TRUE(r.ok) << r.message;
  std::printf(
      "spinning wheel over 2 s: |ω − ω0| ≤ %.2e rad/s, |v_rim − closed form| ≤ %.2e m/s (|v_rim| = "
      "%.3f)\n",
      w.worst_spin, w.worst_rim, 3.0 * std::hypot(0.2, 0.1));
  EXPECT_LT(w.worst_spin, 1e-9);
  EXPECT_LT(w.worst_rim, 1e-9);
}
