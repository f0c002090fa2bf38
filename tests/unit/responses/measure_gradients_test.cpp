// Partial derivatives ∂f/∂q (eq. 24) of the strain_energy, distance and elongation measures
// against central differences of the measures' own values, at random deformed states of a
// model with a flexible plate (strain energy: ∂W/∂q = f_int) and with distance endpoints of
// every kind (plate node, rigid-body point off the reference point, ground); and the strain
// energy's value against the closed form of a uniformly stretched plate.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

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
