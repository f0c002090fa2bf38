// The IDAS reference path (GGL index 2, SUNDIALS IDAS) against the generalized-α path and
// against finite differences of itself:
//  * generalized-α trajectories converge to the IDAS reference at second order in h (halving
//    h divides the difference by 3.5–4.5), on a rigid mechanism and on a flexible model;
//  * IDAS forward sensitivities agree with central differences of IDAS runs, on the spring and
//    damper of the rigid slider-crank and on level-set variables of the flexible arm;
//  * IDAS adjoint gradients of time integrals agree with the forward ones;
//  * generalized-α direct-analytic gradients converge to the IDAS gradients at second order.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>

#include "lsmbs/core/error.hpp"
#include "lsmbs/sensitivity/sensitivity.hpp"
#include "support/test_models.hpp"

using namespace lsmbs;
using json = nlohmann::json;

namespace {

json spring_crank() {
  return json::parse(std::ifstream(std::string(LSMBS_SOURCE_DIR) +
                                   "/data/slider_crank_rigid/slider_crank_spring.json"));
}

// Small flexible model: the robot arm with holes on a 12 × 2 mesh, 0.1 s. (IDAS's error test is
// on positions only for flexible models; with velocities in it, the lightly excited stiff plate
// modes kept its BDF steps near 1e-6 s: ~1.3e5 steps.)
json flexible_arm() {
  json c = json::parse(
      std::ifstream(std::string(LSMBS_SOURCE_DIR) + "/data/robot_arm/robot_arm_holes.json"));
  c["bodies"][2]["mesh"]["elements"] = {12, 2};
  c["simulation"]["t_end"] = 0.1;
  c["output"]["vtu_stride"] = 0;
  c.erase("optimization");
  // windows on the constant-speed phase (from 0.25 s) lie after this run: refused by the loader
  json keep = json::array();
  for (const auto& r : c["output"]["responses"])
    if (!r.contains("window")) keep.push_back(r);
  c["output"]["responses"] = keep;
  return c;
}

// The final tip deviation (a grid value) and its time integral (an IDAS quadrature).
json deviation_responses() {
  return json::array(
      {json{{"name", "final_dev"}, {"measure", "tip_deviation"}, {"aggregate", "final"}},
       json{{"name", "int_dev"}, {"measure", "tip_deviation"}, {"aggregate", "integral"}}});
}

// A simulation of the case by IDAS with the given options (default: the reference preset).
SimulationResult run_idas(const Case& cs, const IdasOptions& io = IdasOptions::reference()) {
  RunOptions ro;
  ro.idas = true;
  ro.idas_options = io;
  return run_simulation(cs, ro);
}

// Final value of a measure column with generalized-α at step h, or with IDAS on the grid h.
double final_value(json c, double h, const std::string& column, bool idas, double rtol) {
  c["simulation"]["h"] = h;
  c["simulation"]["tol_r"] = 1e-12;
  Case cs = test::make_case(c);
  RunOptions ro;
  ro.idas = idas;
  ro.idas_options = IdasOptions::reference();
  ro.idas_options.rtol = rtol;
  ro.idas_options.atol = 1e-3 * rtol;
  const auto r = run_simulation(cs, ro);
  EXPECT_TRUE(r.integrator.ok) << r.integrator.message;
  return r.column(column).back();
}

void expect_second_order(const json& c, const std::string& column, double h0, const char* what,
                         double rtol) {
  const double ref = final_value(c, h0, column, true, rtol);
  double d[3];
  for (int i = 0; i < 3; ++i)
    d[i] = std::abs(final_value(c, h0 / (1 << i), column, false, rtol) - ref);
  const double r1 = d[0] / d[1], r2 = d[1] / d[2];
  std::printf("%s: |GA - IDAS| = %.3e, %.3e, %.3e; ratios %.2f %.2f\n", what, d[0], d[1], d[2], r1,
              r2);
  EXPECT_GT(r1, 3.5);
  EXPECT_LT(r1, 4.5);
  EXPECT_GT(r2, 3.5);
  EXPECT_LT(r2, 4.5);
}

// Relative step of the central differences of IDAS runs. Each run's adaptive step sequence
// differs, which puts a noise of ~1e-9 on the responses: at 1e-4 it reached 1.4e-4 of the
// smallest derivative (d/dp0 ≈ 4e-4) and moved by 3.5e-5 when only KLU's pivoting changed,
// while IDAS's own sensitivities moved by 7e-8. At 1e-3 the noise is ten times smaller and
// the O(h²) truncation error stays below 1e-6.
constexpr double kFdStep = 1e-3;

// IDAS forward sensitivities at the tight tolerances of the sensitivity tests.
SensitivityOptions tight_idas() {
  SensitivityOptions o;
  o.method = SensitivityOptions::Method::kIdas;
  o.idas.rtol = 1e-10;
  o.idas.atol = 1e-13;
  return o;
}

// One IDAS run of the case with design variable i moved by dp (the parameters are restored).
SimulationResult idas_run_at(Case& cs, const Vec& p, int i, double dp, const IdasOptions& io) {
  Vec pp = p;
  pp[i] += dp;
  cs.design->apply(pp, cs.model->params());
  auto res = run_idas(cs, io);
  cs.design->apply(p, cs.model->params());
  return res;
}

}  // namespace

TEST(Idas, GeneralizedAlphaConvergesToIdasAtSecondOrderOnARigidMechanism) {
  expect_second_order(spring_crank(), "crank_angle", 2e-3, "rigid slider-crank, final crank angle",
                      1e-10);
}

TEST(Idas, GeneralizedAlphaConvergesToIdasAtSecondOrderOnAFlexibleModel) {
  expect_second_order(flexible_arm(), "tip.x", 0.01, "flexible robot arm, final tip x", 1e-9);
}

TEST(Idas, ForwardSensitivitiesAgreeWithFiniteDifferencesOfIdasRuns) {
  Case cs = test::make_case(spring_crank());
  const SensitivityOptions o = tight_idas();
  const Vec p = cs.design->initial();
  const auto s = compute_sensitivities(cs, p, o);
  ASSERT_TRUE(s.ok) << s.message;
  // central differences of IDAS runs of the responses
  const char* resp[] = {"final_crank_angle", "mean_piston_x", "energy_integral"};
  double worst = 0;
  for (int i = 0; i < 2; ++i) {
    const double h = kFdStep * std::abs(p[i]);
    const auto plus = idas_run_at(cs, p, i, h, o.idas), minus = idas_run_at(cs, p, i, -h, o.idas);
    for (int r = 0; r < 3; ++r) {
      const double fd = (plus.responses.at(resp[r]) - minus.responses.at(resp[r])) / (2 * h);
      double an = NAN;
      for (const auto& rs : s.responses)
        if (rs.name == resp[r]) an = rs.gradient(0, i);
      const double e = std::abs(an - fd) / std::abs(fd);
      std::printf("d %s / d p%d: IDAS %.8e, FD of IDAS %.8e (%.1e)\n", resp[r], i, an, fd, e);
      worst = std::max(worst, e);
    }
  }
  EXPECT_LT(worst, 1e-4);
}

// idas_on_grids (verify's time-step study): one IDAS run with outputs every h/2 gives, on the
// grids of step h/2, h and 2h, what a run on each grid gives by itself (its own output times,
// its own response windows and aggregates), to IDAS's tolerance: values and gradients of every
// response, per-step ones included, against separate runs on each grid.
TEST(Idas, OneRunOnTheFinestGridGivesTheResponsesOfEveryCoarserGrid) {
  json c = spring_crank();
  const double h = c["simulation"]["h"].get<double>();
  SensitivityOptions o = tight_idas();
  Case cs = test::make_case(c);
  const Vec p = cs.design->initial();
  const std::vector<int> strides = {1, 2, 4};
  const auto grids = idas_on_grids(cs, p, o, h / 2, strides);
  ASSERT_EQ(grids.size(), strides.size());
  for (size_t g = 0; g < strides.size(); ++g) {
    ASSERT_TRUE(grids[g].ok) << grids[g].message;
    c["simulation"]["h"] = strides[g] * h / 2;
    Case one = test::make_case(c);
    const auto ref = compute_sensitivities(one, p, o);
    ASSERT_TRUE(ref.ok) << ref.message;
    ASSERT_EQ(grids[g].responses.size(), ref.responses.size());
    for (size_t r = 0; r < ref.responses.size(); ++r) {
      const auto &a = grids[g].responses[r], &b = ref.responses[r];
      ASSERT_EQ(a.values.size(), b.values.size()) << b.name << ", stride " << strides[g];
      ASSERT_EQ(a.times, b.times) << b.name;
      const double
          vs = std::max(
              Eigen::Map<const Vec>(b.values.data(), b.values.size()).cwiseAbs().maxCoeff(), 1e-12),
          gs = std::max(b.gradient.cwiseAbs().maxCoeff(), 1e-12);
      for (size_t k = 0; k < b.values.size(); ++k)
        EXPECT_NEAR(a.values[k], b.values[k], 1e-6 * vs) << b.name << " step " << k;
      EXPECT_LT((a.gradient - b.gradient).cwiseAbs().maxCoeff(), 1e-5 * gs)
          << b.name << ", stride " << strides[g];
    }
  }
}

// Directional derivatives (DirectionalParameterization, verify's IDAS reference): IDAS along two
// combinations w_j of the 15 level-set variables of the flexible arm (their cut elements overlap:
// entries of one element merge) equals the per-variable IDAS gradient times W, for a grid
// response and a quadrature.
TEST(Idas, DirectionalSensitivitiesAreTheGradientAlongTheDirections) {
  json c = flexible_arm();
  c["output"]["responses"] = deviation_responses();
  Case cs = test::make_case(c);
  const SensitivityOptions o = tight_idas();
  const Vec p = cs.design->initial();
  const auto full = compute_sensitivities(cs, p, o);
  ASSERT_TRUE(full.ok) << full.message;
  Mat W(cs.design->size(), 2);
  for (Eigen::Index i = 0; i < W.rows(); ++i) {
    W(i, 0) = 0.01 * (1.0 + 0.3 * std::sin(1.0 + i));
    W(i, 1) = 0.01 * ((i % 3) - 1.0 + 0.5);
  }
  const auto dir = idas_on_grids(cs, p, o, cs.simulation.h, {1}, &W);
  ASSERT_TRUE(dir[0].ok) << dir[0].message;
  for (size_t r = 0; r < full.responses.size(); ++r) {
    const Mat expect = full.responses[r].gradient * W;
    const Mat& got = dir[0].responses[r].gradient;
    ASSERT_EQ(got.cols(), 2);
    const double e = (got - expect).cwiseAbs().maxCoeff() / expect.cwiseAbs().maxCoeff();
    std::printf("%s along W: %.8e %.8e (per-variable · W: %.8e %.8e), %.1e\n",
                full.responses[r].name.c_str(), got(0, 0), got(0, 1), expect(0, 0), expect(0, 1),
                e);
    EXPECT_LT(e, 1e-5) << full.responses[r].name;
  }
  ASSERT_EQ(dir[0].quadratures.size(), 1u);
  const Eigen::RowVectorXd eq = full.quadratures[0].gradient * W;
  EXPECT_LT((dir[0].quadratures[0].gradient - eq).cwiseAbs().maxCoeff(),
            1e-5 * eq.cwiseAbs().maxCoeff());
}

// The flexible arm with the level-set variables of its five holes: IDAS forward sensitivities
// (∂μ_e/∂p through ∂r/∂p of the elements the holes cut) against central differences of IDAS
// runs, for the final tip deviation (grid value) and its time integral (quadrature), ∂/∂ of the
// first hole's centre and semi-axes. A band of 2 sub-cells (ε = 8.8 mm on this 50 mm mesh)
// keeps μ_e(p) smooth on the scale of the difference step.
TEST(Idas, ForwardSensitivitiesOnLevelSetVariablesOfAFlexibleModelAgreeWithFiniteDifferences) {
  json c = flexible_arm();
  c["design"]["geometry"][0]["band"] = 2.0;
  c["output"]["responses"] = deviation_responses();
  Case cs = test::make_case(c);
  const SensitivityOptions o = tight_idas();
  const Vec p = cs.design->initial();
  const auto s = compute_sensitivities(cs, p, o);
  ASSERT_TRUE(s.ok) << s.message;
  ASSERT_EQ(s.quadratures.size(), 1u);
  // Differences of runs at rtol 1e-12 with an absolute step of 1e-5 m. Their truncation falls as
  // Δ² (for ∂/∂cx1, the largest: 5.2e-3 at 1e-4 m, 4.6e-4 at 3e-5 m, so ~5e-5 here); at rtol
  // 1e-10 the runs' step sequences put a noise of ~5e-3 on differences at this step, at 1e-11
  // ~1e-4.
  IdasOptions fd_io = o.idas;
  fd_io.rtol = 1e-12;
  fd_io.atol = 1e-15;
  const double h = 1e-5;
  double worst = 0;
  for (int i : {0, 1, 2}) {  // cx1, a1, b1
    const auto plus = idas_run_at(cs, p, i, h, fd_io), minus = idas_run_at(cs, p, i, -h, fd_io);
    ASSERT_TRUE(plus.integrator.ok && minus.integrator.ok);
    const double fd[2] = {
        (plus.responses.at("final_dev") - minus.responses.at("final_dev")) / (2 * h),
        (plus.quadratures[0].value - minus.quadratures[0].value) / (2 * h)};
    const double an[2] = {s.responses[0].gradient(0, i), s.quadratures[0].gradient[i]};
    for (int k = 0; k < 2; ++k) {
      const double e = std::abs(an[k] - fd[k]) / std::abs(fd[k]);
      std::printf("d %s / d %s: IDAS %.8e, FD of IDAS %.8e (%.1e)\n", k ? "int_dev" : "final_dev",
                  cs.design->variables[i].name.c_str(), an[k], fd[k], e);
      worst = std::max(worst, e);
    }
  }
  EXPECT_LT(worst, 2e-4);  // measured 5.7e-5
}

TEST(Idas, GeneralizedAlphaGradientsConvergeToIdasGradientsAtSecondOrder) {
  json c = spring_crank();
  Case ci = test::make_case(c);
  const SensitivityOptions oi = tight_idas();
  double d[3];
  const double h0 = 2e-3;
  std::vector<double> ref;
  for (int k = 0; k < 3; ++k) {
    c["simulation"]["h"] = h0 / (1 << k);
    Case cg = test::make_case(c);
    ci.simulation.h = h0;  // IDAS on the coarsest grid (the final value is compared)
    if (k == 0) {
      const auto si = compute_sensitivities(ci, ci.design->initial(), oi);
      ASSERT_TRUE(si.ok) << si.message;
      ref = {si.responses[0].gradient(0, 0), si.responses[0].gradient(0, 1)};  // final_crank_angle
    }
    SensitivityOptions og;
    og.method = SensitivityOptions::Method::kDirectAnalytic;
    og.matrix = SensitivityOptions::Matrix::kRefined;
    const auto sg = compute_sensitivities(cg, cg.design->initial(), og);
    d[k] = std::max(std::abs(sg.responses[0].gradient(0, 0) - ref[0]) / std::abs(ref[0]),
                    std::abs(sg.responses[0].gradient(0, 1) - ref[1]) / std::abs(ref[1]));
  }
  std::printf("d final_crank_angle / dp: |GA - IDAS| relative %.3e %.3e %.3e; ratios %.2f %.2f\n",
              d[0], d[1], d[2], d[0] / d[1], d[1] / d[2]);
  EXPECT_GT(d[0] / d[1], 3.5);
  EXPECT_LT(d[0] / d[1], 4.5);
  EXPECT_GT(d[1] / d[2], 3.5);
  EXPECT_LT(d[1] / d[2], 4.5);
}

// IDAS quadratures (IDAQuadInit) of a fully driven rigid slider-crank against the closed form:
// after the ramp the crank turns at ω, θ(t) = ω (t − T/2), and the piston is at
// x = r cos θ + sqrt(l² − r² sin² θ); ∫ x dt over a window that starts and ends between grid
// times (IDAS must stop there) is integrated by composite Simpson with 20,000 intervals.
TEST(Idas, QuadratureOfTheDrivenPistonMatchesTheClosedForm) {
  json c = json::parse(std::ifstream(std::string(LSMBS_SOURCE_DIR) +
                                     "/data/slider_crank_rigid/slider_crank_rigid.json"));
  const double a = 0.0153, b = 0.0391;
  c["output"]["responses"] = json::array({json{{"name", "int_x"},
                                               {"measure", "piston.x"},
                                               {"aggregate", "integral"},
                                               {"window", {{"t0", a}, {"t1", b}}}},
                                          json{{"name", "mean_x"},
                                               {"measure", "piston.x"},
                                               {"aggregate", "average"},
                                               {"window", {{"t0", a}, {"t1", b}}}},
                                          json{{"name", "rms_x"},
                                               {"measure", "piston.x"},
                                               {"aggregate", "rms"},
                                               {"window", {{"t0", a}, {"t1", b}}}}});
  Case cs = test::make_case(c);
  const auto r = run_idas(cs);
  ASSERT_TRUE(r.integrator.ok) << r.integrator.message;
  ASSERT_EQ(r.quadratures.size(), 3u);
  const double rc = 0.045, l = 0.1356, w = 418.87902047863906, T = 0.01;
  auto x = [&](double t) {
    const double th = w * (t - T / 2);
    return rc * std::cos(th) + std::sqrt(l * l - rc * rc * std::sin(th) * std::sin(th));
  };
  const int n = 20000;
  double s1 = 0, s2 = 0;
  for (int i = 0; i <= n; ++i) {
    const double t = a + (b - a) * i / n, wgt = (i == 0 || i == n) ? 1 : (i % 2 ? 4 : 2);
    s1 += wgt * x(t), s2 += wgt * x(t) * x(t);
  }
  s1 *= (b - a) / (3 * n), s2 *= (b - a) / (3 * n);
  const double expect[3] = {s1, s1 / (b - a), std::sqrt(s2 / (b - a))};
  for (int k = 0; k < 3; ++k) {
    const auto& q = r.quadratures[k];
    std::printf("%s: IDAS quadrature %.12e, closed form %.12e (%.1e), window [%g, %g]\n",
                q.name.c_str(), q.value, expect[k], std::abs(q.value / expect[k] - 1), q.t0, q.t1);
    EXPECT_NEAR(q.value / expect[k], 1.0, 1e-8) << q.name;
    EXPECT_DOUBLE_EQ(q.t0, a);
    EXPECT_DOUBLE_EQ(q.t1, b);
  }
}

// Quadrature sensitivities (IDAQuadSensInit) of the spring slider-crank's time-integral
// responses against central differences of IDAS quadrature values, and the generalized-α
// trapezoidal `energy_integral` gradient (direct-analytic) converging to them at second order.
TEST(Idas, QuadratureSensitivitiesMatchFiniteDifferencesAndGeneralizedAlpha) {
  json c = spring_crank();
  Case cs = test::make_case(c);
  const SensitivityOptions o = tight_idas();
  const Vec p = cs.design->initial();
  const auto s = compute_sensitivities(cs, p, o);
  ASSERT_TRUE(s.ok) << s.message;
  ASSERT_EQ(s.quadratures.size(), 2u);  // mean_piston_x (average), energy_integral (integral)
  double worst = 0;
  for (int i = 0; i < 2; ++i) {
    const double h = kFdStep * std::abs(p[i]);
    const auto plus = idas_run_at(cs, p, i, h, o.idas).quadratures,
               minus = idas_run_at(cs, p, i, -h, o.idas).quadratures;
    for (size_t k = 0; k < 2; ++k) {
      const double fd = (plus[k].value - minus[k].value) / (2 * h),
                   an = s.quadratures[k].gradient[i];
      const double e = std::abs(an - fd) / std::abs(fd);
      std::printf("d %s / d p%d (quadrature): IDAS %.8e, FD of IDAS %.8e (%.1e)\n",
                  s.quadratures[k].name.c_str(), i, an, fd, e);
      worst = std::max(worst, e);
    }
  }
  EXPECT_LT(worst, 1e-4);
  // generalized-α: trapezoidal integral of the energy on the grid, h0, h0/2, h0/4
  const Eigen::RowVectorXd ref = s.quadratures[1].gradient;
  double d[3];
  for (int k = 0; k < 3; ++k) {
    c["simulation"]["h"] = 2e-3 / (1 << k);
    Case cg = test::make_case(c);
    SensitivityOptions og;
    og.matrix = SensitivityOptions::Matrix::kRefined;
    const auto sg = compute_sensitivities(cg, cg.design->initial(), og);
    ASSERT_TRUE(sg.ok);
    d[k] = 0;
    for (const auto& rs : sg.responses)
      if (rs.name == "energy_integral")
        for (int i = 0; i < 2; ++i)
          d[k] = std::max(d[k], std::abs(rs.gradient(0, i) - ref[i]) / std::abs(ref[i]));
  }
  std::printf(
      "d energy_integral / dp: |GA trapezoid - IDAS quadrature| relative %.3e %.3e %.3e; ratios "
      "%.2f %.2f\n",
      d[0], d[1], d[2], d[0] / d[1], d[1] / d[2]);
  EXPECT_GT(d[0] / d[1], 3.5);
  EXPECT_LT(d[0] / d[1], 4.5);
  EXPECT_GT(d[1] / d[2], 3.5);
  EXPECT_LT(d[1] / d[2], 4.5);
}

// The flexible connecting rod (coarse mesh, gas load, speed ramp), which IDAS could not integrate
// before KLU's pivot tolerance was raised (0.001 → 1: the first Newton correction was wrong by
// 300×) and BDF limited to order 2 on flexible models (order 5 forced h = 5e-8 s). The reference
// preset must now complete the first 10 ms, and its elongation history must agree with
// generalized-α's. The two differ in the rod's high-frequency vibration, which the start
// excites and which generalized-α damps (ρ∞ = 0.8) and cannot resolve at any practical h
// (periods of a few µs): measured 1.9 % of the peak elongation over these 10 ms, and no
// improvement from h = 0.25 ms to 0.03 ms over 20 ms against IDAS at rtol 1e-10. The bound
// (5 %) checks the deformation history, not the vibration.
TEST(Idas, ReferencePresetIntegratesTheFlexibleConnectingRod) {
  const std::string dir = std::string(LSMBS_SOURCE_DIR) + "/data/slider_crank/";
  json c = json::parse(std::ifstream(dir + "slider_crank_1hole_coarse.json"));
  c["bodies"][2]["mesh"]["file"] = dir + "rod_coarse.msh";
  c["forces"][0]["table"]["file"] = dir + "pressure.csv";
  c["output"]["vtu_stride"] = 0;
  c["simulation"]["t_end"] = 0.01;
  c.erase("optimization");
  Case cs = test::make_case(c);
  const auto ri = run_idas(cs);
  ASSERT_TRUE(ri.integrator.ok) << ri.integrator.message;
  EXPECT_EQ(ri.idas.max_order, 2);
  const auto rg = run_simulation(cs, RunOptions{});
  ASSERT_TRUE(rg.integrator.ok);
  const auto& ei = ri.column("elongation");
  const auto& eg = rg.column("elongation");
  ASSERT_EQ(ei.size(), eg.size());
  double dev = 0, peak = 0;
  for (size_t k = 0; k < ei.size(); ++k)
    dev = std::max(dev, std::abs(ei[k] - eg[k])), peak = std::max(peak, std::abs(ei[k]));
  std::printf(
      "coarse rod, 10 ms: IDAS %ld steps, %ld Jacobians; max |elongation GA - IDAS| = %.3e of the "
      "peak %.3e m\n",
      ri.idas.steps, ri.idas.jacobian_evaluations, dev / peak, peak);
  EXPECT_GT(peak, 1e-6);
  EXPECT_LT(dev / peak, 5e-2);
}

// Out-of-range IDAS options are refused with a message naming the option (no silent clamp).
TEST(Idas, RefusesOutOfRangeOrderAndPivotTolerance) {
  Case cs = test::make_case(spring_crank());
  for (int k = 0; k < 2; ++k) {
    IdasOptions io;
    if (k == 0)
      io.max_order = 6;
    else
      io.klu_pivot_tolerance = 0;
    const auto r = run_idas(cs, io);
    EXPECT_FALSE(r.integrator.ok);
    EXPECT_NE(r.integrator.message.find(k == 0 ? "max_order" : "klu_pivot_tolerance"),
              std::string::npos)
        << r.integrator.message;
  }
}

// ---- adjoint sensitivities (IDAAdjInit, IDASolveB, IDAQuadInitB): issue 5's stretch.
namespace {

// Gradients of the case's IDAS quadratures by the forward and by the adjoint path at the same
// tolerances; returns the largest relative difference over all quadratures and variables.
double adjoint_against_forward(Case& cs, const IdasOptions& io, long expect_backward_problems) {
  SensitivityOptions o;
  o.idas = io;
  o.method = SensitivityOptions::Method::kIdas;
  const auto fwd = compute_sensitivities(cs, cs.design->initial(), o);
  o.method = SensitivityOptions::Method::kIdasAdjoint;
  const auto adj = compute_sensitivities(cs, cs.design->initial(), o);
  EXPECT_TRUE(fwd.ok) << fwd.message;
  EXPECT_TRUE(adj.ok) << adj.message;
  EXPECT_EQ(adj.idas.adjoint_problems, expect_backward_problems);
  EXPECT_EQ(fwd.quadratures.size(), adj.quadratures.size());
  double worst = 0;
  for (size_t k = 0; k < fwd.quadratures.size() && k < adj.quadratures.size(); ++k) {
    const auto& f = fwd.quadratures[k];
    const auto& a = adj.quadratures[k];
    // same quantity; the runs differ in their steps (the adjoint's forward pass has no stop times
    // and no sensitivity error test): measured 2.5e-7 at rtol 1e-10 on the flexible arm
    EXPECT_NEAR(a.value, f.value, 1e-6 * std::abs(f.value)) << f.name;
    const double e =
        (a.gradient - f.gradient).lpNorm<Eigen::Infinity>() / f.gradient.lpNorm<Eigen::Infinity>();
    std::printf("d %s / dp (%ld variables): adjoint vs forward %.2e (|grad| %.3e)\n",
                f.name.c_str(), static_cast<long>(f.gradient.size()), e,
                f.gradient.lpNorm<Eigen::Infinity>());
    worst = std::max(worst, e);
  }
  for (const auto& r : adj.responses)  // the grid aggregates are not differentiated by the adjoint
    EXPECT_TRUE(r.gradient.hasNaN()) << r.name;
  std::printf(
      "forward: %ld steps, %.2f s; adjoint: %ld forward + %ld backward steps in %ld problems, %.2f "
      "s\n",
      fwd.idas.steps, fwd.idas.wall_seconds, adj.idas.steps, adj.idas.adjoint_steps,
      adj.idas.adjoint_problems, adj.idas.wall_seconds);
  return worst;
}

}  // namespace

// Rigid slider-crank with a damped spring (design: stiffness, damping): the averaged piston
// position (whole run, a window [0.1, 0.2] inside it, an rms from 0.05 to the end) and the time
// integral of the kinetic energy, which depends on the velocities and on the masses, and whose
// connecting rod has an offset centre of mass (M(q): the adjoint's Ṁ ξ_v term; without it the
// gradients were off by up to 6 %).
TEST(IdasAdjoint, GradientsOfTimeIntegralsAgreeWithForwardSensitivitiesOnTheSpringCrank) {
  json c = spring_crank();
  c["output"]["responses"] = json::array(
      {json{{"name", "mean_x"}, {"measure", "piston.x"}, {"aggregate", "average"}},
       json{{"name", "energy_integral"}, {"measure", "energy"}, {"aggregate", "integral"}},
       json{{"name", "mean_x_window"},
            {"measure", "piston.x"},
            {"aggregate", "average"},
            {"window", {{"t0", 0.1}, {"t1", 0.2}}}},
       json{{"name", "rms_x"},
            {"measure", "piston.x"},
            {"aggregate", "rms"},
            {"window", {{"t0", 0.05}, {"t1", 0.25}}}}});
  Case cs = test::make_case(c);
  // both at rtol 1e-10; the runs differ in their steps (see adjoint_against_forward): measured
  // 4.1e-8, bound 1e-7
  EXPECT_LT(adjoint_against_forward(cs, tight_idas().idas, 6), 1e-7);  // window ends: 1 + 1 + 2 + 2
}

// The flexible arm (12 × 2 mesh, 15 design variables of the holes): the average tip deviation
// over [0.02, 0.09] s and its integral over the run. Three backward problems (two window ends and
// the final time) give the 2 × 15 gradients.
TEST(IdasAdjoint, GradientsAgreeWithForwardSensitivitiesOnAFlexibleArm) {
  json c = flexible_arm();
  c["output"]["responses"] = json::array(
      {json{{"name", "avg_dev"},
            {"measure", "tip_deviation"},
            {"aggregate", "average"},
            {"window", {{"t0", 0.02}, {"t1", 0.09}}}},
       json{{"name", "int_dev"}, {"measure", "tip_deviation"}, {"aggregate", "integral"}}});
  Case cs = test::make_case(c);
  IdasOptions io = IdasOptions::reference();
  io.rtol = io.atol = 1e-10;
  // Checkpoints every 25 steps (default 200): IDASolveB recomputes the forward steps between
  // checkpoints into a fixed array and must repeat them exactly (KLU re-analyzed at every
  // Jacobian; with SUNLinSol_KLU's history-dependent pivots the full robot arm crashed inside
  // IDASolveB — this small model did not).
  io.adjoint_checkpoint_steps = 25;
  // the error test on positions only (flexible models) leaves the velocities, which the adjoint
  // integrates backwards, less accurate: measured 4.9e-6 at rtol 1e-10
  EXPECT_LT(adjoint_against_forward(cs, io, 3), 1e-5);
}

// A case without time-integral responses is refused with the JSON path; an integrand of a
// constraint force (a multiplier: not supported by the adjoint's final values) fails the run
// with a message naming the response.
TEST(IdasAdjoint, RefusesResponsesItCannotDifferentiate) {
  json c = spring_crank();
  SensitivityOptions o;
  o.method = SensitivityOptions::Method::kIdasAdjoint;
  c["output"]["responses"] =
      json::array({json{{"name", "final_x"}, {"measure", "piston.x"}, {"aggregate", "final"}}});
  {
    Case cs = test::make_case(c);
    try {
      compute_sensitivities(cs, cs.design->initial(), o);
      ADD_FAILURE() << "no time-integral response: expected an Error";
    } catch (const SetupError& e) {  // by name; the command line locates it in the case file
      EXPECT_EQ(e.subject(), "responses") << e.what();
      EXPECT_EQ(locate("c.json", e).json_path(), "/output/responses");
    }
  }
  c["output"]["responses"] = json::array({json{
      {"name", "mean_side_force"}, {"measure", "cylinder_force.0"}, {"aggregate", "average"}}});
  Case cs = test::make_case(c);
  const auto r = compute_sensitivities(cs, cs.design->initial(), o);
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.message.find("mean_side_force"), std::string::npos) << r.message;
  EXPECT_NE(r.message.find("constraint forces"), std::string::npos) << r.message;
}
