#pragma once
// The rigid pendulum of several tests: a bob (mass m, inertia J about its centre) at distance
// l from a revolute joint to ground, released horizontally at rest under gravity g, and its
// independent reference: the minimal-coordinate ODE (J + m l²) θ̈ = −m g l cos θ by RK4.
#include <cmath>
#include <nlohmann/json.hpp>

#include "lsmbs/core/types.hpp"

namespace lsmbs::test {

struct Pendulum {
  double m = 1.0, J = 0.01, l = 1.0, g = 9.81;

  /// Case document: bob at (l, 0), pin at the origin, run to t_end with step h.
  nlohmann::json json(double h, double t_end = 1.0) const {
    return {
        {"name", "pendulum"},
        {"gravity", {0, -g}},
        {"bodies",
         {{{"name", "bob"}, {"type", "rigid"}, {"position", {l, 0}}, {"mass", m}, {"inertia", J}}}},
        {"joints",
         {{{"name", "pin"},
           {"type", "revolute"},
           {"a", {{"body", "bob"}, {"at", {-l, 0}}}},
           {"b", "ground"}}}},
        {"simulation", {{"t_end", t_end}, {"h", h}}}};
  }

  /// θ(t) from classical RK4 on the minimal ODE with n steps (global error O(n⁻⁴): with
  /// n = 2e5 over 1 s, far below the generalized-α errors it is compared with).
  double angle(double t, int n = 200000) const {
    const double c = m * g * l / (J + m * l * l);
    auto acc = [c](double th) { return -c * std::cos(th); };
    double th = 0, om = 0;
    const double dt = t / n;
    for (int i = 0; i < n; ++i) {
      const double k1t = om, k1o = acc(th);
      const double k2t = om + 0.5 * dt * k1o, k2o = acc(th + 0.5 * dt * k1t);
      const double k3t = om + 0.5 * dt * k2o, k3o = acc(th + 0.5 * dt * k2t);
      const double k4t = om + dt * k3o, k4o = acc(th + dt * k3t);
      th += dt / 6 * (k1t + 2 * k2t + 2 * k3t + k4t);
      om += dt / 6 * (k1o + 2 * k2o + 2 * k3o + k4o);
    }
    return th;
  }

  /// Bob position (l cos θ, l sin θ) at time t from the RK4 reference.
  Vec2 bob(double t) const {
    const double th = angle(t);
    return {l * std::cos(th), l * std::sin(th)};
  }
};

}  // namespace lsmbs::test
