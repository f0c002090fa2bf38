// Rigid slider-crank (crank radius r = 45 mm, rod l = 135.6 mm) driven through its crank angle:
// the crank angle equals the driver law θ(t) and the piston position equals the closed-form
// kinematics x = r cos θ + √(l² − r² sin²θ) to Newton tolerance at every step, for every law and
// every phase of it — θ(t) written here independently of lsmbs::TimeLaw (trapezoids and ramps as
// sums of shifted ramp functions, tables by their own interpolation). The piston velocity
// ẋ = −r θ̇ sin θ (1 + r cos θ / √(l² − r² sin²θ)) is reached at second order in h (velocities of
// the index-3 scheme are integrated, not projected).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <map>

#include "support/convergence.hpp"
#include "support/test_models.hpp"

using namespace lsmbs;
using json = nlohmann::json;

namespace {

constexpr double R = 0.045, L = 0.1356;

// θ, θ̇, θ̈ at t and the name of the phase t lies in.
struct Theta {
  double th = 0, thd = 0, thdd = 0;
  std::string phase;
};
using Law = std::function<Theta(double)>;

double ramp(double x) { return x > 0 ? x : 0; }
double step(double x) { return x > 0 ? 1 : 0; }

// Constant acceleration ±a between the switching times t0 < t1 ≤ t2 < t3: θ̈ = dir a (H(t − t0)
// − H(t − t1) − H(t − t2) + H(t − t3)), integrated twice. The cruise speed v is reached when the
// distance allows (a (v/a)² ≤ |Δθ|), otherwise the profile is triangular with peak √(a|Δθ|).
Law trapezoid(double from, double to, double a, double v, double start) {
  const double dist = std::abs(to - from), dir = to >= from ? 1 : -1;
  const double ta = a * (v / a) * (v / a) <= dist ? v / a : std::sqrt(dist / a);
  const double tc = (dist - a * ta * ta) / v;  // 0 for the triangle (up to round-off)
  const double t0 = start, t1 = start + ta, t2 = t1 + std::max(tc, 0.0), t3 = t2 + ta;
  return [=](double t) {
    Theta r;
    r.th = from + dir * a / 2 *
                      (ramp(t - t0) * ramp(t - t0) - ramp(t - t1) * ramp(t - t1) -
                       ramp(t - t2) * ramp(t - t2) + ramp(t - t3) * ramp(t - t3));
    r.thd = dir * a * (ramp(t - t0) - ramp(t - t1) - ramp(t - t2) + ramp(t - t3));
    r.thdd = dir * a * (step(t - t0) - step(t - t1) - step(t - t2) + step(t - t3));
    r.phase = t <= t0  ? "before"
              : t < t1 ? "accelerate"
              : t < t2 ? "constant"
              : t < t3 ? "decelerate"
                       : "after";
    return r;
  };
}

// Speed ω reached linearly in t_r from `start`, then constant.
Law ramp_law(double from, double w, double tr, double start) {
  return [=](double t) {
    Theta r;
    r.th = from +
           w / (2 * tr) *
               (ramp(t - start) * ramp(t - start) - ramp(t - start - tr) * ramp(t - start - tr));
    r.thd = w / tr * (ramp(t - start) - ramp(t - start - tr));
    r.thdd = w / tr * (step(t - start) - step(t - start - tr));
    r.phase = t <= start ? "before" : t < start + tr ? "ramp" : "constant";
    return r;
  };
}

// Piecewise-linear table, held beyond its ends.
Law linear_table(std::vector<double> x, std::vector<double> y) {
  return [=](double t) {
    Theta r;
    if (t <= x.front()) return r.th = y.front(), r.phase = "before", r;
    if (t >= x.back()) return r.th = y.back(), r.phase = "after", r;
    size_t i = 0;
    while (t > x[i + 1]) ++i;
    r.thd = (y[i + 1] - y[i]) / (x[i + 1] - x[i]);
    r.th = y[i] + r.thd * (t - x[i]);
    r.phase = "segment " + std::to_string(i);
    return r;
  };
}

// Natural cubic spline (s″ = 0 at both ends), held beyond its ends: second derivatives from the
// tridiagonal system h_{i−1} m_{i−1} + 2 (h_{i−1} + h_i) m_i + h_i m_{i+1} = 6 (d_i − d_{i−1}).
Law natural_spline(std::vector<double> x, std::vector<double> y) {
  const size_t n = x.size();
  std::vector<double> h(n - 1), d(n - 1), m(n, 0.0);
  for (size_t i = 0; i + 1 < n; ++i) h[i] = x[i + 1] - x[i], d[i] = (y[i + 1] - y[i]) / h[i];
  Mat A = Mat::Zero(n - 2, n - 2);
  Vec b(n - 2);
  for (size_t i = 1; i + 1 < n; ++i) {
    A(i - 1, i - 1) = 2 * (h[i - 1] + h[i]);
    if (i > 1) A(i - 1, i - 2) = h[i - 1];
    if (i + 2 < n) A(i - 1, i) = h[i];
    b[i - 1] = 6 * (d[i] - d[i - 1]);
  }
  const Vec mi = A.lu().solve(b);
  for (size_t i = 1; i + 1 < n; ++i) m[i] = mi[i - 1];
  return [=](double t) {
    Theta r;
    if (t <= x.front()) return r.th = y.front(), r.phase = "before", r;
    if (t >= x.back()) return r.th = y.back(), r.phase = "after", r;
    size_t i = 0;
    while (t > x[i + 1]) ++i;
    const double u = x[i + 1] - t, w = t - x[i];
    r.th = m[i] * u * u * u / (6 * h[i]) + m[i + 1] * w * w * w / (6 * h[i]) +
           (y[i] / h[i] - m[i] * h[i] / 6) * u + (y[i + 1] / h[i] - m[i + 1] * h[i] / 6) * w;
    r.thd = -m[i] * u * u / (2 * h[i]) + m[i + 1] * w * w / (2 * h[i]) - y[i] / h[i] +
            m[i] * h[i] / 6 + y[i + 1] / h[i] - m[i + 1] * h[i] / 6;
    r.thdd = (m[i] * u + m[i + 1] * w) / h[i];
    r.phase = "segment " + std::to_string(i);
    return r;
  };
}

double piston_x(double th) {
  return R * std::cos(th) + std::sqrt(L * L - R * R * std::sin(th) * std::sin(th));
}
double piston_v(double th, double thd) {
  const double s = std::sqrt(L * L - R * R * std::sin(th) * std::sin(th));
  return -R * thd * std::sin(th) * (1 + R * std::cos(th) / s);
}

struct Errors {
  double angle = 0, pos = 0, vel = 0, vel_scale = 0;
  std::map<std::string, int> steps_in_phase;
};

// The shipped rigid slider-crank with `law` on the crank (all laws start at θ = 0, the shipped
// initial configuration), run to t_end at step h; errors against `theta`. Velocities are compared
// from t_vel on.
Errors run(const json& law, const Law& theta, double t_end, double h, double t_vel = 1e300) {
  json c = json::parse(std::ifstream(std::string(LSMBS_SOURCE_DIR) +
                                     "/data/slider_crank_rigid/slider_crank_rigid.json"));
  for (auto& j : c["joints"])
    if (j["name"] == "crank_drive") j["law"] = law;
  c["simulation"].update({{"t_end", t_end}, {"h", h}, {"tol_r", 1e-12}, {"tol_phi", 1e-14}});
  Case cs = test::make_case(c);
  struct Obs : StepObserver {
    const Law* theta;
    int crank, piston;
    double t_vel;
    Errors e;
    bool on_step(const StepInfo& i) override {
      const Theta th = (*theta)(i.state->t);
      ++e.steps_in_phase[th.phase];
      e.angle = std::max(e.angle, std::abs(i.state->q[crank] - th.th));
      e.pos = std::max(e.pos, std::abs(i.state->q[piston] - piston_x(th.th)) / piston_x(th.th));
      if (i.state->t >= t_vel) {
        e.vel = std::max(e.vel, std::abs(i.state->v[piston] - piston_v(th.th, th.thd)));
        e.vel_scale = std::max(e.vel_scale, std::abs(piston_v(th.th, th.thd)));
      }
      return true;
    }
  } obs;
  obs.theta = &theta;
  obs.crank = cs.model->find_rigid("crank")->dof0 + 2;
  obs.piston = cs.model->find_rigid("piston")->dof0;
  obs.t_vel = t_vel;
  const auto sum =
      GeneralizedAlpha(cs.simulation).run(*cs.model, cs.model->params(), cs.initial, {&obs});
  EXPECT_TRUE(sum.ok) << sum.message;
  return obs.e;
}

const double kOmega = 4000 * 2 * M_PI / 60;  // §5: 0 → 4000 rpm in 0.01 s

}  // namespace

TEST(RigidSliderCrank, CrankAngleAndPistonPositionFollowEveryPhaseOfEveryDriverLaw) {
  struct Case_ {
    const char* what;
    json law;
    Law theta;
    double t_end;
    std::vector<std::string> phases;
  };
  const std::vector<double> tx = {0, 0.004, 0.008, 0.011, 0.016}, ty = {0, 0.3, 1.4, 1.2, 2.5};
  const Case_ cases[] = {
      {"ramp (§5)",
       {{"type", "ramp"}, {"from", 0}, {"speed", kOmega}, {"ramp_time", 0.01}},
       ramp_law(0, kOmega, 0.01, 0),
       0.02,
       {"ramp", "constant"}},
      {"ramp, delayed start",
       {{"type", "ramp"}, {"from", 0}, {"speed", 200}, {"ramp_time", 0.005}, {"start", 0.003}},
       ramp_law(0, 200, 0.005, 0.003),
       0.012,
       {"before", "ramp", "constant"}},
      {"trapezoid",
       {{"type", "trapezoid"},
        {"from", 0},
        {"to", 3},
        {"acceleration", 4e4},
        {"speed", 200},
        {"start", 0.002}},
       trapezoid(0, 3, 4e4, 200, 0.002),
       0.026,
       {"before", "accelerate", "constant", "decelerate", "after"}},
      {"trapezoid, backwards",
       {{"type", "trapezoid"}, {"from", 0}, {"to", -2}, {"acceleration", 4e4}, {"speed", 150}},
       trapezoid(0, -2, 4e4, 150, 0),
       0.02,
       {"accelerate", "constant", "decelerate", "after"}},
      {"trapezoid, triangular",
       {{"type", "trapezoid"}, {"from", 0}, {"to", 0.5}, {"acceleration", 4e4}, {"speed", 200}},
       trapezoid(0, 0.5, 4e4, 200, 0),
       0.01,
       {"accelerate", "decelerate", "after"}},
      {"constant",
       {{"type", "constant"}, {"value", 0}},
       [](double) {
         return Theta{0, 0, 0, "constant"};
       },
       0.005,
       {"constant"}},
      {"linear table",
       {{"type", "table"},
        {"interpolation", "linear"},
        {"points", {{0, 0}, {0.004, 0.3}, {0.008, 1.4}, {0.011, 1.2}, {0.016, 2.5}}}},
       linear_table(tx, ty),
       0.02,
       {"segment 0", "segment 1", "segment 2", "segment 3", "after"}},
      {"cubic table",
       {{"type", "table"},
        {"points", {{0, 0}, {0.004, 0.3}, {0.008, 1.4}, {0.011, 1.2}, {0.016, 2.5}}}},
       natural_spline(tx, ty),
       0.02,
       {"segment 0", "segment 1", "segment 2", "segment 3", "after"}},
  };
  for (const auto& c : cases) {
    const Errors e = run(c.law, c.theta, c.t_end, 2.5e-4);
    std::printf(
        "%-22s: max |θ − θ(t)| %.1e rad, max relative piston position error %.1e; steps per phase:",
        c.what, e.angle, e.pos);
    for (const auto& [p, n] : e.steps_in_phase) std::printf(" %s %d", p.c_str(), n);
    std::printf("\n");
    // Newton tolerance: |Φ| ≤ tol_phi = 1e-14 × the 0.18 m length scale on every constraint, an
    // angle error of ~5e-14 rad through the crank radius (measured ≤ 2.2e-15)
    EXPECT_LT(e.angle, 1e-13) << c.what;
    EXPECT_LT(e.pos, 1e-13) << c.what;
    for (const auto& p : c.phases)
      EXPECT_GE(e.steps_in_phase.count(p) ? e.steps_in_phase.at(p) : 0, 3) << c.what << ": " << p;
    EXPECT_EQ(e.steps_in_phase.size(), c.phases.size()) << c.what;
  }
}

TEST(RigidSliderCrank, PistonVelocityConvergesToTheClosedFormAtSecondOrder) {
  // the §5 ramp; velocities in the smooth constant-speed phase after the 2.5 ms settling period
  // (the ramp's acceleration jumps at t = 0 and t = 0.01 s excite O(h) transients that the
  // numerical damping removes)
  const json law = {{"type", "ramp"}, {"from", 0}, {"speed", kOmega}, {"ramp_time", 0.01}};
  const Law theta = ramp_law(0, kOmega, 0.01, 0);
  std::vector<double> rel;
  for (double h : {1e-4, 5e-5, 2.5e-5}) {
    const Errors e = run(law, theta, 0.0425, h, 0.0125);
    rel.push_back(e.vel / e.vel_scale);
  }
  // the asymptotic range (measured 2.000, 2.000)
  test::expect_order(rel, 2.0, 0.1, "piston velocity error / max speed, h = 1e-4, 5e-5, 2.5e-5");
  EXPECT_LT(rel.back(), 1e-4);
}
