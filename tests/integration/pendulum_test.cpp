// Rigid pendulum as an index-3 DAE (absolute coordinates x, y, θ of the bob, revolute to
// ground): generalized-α converges at second order to an independent reference — the
// minimal-coordinate ODE (J + m l²) θ̈ = −m g l cos θ integrated by RK4 with a tiny step —
// the constraints hold to tolerance at every step, and the solution does not depend on the
// augmented-Lagrangian penalty ζ (eq. 7).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "support/test_models.hpp"

using namespace lsmbs;
using json = nlohmann::json;

namespace {

constexpr double M = 1.0, J = 0.01, LEN = 1.0, G = 9.81, T_END = 1.0;

json pendulum(double h, double zeta_factor = 0) {
  json j = {{"name", "pendulum"},
            {"gravity", {0, -G}},
            {"bodies", {{{"name", "bob"}, {"type", "rigid"}, {"position", {LEN, 0}}, {"mass", M}, {"inertia", J}}}},
            {"joints", {{{"name", "pin"}, {"type", "revolute"}, {"a", {{"body", "bob"}, {"at", {-LEN, 0}}}}, {"b", "ground"}}}},
            {"simulation", {{"t_end", T_END}, {"h", h}, {"rho_inf", 0.8}, {"tol_r", 1e-12}, {"tol_phi", 1e-14}}}};
  return j;
}

// θ(T_END) from RK4 on the minimal ODE.
double reference_angle() {
  const double I = J + M * LEN * LEN;
  auto f = [&](double th, double om, double& dth, double& dom) {
    dth = om;
    dom = -M * G * LEN * std::cos(th) / I;
  };
  double th = 0, om = 0;
  const int n = 200000;
  const double dt = T_END / n;
  for (int i = 0; i < n; ++i) {
    double k1t, k1o, k2t, k2o, k3t, k3o, k4t, k4o;
    f(th, om, k1t, k1o);
    f(th + 0.5 * dt * k1t, om + 0.5 * dt * k1o, k2t, k2o);
    f(th + 0.5 * dt * k2t, om + 0.5 * dt * k2o, k3t, k3o);
    f(th + dt * k3t, om + dt * k3o, k4t, k4o);
    th += dt / 6 * (k1t + 2 * k2t + 2 * k3t + k4t);
    om += dt / 6 * (k1o + 2 * k2o + 2 * k3o + k4o);
  }
  return th;
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
    const double k = GeneralizedAlpha::automatic_scaling(*cs.model, cs.model->params(), cs.initial, c);
    cs.simulation.k = k;
    cs.simulation.zeta = zeta_factor * k;
  }
  ConstraintWatch w;
  w.m = cs.model.get();
  State fin;
  const auto s = GeneralizedAlpha(cs.simulation).run(*cs.model, cs.model->params(), cs.initial, {&w}, &fin);
  EXPECT_TRUE(s.ok) << s.message;
  if (worst_phi) *worst_phi = w.worst;
  return fin.q;
}

}  // namespace

TEST(RigidPendulum, PositionErrorConvergesAtSecondOrderInH) {
  const double th = reference_angle();
  const Vec2 ref(LEN * std::cos(th), LEN * std::sin(th));
  double e[4];
  const double hs[4] = {0.02, 0.01, 0.005, 0.0025};
  for (int i = 0; i < 4; ++i) {
    double worst = 0;
    const Vec q = final_q(hs[i], &worst);
    e[i] = (q.head<2>() - ref).norm();
    EXPECT_LT(worst, 1e-13) << "constraints at every step, h = " << hs[i];
  }
  for (int i = 0; i < 3; ++i) {
    const double order = std::log2(e[i] / e[i + 1]);
    std::printf("h = %.4f  error %.3e  observed order %.3f\n", hs[i], e[i], order);
    EXPECT_GE(order, 1.8);
    EXPECT_LE(order, 2.2);
  }
}

TEST(RigidPendulum, SolutionDoesNotDependOnThePenaltyZeta) {
  const Vec q1 = final_q(0.01, nullptr, 1.0);
  const Vec q2 = final_q(0.01, nullptr, 1e-3);
  const Vec q3 = final_q(0.01, nullptr, 1e3);
  EXPECT_LT((q1 - q2).norm(), 1e-10);
  EXPECT_LT((q1 - q3).norm(), 1e-10);
}
