// Rigid pendulum as an index-3 DAE (absolute coordinates x, y, θ of the bob, revolute to
// ground): generalized-α converges at second order to an independent reference — the
// minimal-coordinate ODE (J + m l²) θ̈ = −m g l cos θ integrated by RK4 with a tiny step —
// the constraints hold to tolerance at every step, and the solution does not depend on the
// augmented-Lagrangian penalty ζ (eq. 7).
#include "support/pendulum.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "support/convergence.hpp"
#include "support/test_models.hpp"

using namespace lsmbs;
using json = nlohmann::json;

namespace {

const test::Pendulum kPendulum;  // m = 1, J = 0.01, l = 1, g = 9.81

json pendulum(double h) {
  json j = kPendulum.json(h, 1.0);
  j["simulation"].update({{"rho_inf", 0.8}, {"tol_r", 1e-12}, {"tol_phi", 1e-14}});
  return j;
}

struct ConstraintWatch : StepObserver {
  const Model* m;
  double worst = 0;
  bool on_step(const StepInfo& i) override {
    Vec phi;
    m->constraints(i.state->t, i.state->q, m->params(), phi);
    worst = std::max(worst, phi.lpNorm<Eigen::Infinity>());
    return true;
  }
};

Vec final_q(double h, double* worst_phi = nullptr, double zeta_factor = 0) {
  Case cs = test::make_case(pendulum(h));
  if (zeta_factor > 0) {
    // ζ relative to the automatic k
    const auto c = AlphaCoefficients::make(0.8, h);
    const double k =
        GeneralizedAlpha::automatic_scaling(*cs.model, cs.model->params(), cs.initial, c);
    cs.simulation.k = k;
    cs.simulation.zeta = zeta_factor * k;
  }
  ConstraintWatch w;
  w.m = cs.model.get();
  State fin;
  const auto s =
      GeneralizedAlpha(cs.simulation).run(*cs.model, cs.model->params(), cs.initial, {&w}, &fin);
  EXPECT_TRUE(s.ok) << s.message;
  if (worst_phi) *worst_phi = w.worst;
  return fin.q;
}

}  // namespace

TEST(RigidPendulum, PositionErrorConvergesAtSecondOrderInH) {
  const Vec2 ref = kPendulum.bob(1.0);
  std::vector<double> e;
  for (double h : {0.02, 0.01, 0.005, 0.0025}) {
    double worst = 0;
    const Vec q = final_q(h, &worst);
    e.push_back((q.head<2>() - ref).norm());
    EXPECT_LT(worst, 1e-13) << "constraints at every step, h = " << h;
  }
  // in the asymptotic range the orders are 2 up to the O(h) next term: 0.05 is ten times what
  // that term contributes at h = 0.02 (the RK4 reference's error is ~1e-15 rad)
  test::expect_order(e, 2.0, 0.05, "rigid pendulum, bob position at 1 s (h = 0.02 ... 0.0025)");
}

TEST(RigidPendulum, SolutionDoesNotDependOnThePenaltyZeta) {
  const Vec q1 = final_q(0.01, nullptr, 1.0);
  const Vec q2 = final_q(0.01, nullptr, 1e-3);
  const Vec q3 = final_q(0.01, nullptr, 1e3);
  EXPECT_LT((q1 - q2).norm(), 1e-10);
  EXPECT_LT((q1 - q3).norm(), 1e-10);
}

TEST(AugmentedLagrangian, AutomaticScalingIsTheMeanDiagonalOfTheIterationMatrix) {
  // k = mean |diag(β′M + γ′C_t + K_t)| over the positions (DESIGN.md, eq. 7's scaling), with
  // β′ = (1 − α_m)/((1 − α_f) β h²), γ′ = γ/(β h) from eq. (11) for ρ∞ = 0.8 (α_m = 1/3,
  // α_f = 4/9). A rigid body (m, J, centre of mass at its reference point) on a spring–damper to
  // ground along x at its free length and at rest: K_t = k_s n nᵀ, C_t = c n nᵀ with n = (1, 0),
  // so the diagonal is (β′m + γ′c + k_s, β′m, β′J).
  const double m = 2.0, J = 0.03, ks = 5e3, c = 40.0, h = 1e-3;
  const json j = json::parse(R"({
    "name": "scaling",
    "bodies": [{"name": "b", "type": "rigid", "position": [0.5, 0], "mass": 2.0, "inertia": 0.03}],
    "forces": [{"name": "s", "type": "spring_damper", "a": {"body": "b"}, "b": {"ground": [0, 0]},
                "stiffness": 5e3, "damping": 40, "free_length": 0.5}],
    "simulation": {"t_end": 0.001, "h": 0.001}
  })");
  Case cs = test::make_case(j);
  const double am = 1.0 / 3, af = 4.0 / 9, g = 0.5 - am + af, b = 0.25 * (g + 0.5) * (g + 0.5);
  const double bp = (1 - am) / ((1 - af) * b * h * h), gp = g / (b * h);
  const double ref = ((bp * m + gp * c + ks) + bp * m + bp * J) / 3;
  const double k = GeneralizedAlpha::automatic_scaling(*cs.model, cs.model->params(), cs.initial,
                                                       AlphaCoefficients::make(0.8, h));
  EXPECT_NEAR(k, ref, 1e-12 * ref);
}
