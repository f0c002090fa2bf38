// Partial derivatives ∂f/∂q (eq. 24) of the strain_energy, distance and elongation measures
// against central differences of the measures' own values, at random deformed states of a
// model with a flexible plate (strain energy: ∂W/∂q = f_int) and with distance endpoints of
// every kind (plate node, rigid-body point off the reference point, ground); and the strain
// energy's value against the closed form of a uniformly stretched plate.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "support/test_models.hpp"

using namespace lsmbs;
using json = nlohmann::json;

namespace {

json plate_case() {
  return R"({
    "name": "measure_gradients",
    "bodies": [
      {"name": "arm", "type": "rigid", "position": [0.4, -0.1], "angle": 0.7, "mass": 2, "inertia": 0.05},
      {"name": "plate", "type": "flexible",
       "mesh": {"type": "rectangle", "origin": [0, 0], "size": [0.3, 0.06], "elements": [3, 2]},
       "placement": {"origin": [1, 0.2], "angle": 0.4}, "material": {"E": 2e9, "nu": 0.3, "rho": 1000},
       "thickness": 0.005}
    ],
    "joints": [{"name": "pin", "type": "revolute", "a": {"body": "arm", "at": [0, 0]}, "b": "ground"},
               {"name": "hold", "type": "clamp", "flexible": "plate", "node_set": "left"}],
    "simulation": {"t_end": 0.1, "h": 0.01},
    "output": {"measures": [
      {"name": "W", "type": "strain_energy"},
      {"name": "node_to_arm", "type": "distance", "a": {"body": "plate", "node": 11}, "b": {"body": "arm", "at": [0.2, 0.05]}},
      {"name": "arm_to_ground", "type": "elongation", "a": {"body": "arm", "at": [-0.1, 0.3]}, "b": {"ground": [2, 1]}},
      {"name": "across_plate", "type": "elongation", "a": {"body": "plate", "node": 0}, "b": {"body": "plate", "node": 11}}
    ]}
  })"_json;
}

using test::measure;

}  // namespace

TEST(MeasureGradients, StrainEnergyDistanceAndElongationMatchCentralDifferences) {
  const Case cs = test::make_case(plate_case());
  const Model& m = *cs.model;
  std::mt19937 g(11);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int trial = 0; trial < 3; ++trial) {
    State s = cs.initial;
    // displacements of 1 mm (strains ~1e-2 on the 0.1 m elements: the quartic terms of W count)
    s.q += Vec::NullaryExpr(m.nq(), [&] { return 1e-3 * u(g); });
    for (const char* name : {"W", "node_to_arm", "arm_to_ground", "across_plate"}) {
      const Measure& ms = measure(cs, name);
      MeasureGradient gr;
      ms.gradient(m, s, m.params(), 0, gr);
      EXPECT_TRUE(gr.dv.empty() && gr.da.empty() && gr.dl.empty()) << name;
      Vec dq = Vec::Zero(m.nq());
      for (const auto& [i, v] : gr.dq) dq[i] += v;
      auto value = [&](const State& x) {
        double o;
        ms.evaluate(m, x, m.params(), &o);
        return o;
      };
      // central differences with step 1e-7 m: truncation (h²/6) f''' ~ 1e-14 relative to the
      // gradient for these polynomials and smooth norms at lengths ≥ 0.05 m; round-off ε|f|/h
      // ~ 1e-9 of |f| per metre. Tolerance 1e-7 of the gradient's largest entry.
      Vec fd(m.nq());
      const double h = 1e-7;
      for (int i = 0; i < m.nq(); ++i) {
        State a = s, b = s;
        a.q[i] += h, b.q[i] -= h;
        fd[i] = (value(a) - value(b)) / (2 * h);
      }
      const double scale = fd.lpNorm<Eigen::Infinity>();
      ASSERT_GT(scale, 0) << name;
      const double e = (dq - fd).lpNorm<Eigen::Infinity>() / scale;
      std::printf("%-14s trial %d: |∂f/∂q − central difference|∞ / |∂f/∂q|∞ = %.2e\n", name, trial,
                  e);
      EXPECT_LT(e, 1e-7) << name << " trial " << trial;
    }
  }
}

TEST(MeasureGradients, StrainEnergyOfAUniformStretchIsTheClosedForm) {
  // Every node moved by x ↦ (1 + e) x along the plate axis, no lateral displacement (plane stress,
  // St Venant–Kirchhoff): Green strain E11 = e + e²/2, E22 = E12 = 0, so
  // W = ½ V · E0/(1 − ν²) · E11² with V = 0.3 × 0.06 × 0.005 m³.
  const Case cs = test::make_case(plate_case());
  const Model& m = *cs.model;
  const FlexibleBody& p = *m.find_flexible("plate");
  State s = cs.initial;
  const double e = 2e-3, th = 0.4;
  const Vec2 x0(1, 0.2), ax(std::cos(th), std::sin(th));
  for (int i = 0; i < p.mesh.num_nodes(); ++i) {
    const Vec2 x = s.q.segment<2>(p.node_dof(i));
    s.q.segment<2>(p.node_dof(i)) = x + e * ax * ax.dot(x - x0);
  }
  double W;
  measure(cs, "W").evaluate(m, s, m.params(), &W);
  const double E11 = e + e * e / 2, V = 0.3 * 0.06 * 0.005;
  const double ref = 0.5 * V * 2e9 / (1 - 0.3 * 0.3) * E11 * E11;
  std::printf("uniform stretch: W = %.15e J, closed form %.15e J\n", W, ref);
  EXPECT_NEAR(W, ref, 1e-12 * ref);  // a constant strain is integrated exactly by either rule
}

// Measures derived from points: a point's position and velocity in a rigid body's frame, its
// signed distance from the line through two points, and a linear combination of columns. Values
// against closed forms (the frame velocity against the directional derivative of the frame
// position along q̇, which is its definition), partials against central differences in q and q̇.
TEST(MeasureGradients, FrameLineAndCombinationMeasuresMatchClosedFormsAndCentralDifferences) {
  json j = plate_case();
  j["bodies"].push_back({{"name", "hub"},
                         {"type", "rigid"},
                         {"position", {0.2, 0.5}},
                         {"angle", -0.3},
                         {"mass", 1.0},
                         {"inertia", 0.01}});
  const json tip = {{"body", "plate"}, {"node", 11}},
             frame = {{"body", "arm"}, {"at", {0.1, 0.02}}},
             hub_pt = {{"body", "hub"}, {"at", {0.05, -0.04}}};
  auto& ms = j["output"]["measures"];
  ms.push_back({{"name", "arm_angle"}, {"type", "angle"}, {"body", "arm"}});
  ms.push_back({{"name", "frame_origin"}, {"type", "position"}, {"point", frame}});
  ms.push_back({{"name", "hub_point"}, {"type", "position"}, {"point", hub_pt}});
  ms.push_back({{"name", "n5"}, {"type", "position"}, {"point", {{"body", "plate"}, {"node", 5}}}});
  ms.push_back({{"name", "n0"}, {"type", "position"}, {"point", {{"body", "plate"}, {"node", 0}}}});
  ms.push_back(
      {{"name", "arm_b"}, {"type", "position"}, {"point", {{"body", "arm"}, {"at", {0.1, 0}}}}});
  ms.push_back(
      {{"name", "tip_in_arm"}, {"type", "frame_position"}, {"point", tip}, {"frame", frame}});
  ms.push_back(
      {{"name", "hub_in_arm"}, {"type", "frame_position"}, {"point", hub_pt}, {"frame", frame}});
  ms.push_back(
      {{"name", "tip_v_in_arm"}, {"type", "frame_velocity"}, {"point", tip}, {"frame", frame}});
  ms.push_back(
      {{"name", "hub_v_in_arm"}, {"type", "frame_velocity"}, {"point", hub_pt}, {"frame", frame}});
  ms.push_back({{"name", "sag"},
                {"type", "line_distance"},
                {"point", {{"body", "plate"}, {"node", 5}}},
                {"a", {{"body", "plate"}, {"node", 0}}},
                {"b", {{"body", "arm"}, {"at", {0.1, 0}}}}});
  ms.push_back(
      {{"name", "combo"},
       {"type", "combination"},
       {"constant", 0.5},
       {"terms",
        {{{"measure", "tip_in_arm.x"}, {"weight", 2.0}}, {{"measure", "sag"}, {"weight", -3.0}}}}});
  const Case cs = test::make_case(j);
  const Model& m = *cs.model;
  std::mt19937 g(5);
  std::uniform_real_distribution<double> u(-1, 1);
  auto value = [&](const Measure& me, const State& x, int c) {
    std::vector<double> o(me.components().size());
    me.evaluate(m, x, m.params(), o.data());
    return o[static_cast<size_t>(c)];
  };
  for (int trial = 0; trial < 3; ++trial) {
    State s = cs.initial;
    s.q += Vec::NullaryExpr(m.nq(), [&] { return 1e-2 * u(g); });
    s.v = Vec::NullaryExpr(m.nq(), [&] { return u(g); });
    for (int c = 0; c < 2; ++c) {
      // ṙ = ∂r/∂q q̇: the directional derivative of the frame position along q̇
      const double e = 1e-6;
      State a = s, b = s;
      a.q += e * s.v, b.q -= e * s.v;
      for (const char* pair : {"tip", "hub"}) {
        const Measure& pos = measure(cs, std::string(pair) + "_in_arm");
        const Measure& vel = measure(cs, std::string(pair) + "_v_in_arm");
        const double rd = (value(pos, a, c) - value(pos, b, c)) / (2 * e);
        EXPECT_NEAR(value(vel, s, c), rd, 1e-7 * std::max(1.0, std::abs(rd))) << pair << c;
      }
    }
    // the hub point in the arm's frame, R(θ)ᵀ (p − o), from the plain position and angle measures
    const double th = value(measure(cs, "arm_angle"), s, 0);
    const Vec2 o(value(measure(cs, "frame_origin"), s, 0),
                 value(measure(cs, "frame_origin"), s, 1));
    const Vec2 hub(value(measure(cs, "hub_point"), s, 0), value(measure(cs, "hub_point"), s, 1));
    const Vec2 r_hub = rotation(th).transpose() * (hub - o);
    EXPECT_NEAR(value(measure(cs, "hub_in_arm"), s, 0), r_hub.x(), 1e-14);
    EXPECT_NEAR(value(measure(cs, "hub_in_arm"), s, 1), r_hub.y(), 1e-14);
    // sag = ((b − a) × (p − a)) / |b − a|
    auto at = [&](const char* n) {
      return Vec2(value(measure(cs, n), s, 0), value(measure(cs, n), s, 1));
    };
    const Vec2 ua = at("arm_b") - at("n0"), wa = at("n5") - at("n0");
    EXPECT_NEAR(value(measure(cs, "sag"), s, 0), (ua.x() * wa.y() - ua.y() * wa.x()) / ua.norm(),
                1e-14);
    // combination = 0.5 + 2 tip_in_arm.x − 3 sag
    EXPECT_NEAR(
        value(measure(cs, "combo"), s, 0),
        0.5 + 2 * value(measure(cs, "tip_in_arm"), s, 0) - 3 * value(measure(cs, "sag"), s, 0),
        1e-14);
    // partials against central differences in q and q̇
    for (const char* name :
         {"tip_in_arm", "hub_in_arm", "tip_v_in_arm", "hub_v_in_arm", "sag", "combo"}) {
      const Measure& me = measure(cs, name);
      for (int c = 0; c < static_cast<int>(me.components().size()); ++c) {
        MeasureGradient gr;
        me.gradient(m, s, m.params(), c, gr);
        Vec dq = Vec::Zero(m.nq()), dv = Vec::Zero(m.nq());
        for (const auto& [i, v] : gr.dq) dq[i] += v;
        for (const auto& [i, v] : gr.dv) dv[i] += v;
        Vec fq(m.nq()), fv(m.nq());
        const double h = 1e-7;
        for (int i = 0; i < m.nq(); ++i) {
          State a = s, b = s;
          a.q[i] += h, b.q[i] -= h;
          fq[i] = (value(me, a, c) - value(me, b, c)) / (2 * h);
          a = s, b = s;
          a.v[i] += h, b.v[i] -= h;
          fv[i] = (value(me, a, c) - value(me, b, c)) / (2 * h);
        }
        const double scale = std::max(fq.lpNorm<Eigen::Infinity>(), fv.lpNorm<Eigen::Infinity>());
        ASSERT_GT(scale, 0) << name;
        EXPECT_LT((dq - fq).lpNorm<Eigen::Infinity>() / scale, 1e-7) << name << "." << c << " q";
        EXPECT_LT((dv - fv).lpNorm<Eigen::Infinity>() / scale, 1e-7) << name << "." << c << " v";
      }
    }
  }
}
