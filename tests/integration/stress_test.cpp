// The stress measure (StressMeasure, measure.hpp; issue 25) against independent references:
//  * a homogeneous uniaxial stretch of the robot arm's plate: every element's Cauchy von Mises
//    stress is the closed form of St Venant–Kirchhoff plane stress, the relaxation multiplies it
//    by μ^q, and the KS and p-norm aggregates of N equal values are s + σ_ref ln(N)/ρ and
//    N^(1/P) s; a rigid rotation of the stretched plate changes nothing (objectivity);
//  * ∂f/∂q and ∂f/∂μ_e against central differences of the measure on a random deformed state
//    with random densities (KS and p-norm);
//  * design gradients of stress responses on the robot arm with level-set holes (elements cut by
//    the features' boundaries) by direct-analytic, the discrete adjoint, semi-analytical-central
//    against central differences of whole re-simulations, and IDAS against central differences of
//    IDAS runs.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <random>

#include "lsmbs/core/error.hpp"
#include "lsmbs/responses/measure.hpp"
#include "lsmbs/runs/simulate.hpp"
#include "support/gradients.hpp"
#include "support/test_models.hpp"

using namespace lsmbs;
using json = nlohmann::json;
using Method = SensitivityOptions::Method;

namespace {

json robot_arm_json() {
  json c = json::parse(
      std::ifstream(std::string(LSMBS_SOURCE_DIR) + "/data/robot_arm/robot_arm_holes.json"));
  c["bodies"][2]["mesh"]["elements"] = {60, 5};
  c["design"]["geometry"][0]["band"] = 2.0;
  c["simulation"]["t_end"] = 0.3;
  c["simulation"]["tol_r"] = 1e-11;
  c["output"]["vtu_stride"] = 0;
  c["output"]["measures"].push_back({{"name", "plate_ks"},
                                     {"type", "stress"},
                                     {"body", "plate"},
                                     {"reference", 1e8},
                                     {"parameter", 20}});
  c["output"]["measures"].push_back({{"name", "plate_pnorm"},
                                     {"type", "stress"},
                                     {"body", "plate"},
                                     {"aggregate", "pnorm"},
                                     {"parameter", 6},
                                     {"relaxation", 0.7}});
  c["output"]["responses"] = json::parse(R"([
    {"name": "mean_ks_stress", "measure": "plate_ks", "aggregate": "average", "window": {"t0": 0.1, "t1": 0.3}},
    {"name": "ks_ks_stress", "measure": "plate_ks", "aggregate": "ks", "ks": 1e-5},
    {"name": "final_pnorm_stress", "measure": "plate_pnorm", "aggregate": "final"}
  ])");
  return c;
}

const StressMeasure& stress_measure(const Case& cs, const std::string& name) {
  for (const auto& m : cs.measures)
    if (m->name() == name) return dynamic_cast<const StressMeasure&>(*m);
  throw std::runtime_error("no measure " + name);
}

// The plate's nodes at x = origin + R(θ) (R0 diag(λ, 1) X_mesh): stretched by λ along the
// body's x axis, then rotated rigidly by θ.
State stretched(const Case& cs, const FlexibleBody& b, double lambda, double theta) {
  State s = cs.initial;
  const Mat2 R0 = rotation(b.angle), R = rotation(theta);
  for (int n = 0; n < b.mesh.num_nodes(); ++n) {
    const Vec2 X = b.mesh.nodes[n];
    s.q.segment<2>(b.node_dof(n)) = b.origin + R * (R0 * Vec2(lambda * X.x(), X.y()));
  }
  return s;
}

}  // namespace

TEST(Stress, UniaxialStretchIsTheClosedFormAndObjective) {
  Case cs = test::make_case(robot_arm_json());
  const StressMeasure& ks = stress_measure(cs, "plate_ks");
  const StressMeasure& pn = stress_measure(cs, "plate_pnorm");
  const FlexibleBody& b = *ks.flexible();
  ModelParams p = cs.model->params();
  const double E0 = p.scalars[b.E_param], nu = p.scalars[b.nu_param], lambda = 1.001;
  for (auto& mu : p.fields[b.field]) mu = 0.25;
  // closed form: E11 = (λ² − 1)/2, S11 = c E11, S22 = ν c E11, σ11 = λ S11, σ22 = S22/λ
  const double c = E0 / (1 - nu * nu), E11 = (lambda * lambda - 1) / 2;
  const double s11 = lambda * c * E11, s22 = nu * c * E11 / lambda;
  const double vm = std::sqrt(s11 * s11 - s11 * s22 + s22 * s22);
  const double N = static_cast<double>(b.elements.size());
  for (double theta : {0.0, 0.7}) {
    const State s = stretched(cs, b, lambda, theta);
    std::vector<double> se;
    ks.element_stresses(s, p, se);
    for (double v : se) ASSERT_NEAR(v, std::sqrt(0.25) * vm, 1e-9 * vm) << "q = 0.5";
    pn.element_stresses(s, p, se);
    for (double v : se) ASSERT_NEAR(v, std::pow(0.25, 0.7) * vm, 1e-9 * vm) << "q = 0.7";
    double f = 0;
    ks.evaluate(*cs.model, s, p, &f);
    EXPECT_NEAR(f, 0.5 * vm + 1e8 * std::log(N) / 20, 1e-9 * vm);
    pn.evaluate(*cs.model, s, p, &f);
    EXPECT_NEAR(f, std::pow(N, 1.0 / 6) * std::pow(0.25, 0.7) * vm, 1e-9 * vm);
  }
}

TEST(Stress, PartialDerivativesAreTheCentralDifferences) {
  Case cs = test::make_case(robot_arm_json());
  const FlexibleBody& b = *stress_measure(cs, "plate_ks").flexible();
  std::mt19937 gen(7);
  std::uniform_real_distribution<double> u(-1, 1);
  ModelParams p = cs.model->params();
  for (auto& mu : p.fields[b.field]) mu = 0.55 + 0.45 * u(gen);
  State s = stretched(cs, b, 1.0005, 0.3);
  for (int n = 0; n < b.mesh.num_nodes(); ++n)  // a random strain of order 1e-4
    s.q.segment<2>(b.node_dof(n)) += 2e-4 * 0.005 * Vec2(u(gen), u(gen));
  for (const char* name : {"plate_ks", "plate_pnorm"}) {
    const StressMeasure& m = stress_measure(cs, name);
    MeasureGradient g;
    m.gradient(*cs.model, s, p, 0, g);
    Vec dq = Vec::Zero(s.q.size());
    for (const auto& [j, w] : g.dq) dq[j] += w;
    int field = -1;
    Vec dmu;
    ASSERT_TRUE(m.field_partials(*cs.model, s, p, 0, field, dmu));
    ASSERT_EQ(field, b.field);
    double scale_q = dq.lpNorm<Eigen::Infinity>(), worst_q = 0, worst_mu = 0;
    const double scale_mu = dmu.lpNorm<Eigen::Infinity>();
    ASSERT_GT(scale_q, 0);
    ASSERT_GT(scale_mu, 0);
    auto f_at = [&](const State& st, const ModelParams& pp) {
      double f = 0;
      m.evaluate(*cs.model, st, pp, &f);
      return f;
    };
    // the 20 largest entries (the KS weights concentrate on the most stressed elements) and 20
    // spread over the plate
    std::vector<int> qs, es;
    for (int k = 0; k < 20; ++k) qs.push_back(b.dof0 + (k * 97) % (2 * b.mesh.num_nodes()));
    for (int k = 0; k < 20; ++k) es.push_back((k * 31) % static_cast<int>(b.elements.size()));
    {
      std::vector<int> idx(dq.size()), ide(dmu.size());
      for (size_t i = 0; i < idx.size(); ++i) idx[i] = static_cast<int>(i);
      for (size_t i = 0; i < ide.size(); ++i) ide[i] = static_cast<int>(i);
      std::partial_sort(idx.begin(), idx.begin() + 20, idx.end(),
                        [&](int a, int c) { return std::abs(dq[a]) > std::abs(dq[c]); });
      std::partial_sort(ide.begin(), ide.begin() + 20, ide.end(),
                        [&](int a, int c) { return std::abs(dmu[a]) > std::abs(dmu[c]); });
      qs.insert(qs.end(), idx.begin(), idx.begin() + 20);
      es.insert(es.end(), ide.begin(), ide.begin() + 20);
    }
    for (int j : qs) {
      const double h = 1e-9;
      State sp = s, sm = s;
      sp.q[j] += h;
      sm.q[j] -= h;
      const double fd = (f_at(sp, p) - f_at(sm, p)) / (2 * h);
      worst_q = std::max(worst_q, std::abs(fd - dq[j]) / scale_q);
    }
    for (int e : es) {
      const double h = 1e-6;
      ModelParams pp = p, pm = p;
      pp.fields[field][e] += h;
      pm.fields[field][e] -= h;
      const double fd = (f_at(s, pp) - f_at(s, pm)) / (2 * h);
      worst_mu = std::max(worst_mu, std::abs(fd - dmu[e]) / scale_mu);
    }
    std::printf("%s: df/dq vs central differences %.2e, df/dmu %.2e (of the largest entry)\n", name,
                worst_q, worst_mu);
    EXPECT_LT(worst_q, 1e-6);
    EXPECT_LT(worst_mu, 1e-7);
  }
}

TEST(Stress, DesignGradientsOfEveryMethodMatchCentralDifferences) {
  Case cs = test::make_case(robot_arm_json());
  cs.simulation.min_iter = 3;  // re-simulations converged far below their differences
  ASSERT_EQ(cs.design->size(), 15);
  auto run = [&](Method m, double delta) {
    SensitivityOptions o;
    o.method = m;
    o.delta = delta;
    o.relative = m != Method::kFdCentral;  // fd: absolute 1e-5 m (lengths; band 2.5 mm)
    auto r = compute_sensitivities(cs, cs.design->initial(), o);
    EXPECT_TRUE(r.ok) << r.message;
    return r;
  };
  const auto fd = run(Method::kFdCentral, 1e-5);
  for (Method m : {Method::kDirectAnalytic, Method::kAdjoint, Method::kSemiAnalyticalCentral}) {
    const auto r = run(m, 1e-6);
    std::string w;
    const double e = test::worst_relative(r, fd, test::Norm::kPerValue, &w);
    std::printf("stress responses, %s vs fd-central: %.2e (%s)\n", SensitivityOptions::name(m), e,
                w.c_str());
    // fd-central's Δp² truncation against the 2.5 mm band dominates (sensitivity_test)
    EXPECT_LT(e, 1e-5) << SensitivityOptions::name(m);
  }
}

TEST(Stress, IdasGradientsMatchCentralDifferencesOfIdasRuns) {
  // IDAS integrates another discretization (BDF on the GGL form): its gradients are checked
  // against central differences of IDAS runs at a tighter tolerance
  // time integrals of the stress measures: an instantaneous stress carries the plate's highest
  // modes, which BDF resolves differently at each tolerance (final values at rtol 1e-10 and
  // 1e-12 differ in the third digit of their gradient); the integrals do not
  json c = robot_arm_json();
  c["simulation"]["t_end"] = 0.1;
  c["output"]["responses"] = json::parse(R"([
    {"name": "int_ks_stress", "measure": "plate_ks", "aggregate": "integral"},
    {"name": "int_pnorm_stress", "measure": "plate_pnorm", "aggregate": "integral"}
  ])");
  Case cs = test::make_case(c);
  SensitivityOptions o;
  o.method = Method::kIdas;
  o.idas.rtol = 1e-10;
  o.idas.atol = 1e-13;
  const Vec p = cs.design->initial();
  const auto s = compute_sensitivities(cs, p, o);
  ASSERT_TRUE(s.ok) << s.message;
  IdasOptions fd_io = o.idas;
  fd_io.rtol = 1e-12;
  fd_io.atol = 1e-15;
  auto at = [&](int i, double dp) {
    Vec pp = p;
    pp[i] += dp;
    cs.design->apply(pp, cs.model->params());
    RunOptions ro;
    ro.idas = true;
    ro.idas_options = fd_io;
    auto res = run_simulation(cs, ro);
    cs.design->apply(p, cs.model->params());
    EXPECT_TRUE(res.integrator.ok);
    return res;
  };
  const double h = 1e-5;
  double worst = 0;
  for (int i : {0, 1}) {  // c_x1, a1: their derivatives live in the elements the boundary cuts
    const auto plus = at(i, h), minus = at(i, -h);
    for (size_t r = 0; r < s.responses.size(); ++r) {
      const std::string& name = s.responses[r].name;
      const double fd = (plus.responses.at(name) - minus.responses.at(name)) / (2 * h);
      const double an = s.responses[r].gradient(0, i);
      const double e = std::abs(an - fd) / std::abs(fd);
      std::printf("d %s / d %s: IDAS %.8e, FD of IDAS %.8e (%.1e)\n", name.c_str(),
                  cs.design->variables[i].name.c_str(), an, fd, e);
      worst = std::max(worst, e);
    }
  }
  EXPECT_LT(worst, 1e-3);
}

TEST(Stress, InputErrorsNameTheJsonPathAndWhatWasExpected) {
  struct Bad {
    json measure;
    const char* path;
    const char* phrase;
  };
  const Bad bad[] = {
      {{{"name", "s"}, {"type", "stress"}, {"body", "plate"}}, "/output/measures/5", "reference"},
      {{{"name", "s"}, {"type", "stress"}, {"body", "arm1"}, {"reference", 1e8}},
       "/output/measures/5/body",
       "flexible"},
      {{{"name", "s"},
        {"type", "stress"},
        {"body", "plate"},
        {"reference", 1e8},
        {"relaxation", 1.5}},
       "/output/measures/5/relaxation",
       "(0, 1]"},
      {{{"name", "s"},
        {"type", "stress"},
        {"body", "plate"},
        {"aggregate", "pnorm"},
        {"parameter", 0.5}},
       "/output/measures/5/parameter",
       ">= 1"},
      {{{"name", "s"},
        {"type", "stress"},
        {"body", "plate"},
        {"aggregate", "max"},
        {"reference", 1e8}},
       "/output/measures/5/aggregate",
       "expected one of"},
  };
  for (const auto& b : bad) {
    json c = json::parse(
        std::ifstream(std::string(LSMBS_SOURCE_DIR) + "/data/robot_arm/robot_arm_holes.json"));
    ASSERT_EQ(c["output"]["measures"].size(), 5u);
    c["output"]["measures"].push_back(b.measure);
    try {
      test::make_case(c);
      ADD_FAILURE() << "accepted: " << b.measure.dump();
    } catch (const Error& e) {
      const std::string msg = e.what();
      std::printf("  %s\n", msg.c_str());
      EXPECT_NE(msg.find(b.path), std::string::npos) << msg;
      EXPECT_NE(msg.find(b.phrase), std::string::npos) << msg;
    }
  }
}

// The KS aggregate's documented bounds, max_e s_e ≤ f ≤ max_e s_e + σ_ref ln(N)/ρ, for any
// positive reference. With σ_ref = 1e-300 the normalized stresses s_e/σ_ref of elements above
// 1.8e8 Pa overflowed: inf − inf gave NaN (a response's max over the steps skipped those steps,
// and reported 1.67e8 Pa against an element maximum of 2.93e8). The bounds are checked against
// the element stresses themselves, and ∂f/∂q against central differences, from 1e-320 (a
// subnormal reference) to 1e300.
TEST(Stress, KsBoundsAndDerivativesHoldForEveryPositiveReference) {
  Case cs = test::make_case(robot_arm_json());
  const StressMeasure& base = stress_measure(cs, "plate_ks");
  const FlexibleBody& b = *base.flexible();
  std::mt19937 gen(11);
  std::uniform_real_distribution<double> u(-1, 1);
  ModelParams p = cs.model->params();
  for (auto& mu : p.fields[b.field]) mu = 0.55 + 0.45 * u(gen);
  State s = stretched(cs, b, 1.005, 0.3);  // σ of order 3e8 Pa: above 1.8e8 in many elements
  for (int n = 0; n < b.mesh.num_nodes(); ++n)
    s.q.segment<2>(b.node_dof(n)) += 1e-3 * 0.005 * Vec2(u(gen), u(gen));
  std::vector<double> se;
  base.element_stresses(s, p, se);
  const double smax = *std::max_element(se.begin(), se.end());
  const double N = static_cast<double>(se.size());
  ASSERT_GT(smax, 1.8e8);
  for (double rho : {20.0, 1e4})
    for (double ref : {1e-320, 1e-305, 1e-300, 1e-200, 1.0, 1e8, 1e200, 1e300}) {
      StressMeasure::Options o = base.options();
      o.reference = ref;
      o.parameter = rho;
      const StressMeasure m("ks", &b, o);
      double f = 0;
      m.evaluate(*cs.model, s, p, &f);
      const double upper = smax + ref * std::log(N) / rho;
      ASSERT_TRUE(std::isfinite(f)) << "reference " << ref << ", ρ " << rho;
      EXPECT_GE(f, smax * (1 - 4e-16)) << "reference " << ref << ", ρ " << rho;
      EXPECT_LE(f, upper * (1 + 4e-16)) << "reference " << ref << ", ρ " << rho;
      // ∂f/∂q: the largest entries and a spread, against central differences
      MeasureGradient g;
      m.gradient(*cs.model, s, p, 0, g);
      Vec dq = Vec::Zero(s.q.size());
      for (const auto& [j, w] : g.dq) dq[j] += w;
      ASSERT_TRUE(dq.allFinite()) << "reference " << ref;
      const double scale = dq.lpNorm<Eigen::Infinity>();
      ASSERT_GT(scale, 0);
      std::vector<int> idx(static_cast<size_t>(dq.size()));
      for (size_t i = 0; i < idx.size(); ++i) idx[i] = static_cast<int>(i);
      std::partial_sort(idx.begin(), idx.begin() + 10, idx.end(),
                        [&](int a, int c) { return std::abs(dq[a]) > std::abs(dq[c]); });
      idx.resize(10);
      for (int k = 0; k < 10; ++k) idx.push_back(b.dof0 + (k * 97) % (2 * b.mesh.num_nodes()));
      double worst = 0;
      if (upper < 1e6 * smax) {  // f's round-off leaves its central differences meaningful
        for (int j : idx) {
          const double h = 1e-10;
          State sp = s, sm = s;
          sp.q[j] += h;
          sm.q[j] -= h;
          double fp = 0, fm = 0;
          m.evaluate(*cs.model, sp, p, &fp);
          m.evaluate(*cs.model, sm, p, &fm);
          worst = std::max(worst, std::abs((fp - fm) / (2 * h) - dq[j]) / scale);
        }
      } else {  // σ_ref far above the stresses: every weight is 1/N to ρ (max − min)/σ_ref, and
                // ∂f/∂q is the mean of the elements' ∂s_e/∂q: the p-norm with P = 1 (Σ s_e) / N
        StressMeasure::Options sum_options = base.options();
        sum_options.aggregation = StressMeasure::Aggregation::kPNorm;
        sum_options.parameter = 1;
        MeasureGradient gs;
        StressMeasure("sum", &b, sum_options).gradient(*cs.model, s, p, 0, gs);
        Vec mean = Vec::Zero(s.q.size());
        for (const auto& [j, w] : gs.dq) mean[j] += w / N;
        worst = (dq - mean).lpNorm<Eigen::Infinity>() / scale;
      }
      std::printf("ρ %g, σ_ref %g: f − max = %.3e (bound %.3e), ∂f/∂q vs its reference %.2e\n", rho,
                  ref, f - smax, upper - smax, worst);
      EXPECT_LT(worst, 1e-5) << "reference " << ref << ", ρ " << rho;
    }
}
