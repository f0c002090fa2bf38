// Torque and rotational spring–damper in generalized-α runs against closed forms:
//  * a rotor pinned at its reference point, centre of mass off the pin, no gravity, driven by a
//    constant torque T: θ(t) = θ0 + ω0 t + T t²/(2J), J = J_c + m|c|² — and the direct
//    sensitivities of θ(t_end) with respect to the torque's scale, J_c and m against the
//    derivatives of that closed form (exact ∂r/∂p of Torque and RigidInertia end to end);
//  * a rotor on a rotational spring–damper to ground: J θ̈ + c θ̇ + k (θ − θ0) = 0, a damped
//    oscillation at ω_d = sqrt(k/J − (c/2J)²), second-order convergence in h;
//  * two rotors coupled by a rotational spring: the relative angle oscillates at
//    sqrt(k (1/J1 + 1/J2)) and the angular momentum J1 ω1 + J2 ω2 is conserved;
//  * direct-analytic sensitivities with respect to stiffness, damping and free angle against
//    central finite differences of whole runs.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>

#include "lsmbs/sensitivity/sensitivity.hpp"
#include "support/convergence.hpp"
#include "support/test_models.hpp"

using namespace lsmbs;
using json = nlohmann::json;

namespace {

constexpr double kMass = 2.0, kJc = 0.05, kCx = 0.3, kTorque = 0.8, kScale = 1.25, kTheta0 = 0.3,
                 kOmega0 = 0.5, kTEnd = 1.0;

json torque_rotor(double h) {
  json j = json::parse(R"({
    "name": "torque_rotor",
    "bodies": [{"name": "rotor", "type": "rigid", "position": [0, 0], "mass": 2.0, "inertia": 0.05, "com": [0.3, 0]}],
    "joints": [{"name": "pin", "type": "revolute", "a": {"body": "rotor"}, "b": "ground"}],
    "forces": [{"name": "motor", "type": "torque", "body": "rotor", "torque": 0.8, "scale": 1.25}],
    "simulation": {"t_end": 1.0, "h": 0.01, "tol_r": 1e-12},
    "output": {
      "measures": [{"name": "theta", "type": "angle", "body": "rotor"},
                   {"name": "omega", "type": "angular_velocity", "body": "rotor"}],
      "responses": [{"name": "final_angle", "measure": "theta", "aggregate": "final"},
                    {"name": "final_speed", "measure": "omega", "aggregate": "final"}]
    },
    "design": {
      "variables": [{"name": "s", "initial": 1.25, "lower": 0.5, "upper": 2},
                    {"name": "J", "initial": 0.05, "lower": 0.01, "upper": 0.1},
                    {"name": "m", "initial": 2.0, "lower": 1, "upper": 3}],
      "parameters": [{"parameter": "motor.scale", "variable": "s"}, {"parameter": "rotor.inertia", "variable": "J"},
                     {"parameter": "rotor.mass", "variable": "m"}]
    }
  })");
  j["bodies"][0]["angle"] = kTheta0;
  j["bodies"][0]["angular_velocity"] = kOmega0;
  j["simulation"]["h"] = h;
  return j;
}

struct AngleWatch : StepObserver {
  std::function<double(double)> theta, omega;
  int dof = 2;
  double worst_theta = 0, worst_omega = 0;
  bool on_step(const StepInfo& i) override {
    worst_theta = std::max(worst_theta, std::abs(i.state->q[dof] - theta(i.state->t)));
    if (omega) worst_omega = std::max(worst_omega, std::abs(i.state->v[dof] - omega(i.state->t)));
    return true;
  }
};

}  // namespace

TEST(TorqueRotor, ConstantTorqueGivesTheParabolicAngle) {
  Case cs = test::make_case(torque_rotor(0.01));
  const double J = kJc + kMass * kCx * kCx, T = kScale * kTorque;
  AngleWatch w;
  w.theta = [&](double t) { return kTheta0 + kOmega0 * t + T * t * t / (2 * J); };
  w.omega = [&](double t) { return kOmega0 + T * t / J; };
  const auto r =
      GeneralizedAlpha(cs.simulation).run(*cs.model, cs.model->params(), cs.initial, {&w});
  ASSERT_TRUE(r.ok) << r.message;
  std::printf(
      "constant torque, J = %.3f: |θ − θ_exact| ≤ %.2e rad, |ω − ω_exact| ≤ %.2e rad/s over %g s "
      "(θ(t_end) = %.4f)\n",
      J, w.worst_theta, w.worst_omega, kTEnd, w.theta(kTEnd));
  // constant angular acceleration: generalized-α integrates quadratic motion exactly
  EXPECT_LT(w.worst_theta, 1e-10);
  EXPECT_LT(w.worst_omega, 1e-9);
}

TEST(TorqueRotor, DirectSensitivitiesMatchTheDerivativesOfTheClosedForm) {
  // θ(t) = θ0 + ω0 t + s T0 t²/(2J), J = J_c + m c²:
  //   ∂θ/∂s = T0 t²/(2J), ∂θ/∂J_c = −s T0 t²/(2J²), ∂θ/∂m = −s T0 t² c²/(2J²); ω likewise with t.
  Case cs = test::make_case(torque_rotor(0.01));
  SensitivityOptions o;
  o.method = SensitivityOptions::Method::kDirectAnalytic;
  o.matrix = SensitivityOptions::Matrix::kConverged;
  const auto res = compute_sensitivities(cs, cs.design->initial(), o);
  ASSERT_TRUE(res.ok) << res.message;
  const double J = kJc + kMass * kCx * kCx, t = kTEnd;
  const double a = kTorque / (2 * J), b = -kScale * kTorque / (2 * J * J);
  const Eigen::RowVector3d dtheta(a * t * t, b * t * t, b * kCx * kCx * t * t),
      domega(2 * a * t, 2 * b * t, 2 * b * kCx * kCx * t);
  ASSERT_EQ(res.responses.size(), 2u);
  const Eigen::RowVectorXd g0 = res.responses[0].gradient.row(0),
                           g1 = res.responses[1].gradient.row(0);
  const double e0 = (g0 - dtheta).cwiseAbs().maxCoeff() / dtheta.cwiseAbs().maxCoeff();
  const double e1 = (g1 - domega).cwiseAbs().maxCoeff() / domega.cwiseAbs().maxCoeff();
  std::printf(
      "torque rotor: dθ(t_end)/d(scale, J_c, m) = (%.6f, %.6f, %.6f), closed form (%.6f, %.6f, "
      "%.6f): "
      "relative error %.2e; dω: %.2e\n",
      g0[0], g0[1], g0[2], dtheta[0], dtheta[1], dtheta[2], e0, e1);
  EXPECT_LT(e0, 1e-9);
  EXPECT_LT(e1, 1e-9);
}

namespace {

constexpr double kK = 4.0, kC = 0.02, kJ = 0.1, kFree = 0.1, kStart = 0.4;

json spring_rotor(double h, double t_end) {
  json j = json::parse(R"({
    "name": "spring_rotor",
    "bodies": [{"name": "rotor", "type": "rigid", "position": [0, 0], "mass": 1.0, "inertia": 0.1}],
    "joints": [{"name": "pin", "type": "revolute", "a": {"body": "rotor"}, "b": "ground"}],
    "forces": [{"name": "torsion", "type": "rotational_spring_damper", "a": "rotor", "b": "ground",
                "stiffness": 4.0, "damping": 0.02, "free_angle": 0.1}],
    "simulation": {"t_end": 1.0, "h": 0.01, "tol_r": 1e-12},
    "output": {
      "measures": [{"name": "theta", "type": "angle", "body": "rotor"}],
      "responses": [{"name": "final_angle", "measure": "theta", "aggregate": "final"},
                    {"name": "mean_square", "measure": "theta", "aggregate": "rms"}]
    },
    "design": {
      "variables": [{"name": "k", "initial": 4.0, "lower": 1, "upper": 10},
                    {"name": "c", "initial": 0.02, "lower": 0.001, "upper": 0.1},
                    {"name": "a0", "initial": 0.1, "lower": -1, "upper": 1}],
      "parameters": [{"parameter": "torsion.stiffness", "variable": "k"}, {"parameter": "torsion.damping", "variable": "c"},
                     {"parameter": "torsion.free_angle", "variable": "a0"}]
    }
  })");
  j["bodies"][0]["angle"] = kStart;
  j["simulation"]["h"] = h;
  j["simulation"]["t_end"] = t_end;
  return j;
}

// J θ̈ + c θ̇ + k (θ − θf) = 0, θ(0) = θs, θ̇(0) = 0.
double damped(double t) {
  const double sigma = kC / (2 * kJ), wd = std::sqrt(kK / kJ - sigma * sigma);
  return kFree + (kStart - kFree) * std::exp(-sigma * t) *
                     (std::cos(wd * t) + sigma / wd * std::sin(wd * t));
}

}  // namespace

TEST(RotationalSpring, RotorOscillatesAtSqrtKOverJWithSecondOrderConvergence) {
  const double period = 2 * M_PI / std::sqrt(kK / kJ), t_end = 3 * period;
  double err[3];
  const double hs[3] = {period / 50, period / 100, period / 200};
  for (int i = 0; i < 3; ++i) {
    Case cs = test::make_case(spring_rotor(hs[i], t_end));
    AngleWatch w;
    w.theta = damped;
    const auto r =
        GeneralizedAlpha(cs.simulation).run(*cs.model, cs.model->params(), cs.initial, {&w});
    ASSERT_TRUE(r.ok) << r.message;
    err[i] = w.worst_theta;
  }
  std::printf("rotational spring, ω = %.4f rad/s, amplitude %.2f rad, 3 periods:\n",
              std::sqrt(kK / kJ), kStart - kFree);
  test::expect_order({err[0], err[1], err[2]}, 2.0, 0.15,
                     "max |θ − θ_exact| for h = T/50, T/100, T/200");
  EXPECT_LT(err[2], 2e-3 * (kStart - kFree));
}

TEST(RotationalSpring, TwoRotorsCoupledBodyToBody) {
  // Rotors 1 (J1 = 0.1) and 2 (J2 = 0.3) pinned at different points, spring k between them with
  // free angle 0, started at θ1 = 0.3, θ2 = −0.1 at rest: θ1 − θ2 = 0.4 cos(ω t),
  // ω = sqrt(k (1/J1 + 1/J2)), and J1 θ1 + J2 θ2 stays 0.
  const double J1 = 0.1, J2 = 0.3, k = 2.0, w = std::sqrt(k * (1 / J1 + 1 / J2)), T = 2 * M_PI / w;
  json j = json::parse(R"({
    "name": "coupled",
    "bodies": [{"name": "r1", "type": "rigid", "position": [0, 0], "angle": 0.3, "mass": 1.0, "inertia": 0.1},
               {"name": "r2", "type": "rigid", "position": [1, 0], "angle": -0.1, "mass": 1.0, "inertia": 0.3}],
    "joints": [{"type": "revolute", "a": {"body": "r1"}, "b": "ground"},
               {"type": "revolute", "a": {"body": "r2"}, "b": "ground"}],
    "forces": [{"name": "shaft", "type": "rotational_spring_damper", "a": "r1", "b": "r2", "stiffness": 2.0, "free_angle": 0}],
    "simulation": {"t_end": 1.0, "h": 0.01, "tol_r": 1e-12}
  })");
  j["simulation"]["t_end"] = 2 * T;
  j["simulation"]["h"] = T / 200;
  Case cs = test::make_case(j);
  struct Watch : StepObserver {
    double w, J1, J2, worst_rel = 0, worst_momentum = 0, worst_balance = 0;
    bool on_step(const StepInfo& i) override {
      const Vec& q = i.state->q;
      const Vec& v = i.state->v;
      worst_rel = std::max(worst_rel, std::abs(q[2] - q[5] - 0.4 * std::cos(w * i.state->t)));
      worst_momentum = std::max(worst_momentum, std::abs(J1 * v[2] + J2 * v[5]));
      worst_balance = std::max(worst_balance, std::abs(J1 * q[2] + J2 * q[5]));
      return true;
    }
  } watch;
  watch.w = w, watch.J1 = J1, watch.J2 = J2;
  const auto r =
      GeneralizedAlpha(cs.simulation).run(*cs.model, cs.model->params(), cs.initial, {&watch});
  ASSERT_TRUE(r.ok) << r.message;
  std::printf(
      "coupled rotors (ω = %.4f rad/s, 2 periods, h = T/200): |Δθ − 0.4 cos ωt| ≤ %.2e, |J1ω1 + "
      "J2ω2| ≤ %.2e, "
      "|J1θ1 + J2θ2| ≤ %.2e\n",
      w, watch.worst_rel, watch.worst_momentum, watch.worst_balance);
  EXPECT_LT(watch.worst_rel, 2e-3 * 0.4);
  EXPECT_LT(watch.worst_momentum, 1e-10);
  EXPECT_LT(watch.worst_balance, 1e-10);
}

TEST(RotationalSpring, DirectSensitivitiesMatchCentralFiniteDifferences) {
  Case cs = test::make_case(spring_rotor(0.005, 1.5));
  SensitivityOptions o;
  o.matrix = SensitivityOptions::Matrix::kConverged;
  o.method = SensitivityOptions::Method::kDirectAnalytic;
  const auto direct = compute_sensitivities(cs, cs.design->initial(), o);
  o.method = SensitivityOptions::Method::kFdCentral;
  o.delta = 1e-5;
  const auto fd = compute_sensitivities(cs, cs.design->initial(), o);
  ASSERT_TRUE(direct.ok && fd.ok) << direct.message << fd.message;
  double worst = 0;
  for (size_t r = 0; r < fd.responses.size(); ++r) {
    const Mat& A = direct.responses[r].gradient;
    const Mat& B = fd.responses[r].gradient;
    const double e = (A - B).cwiseAbs().maxCoeff() / B.cwiseAbs().maxCoeff();
    std::printf(
        "rotational spring: %s gradient (k, c, θ0) direct (%.6e, %.6e, %.6e) vs fd-central: %.2e\n",
        fd.responses[r].name.c_str(), A(0, 0), A(0, 1), A(0, 2), e);
    worst = std::max(worst, e);
  }
  EXPECT_LT(worst, 1e-6);
}
