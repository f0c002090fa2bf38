// Methods that had no test: the fd-forward sensitivity method, the NLopt ccsaq and slsqp
// optimizers (and mma), the move limit of mma-svanberg, and the files the command line writes
// (gradients.csv, summary.json) against the library's result.
//
// The problem has closed forms. Four free rigid bodies, no gravity, no joints, t ∈ [0, 1]:
//   A (mass m1) and B (mass m2) coast at 2^½ and 2 m/s: kinetic energy m1 + 2 m2;
//   C (mass m1) and D (mass m2) start 1 m apart at rest and are pushed apart by 1 N each:
//   their separation grows by e = ½ (1/m1 + 1/m2) at t = 1, their kinetic energy is ½ (1/m1 +
//   1/m2).
// Constant forces give constant accelerations, which generalized-α integrates exactly (a quadratic
// in t from consistent start accelerations), so the discrete responses are the closed forms to
// round-off:  energy E = m1 + 2 m2 + ½ (1/m1 + 1/m2),  spread e = ½ (1/m1 + 1/m2).
// Minimize E subject to e ≤ ½ (i.e. 1/m1 + 1/m2 ≤ 1), m ∈ [0.5, 10]: on the active constraint the
// energy's second term is the constant ½, and the KKT conditions give m1 = 1 + √2,
// m2 = m1/√2, E* = 3 + 2√2 + ½ with multiplier m1² − ½ > 0.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "lsmbs/io/optimization_spec.hpp"
#include "lsmbs/optimization/optimizer.hpp"
#include "lsmbs/sensitivity/sensitivity.hpp"
#include "support/test_models.hpp"

using namespace lsmbs;
using json = nlohmann::json;

namespace {

const double kM1 = 1 + std::sqrt(2.0), kM2 = kM1 / std::sqrt(2.0),
             kE = 3 + 2 * std::sqrt(2.0) + 0.5;

json coasting_bodies(const std::string& optimizer) {
  json j = R"({
    "name": "coasting_bodies",
    "bodies": [
      {"name": "A", "type": "rigid", "position": [0, 0], "mass": 5, "inertia": 1, "velocity": [1.4142135623730951, 0]},
      {"name": "B", "type": "rigid", "position": [0, 2], "mass": 5, "inertia": 1, "velocity": [2, 0]},
      {"name": "C", "type": "rigid", "position": [-0.5, 5], "mass": 5, "inertia": 1},
      {"name": "D", "type": "rigid", "position": [0.5, 5], "mass": 5, "inertia": 1}
    ],
    "forces": [
      {"name": "push_C", "type": "point_force", "point": {"body": "C"}, "force": [-1, 0]},
      {"name": "push_D", "type": "point_force", "point": {"body": "D"}, "force": [1, 0]}
    ],
    "simulation": {"t_end": 1, "h": 0.1, "tol_r": 1e-12},
    "output": {
      "measures": [{"name": "energy", "type": "kinetic_energy"},
                   {"name": "spread", "type": "elongation", "a": {"body": "C"}, "b": {"body": "D"}}],
      "responses": [{"name": "energy", "measure": "energy", "aggregate": "final"},
                    {"name": "spread", "measure": "spread", "aggregate": "final"}]
    },
    "design": {
      "variables": [{"name": "m1", "initial": 5, "lower": 0.5, "upper": 10},
                    {"name": "m2", "initial": 5, "lower": 0.5, "upper": 10}],
      "parameters": [{"parameter": "A.mass", "variable": "m1"}, {"parameter": "C.mass", "variable": "m1"},
                     {"parameter": "B.mass", "variable": "m2"}, {"parameter": "D.mass", "variable": "m2"}]
    },
    "optimization": {
      "objective": "energy",
      "constraints": [{"response": "spread", "upper": 0.5}],
      "stop": {"relative_objective_change": 1e-9, "relative_constraint_violation": 1e-8, "max_evaluations": 200}
    }
  })"_json;
  j["optimization"]["optimizer"] = optimizer;
  return j;
}

double energy(double m1, double m2) { return m1 + 2 * m2 + 0.5 * (1 / m1 + 1 / m2); }
double spread(double m1, double m2) { return 0.5 * (1 / m1 + 1 / m2); }

struct OptRun {
  std::unique_ptr<Case> cs;
  std::unique_ptr<DesignProblem> prob;
  OptimizeResult res;
};

OptRun optimize_case(const json& j) {
  OptRun r;
  r.cs = std::make_unique<Case>(test::make_case(j));
  r.prob = std::make_unique<DesignProblem>(*r.cs, parse_optimization(*r.cs));
  OptimizeOptions o;  // no output folder
  r.res = optimize(*r.prob, o);
  return r;
}

}  // namespace

TEST(MethodsCoverage, ResponsesOfTheCoastingBodiesAreTheClosedForms) {
  Case cs = test::make_case(coasting_bodies("mma"));
  SensitivityOptions o;
  o.method = SensitivityOptions::Method::kDirectAnalytic;
  const Vec p = (Vec(2) << 2.0, 3.0).finished();
  const auto res = compute_sensitivities(cs, p, o);
  ASSERT_TRUE(res.ok) << res.message;
  const auto& E = res.responses[0];
  const auto& e = res.responses[1];
  std::printf("E = %.17g (closed form %.17g), e = %.17g (%.17g)\n", E.values[0], energy(2, 3),
              e.values[0], spread(2, 3));
  // 10 exact steps: round-off of sums of O(1) numbers
  EXPECT_NEAR(E.values[0], energy(2, 3), 1e-13);
  EXPECT_NEAR(e.values[0], spread(2, 3), 1e-14);
  // dE/dm_i = (1, 2) − ½/m_i², de/dm_i = −½/m_i²; the direct method differentiates the discrete
  // solution, which is the closed form: round-off only. The kinetic energy's explicit ∂T/∂m is a
  // central difference with a relative step of 1e-6 (exact for T linear in m, round-off
  // ε |T| / (1e-6 m) ≈ 1e-9), hence 1e-8 on dE/dm.
  EXPECT_NEAR(E.gradient(0, 0), 1 - 0.5 / 4, 1e-8);
  EXPECT_NEAR(E.gradient(0, 1), 2 - 0.5 / 9, 1e-8);
  EXPECT_NEAR(e.gradient(0, 0), -0.5 / 4, 1e-12);
  EXPECT_NEAR(e.gradient(0, 1), -0.5 / 9, 1e-12);
}

TEST(MethodsCoverage, FdForwardIsTheForwardDifferenceWithItsTruncationError) {
  // With a relative step δ = 1e-4, Δm_i = δ m_i. For e = ½/m1 + …, the forward difference is
  // exactly −½/(m (m + Δm)): its error against de/dm = −½/m² is the truncation ½ e'' Δm = Δm/m
  // relative (1e-4 here, far above round-off ε|e|/Δm ≈ 1e-12 relative). fd-central's error is
  // O(Δm²) instead: −½/((m + Δm)(m − Δm)) exactly.
  Case cs = test::make_case(coasting_bodies("mma"));
  const Vec p = (Vec(2) << 2.0, 3.0).finished();
  SensitivityOptions o;
  o.delta = 1e-4;
  o.relative = true;
  o.method = SensitivityOptions::Method::kFdForward;
  const auto fwd = compute_sensitivities(cs, p, o);
  o.method = SensitivityOptions::Method::kFdCentral;
  const auto ctr = compute_sensitivities(cs, p, o);
  ASSERT_TRUE(fwd.ok && ctr.ok);
  EXPECT_EQ(fwd.counts.simulations, 3) << "one base run and one per variable";
  EXPECT_EQ(ctr.counts.simulations, 5);
  for (int i = 0; i < 2; ++i) {
    const double m = p[i], dm = o.step(*cs.design, p, i);
    ASSERT_NEAR(dm, 1e-4 * m, 1e-18);
    const double exact = -0.5 / (m * m), forward = -0.5 / (m * (m + dm)),
                 central = -0.5 / ((m + dm) * (m - dm));
    // round-off of a difference quotient of values known to ~1e-15: 1e-15 / Δm ≈ 5e-12
    const double tol = 1e-14 / dm;
    std::printf(
        "m%d: fd-forward %.15e (forward difference %.15e, derivative %.15e: truncation %.3e "
        "relative); "
        "fd-central %.15e\n",
        i + 1, fwd.responses[1].gradient(0, i), forward, exact, forward / exact - 1,
        ctr.responses[1].gradient(0, i));
    EXPECT_NEAR(fwd.responses[1].gradient(0, i), forward, tol);
    EXPECT_NEAR(ctr.responses[1].gradient(0, i), central, tol);
    // the truncation error is there, with its sign: the forward difference is not a central one
    EXPECT_NEAR(fwd.responses[1].gradient(0, i) - exact, forward - exact, tol);
    EXPECT_GT(std::abs(forward - exact), 100 * tol);
    // the energy's linear part is differenced exactly
    EXPECT_NEAR(fwd.responses[0].gradient(0, i), (i == 0 ? 1.0 : 2.0) + forward, tol);
  }
}

// Each optimizer ends at the closed-form optimum. The run stops when the objective changes by less
// than 1e-9 (relative) at a design feasible within 1e-8. Along the active constraint the
// objective is flat to first order at the optimum (E − E* ≈ ½ κ Δm²), so an objective 1e-8 off
// leaves the design ~1e-4 off: tolerances 3e-4 on the design and 1e-7 on the objective
// (measured: design 3.8e-5 (ccsaq), 1e-7 (mma), 2.3e-8 (slsqp); objective ≤ 7.4e-9).
TEST(MethodsCoverage, NloptMmaCcsaqAndSlsqpReachTheClosedFormOptimum) {
  for (const std::string opt : {"mma", "ccsaq", "slsqp"}) {
    const OptRun r = optimize_case(coasting_bodies(opt));
    const Vec& p = r.res.p;
    std::printf(
        "%-6s %3ld evaluations, %s: m = (%.9f, %.9f) [closed form (%.9f, %.9f)], E = %.12f "
        "[%.12f], "
        "violation %+.2e\n",
        opt.c_str(), r.res.evaluations, r.res.nlopt_status.c_str(), p[0], p[1], kM1, kM2,
        r.res.final.objective, kE, r.res.final.max_violation);
    EXPECT_TRUE(r.res.converged) << opt << ": " << r.res.nlopt_status;
    EXPECT_NEAR(p[0] / kM1, 1, 3e-4) << opt;
    EXPECT_NEAR(p[1] / kM2, 1, 3e-4) << opt;
    EXPECT_NEAR(r.res.final.objective / kE, 1, 1e-7) << opt;
    // the objective evaluated by the simulation is the closed form at the final design
    EXPECT_NEAR(r.res.final.objective, energy(p[0], p[1]), 1e-12) << opt;
  }
}

TEST(MethodsCoverage, MmaSvanbergRespectsItsMoveLimitAndReachesTheOptimum) {
  // move_limit 0.05: no variable moves by more than 0.05 × (10 − 0.5) = 0.475 per iteration; from
  // m = (5, 5) to (2.41, 1.71) the first iterations take the full move (the optimum is ≥ 5 moves
  // away)
  json j = coasting_bodies("mma-svanberg");
  j["optimization"]["move_limit"] = 0.05;
  const OptRun r = optimize_case(j);
  const auto& h = r.res.history;
  ASSERT_GE(h.size(), 2u);
  double largest = 0;
  int at_limit = 0;
  for (size_t k = 1; k < h.size(); ++k)
    for (int i = 0; i < 2; ++i) {
      const double step = std::abs(h[k].p[i] - h[k - 1].p[i]);
      largest = std::max(largest, step);
      if (step > 0.475 * (1 - 1e-5))
        ++at_limit;  // the interior-point subproblem stays inside its box
      EXPECT_LE(step, 0.475 * (1 + 1e-12)) << "iteration " << k << " variable " << i;
    }
  std::printf(
      "mma-svanberg, move limit 0.05: %ld evaluations, largest step %.6f (limit 0.475), %d steps "
      "at the limit; "
      "m = (%.9f, %.9f), E = %.12f\n",
      r.res.evaluations, largest, at_limit, r.res.p[0], r.res.p[1], r.res.final.objective);
  EXPECT_GE(at_limit, 5) << "the first moves are limited";
  EXPECT_TRUE(r.res.converged);
  EXPECT_NEAR(r.res.p[0] / kM1, 1, 3e-4);  // as above (measured 1.1e-5)
  EXPECT_NEAR(r.res.p[1] / kM2, 1, 3e-4);
  EXPECT_NEAR(r.res.final.objective / kE, 1,
              1e-6);  // the classic MMA stops on the same rule (measured 2.4e-7)
  // the default move limit (0.1 of the range: 0.95) lets the first step go further than 0.475
  const OptRun d = optimize_case(coasting_bodies("mma-svanberg"));
  double first = 0;
  for (int i = 0; i < 2; ++i)
    first = std::max(first, std::abs(d.res.history[1].p[i] - d.res.history[0].p[i]));
  std::printf("mma-svanberg, default move limit: first step %.6f, %ld evaluations\n", first,
              d.res.evaluations);
  EXPECT_GT(first, 0.475);
  EXPECT_NEAR(d.res.p[0] / kM1, 1, 3e-4);
}

TEST(MethodsCoverage, MmaSvanbergAsymptoteInitBoundsTheFirstStep) {
  // Svanberg (1987): the first asymptotes sit at x ± s (xmax − xmin), and the subproblem's box
  // keeps x within L + 0.1 (x − L) … U − 0.1 (U − x): with s = asymptote_init = 0.05 the first step
  // is at most 0.9 × 0.05 × (10 − 0.5) = 0.4275, whatever the (default, 0.5) move limit
  json j = coasting_bodies("mma-svanberg");
  j["optimization"]["asymptote_init"] = 0.05;
  const OptRun r = optimize_case(j);
  ASSERT_GE(r.res.history.size(), 2u);
  double first = 0;
  for (int i = 0; i < 2; ++i)
    first = std::max(first, std::abs(r.res.history[1].p[i] - r.res.history[0].p[i]));
  std::printf(
      "mma-svanberg, asymptote_init 0.05: first step %.6f (bound 0.4275), %ld evaluations\n", first,
      r.res.evaluations);
  EXPECT_LE(first, 0.4275 * (1 + 1e-12));
  EXPECT_GT(first, 0.4275 * 0.99) << "the first step is not limited by the asymptotes";
  EXPECT_TRUE(r.res.converged);
  EXPECT_NEAR(r.res.p[0] / kM1, 1, 3e-4);
  EXPECT_NEAR(r.res.p[1] / kM2, 1, 3e-4);
  // only the classic MMA has asymptote options
  json bad = coasting_bodies("mma");
  bad["optimization"]["asymptote_init"] = 0.2;
  Case bc = test::make_case(bad);
  EXPECT_THROW(parse_optimization(bc), Error);
}

TEST(MethodsCoverage, CliGradientsCsvAndSummaryHoldTheLibraryNumbers) {
  namespace fs = std::filesystem;
  const std::string dir = testing::TempDir() + "lsmbs_cli_numbers";
  fs::remove_all(dir);
  fs::create_directories(dir);
  json j = coasting_bodies("mma");
  // a per-step response too (gradients.csv rows per step, arrays in summary.json)
  j["output"]["responses"].push_back({{"name", "spread_steps"},
                                      {"measure", "spread"},
                                      {"aggregate", "per_step"},
                                      {"window", {{"t0", 0.5}, {"t1", 1.0}}}});
  const std::string file = dir + "/case.json";
  std::ofstream(file) << j.dump(1);
  const std::string out = dir + "/out";
  const std::string cmd = std::string(LSMBS_CLI) + " sensitivity " + file +
                          " --method direct-analytic --set m1=2 --set m2=3 -q -o " + out;
  const int rc = std::system(cmd.c_str());
  ASSERT_TRUE(WIFEXITED(rc) && WEXITSTATUS(rc) == 0) << cmd;

  Case cs = load_case(file);
  SensitivityOptions o;
  o.method = SensitivityOptions::Method::kDirectAnalytic;
  const auto lib = compute_sensitivities(cs, (Vec(2) << 2.0, 3.0).finished(), o);
  ASSERT_TRUE(lib.ok);

  // summary.json: the same doubles (JSON numbers round-trip)
  const json S = json::parse(std::ifstream(out + "/summary.json"));
  const char* vars[2] = {"m1", "m2"};
  int compared = 0;
  for (const auto& rs : lib.responses) {
    if (rs.times.empty()) {
      EXPECT_EQ(S["responses"][rs.name].get<double>(), rs.values[0]) << rs.name;
      for (int i = 0; i < 2; ++i, ++compared)
        EXPECT_EQ(S["gradients"][rs.name][vars[i]].get<double>(), rs.gradient(0, i));
    } else {
      ASSERT_EQ(S["responses"][rs.name].size(), rs.values.size());
      for (size_t k = 0; k < rs.values.size(); ++k) {
        EXPECT_EQ(S["responses"][rs.name][k].get<double>(), rs.values[k]);
        for (int i = 0; i < 2; ++i, ++compared)
          EXPECT_EQ(S["gradients"][rs.name][vars[i]][k].get<double>(),
                    rs.gradient(static_cast<Eigen::Index>(k), i));
      }
    }
  }
  // gradients.csv in long form: response, variable, step, t, value, derivative — numbers
  // written so that they read back as the same doubles
  std::ifstream csv(out + "/gradients.csv");
  std::string line;
  std::getline(csv, line);
  EXPECT_EQ(line, "response,variable,step,t,value,derivative");
  size_t rows = 0;
  while (std::getline(csv, line)) {
    std::vector<std::string> f;
    std::stringstream ss(line);
    for (std::string x; std::getline(ss, x, ',');) f.push_back(x);
    ASSERT_EQ(f.size(), 6u) << line;
    const lsmbs::ResponseSensitivity* rs = nullptr;
    for (const auto& r : lib.responses)
      if (r.name == f[0]) rs = &r;
    ASSERT_NE(rs, nullptr) << line;
    const int i = f[1] == vars[0] ? 0 : 1;
    EXPECT_EQ(f[1], vars[i]) << line;
    const auto k = static_cast<Eigen::Index>(std::stol(f[2]));
    EXPECT_EQ(std::stod(f[4]), rs->values[k]) << line;
    EXPECT_EQ(std::stod(f[5]), rs->gradient(k, i)) << line;
    if (!rs->times.empty())
      EXPECT_EQ(std::stod(f[3]), rs->times[k]) << line;
    else
      EXPECT_EQ(f[3], "nan") << line;
    ++rows;
  }
  EXPECT_EQ(rows, 2u * (2u + 6u));  // (two scalar responses, six steps in [0.5, 1.0]) x 2 variables
  EXPECT_EQ(compared, 2 * 2 + 2 * 6);
}

// The discrete adjoint in an optimization: the same closed-form optimum with the gradients of
// "sensitivity": {"method": "adjoint"} (objective and constraint from one backward pass), and a
// per-step constraint refused at the optimization's JSON path.
TEST(MethodsCoverage, OptimizationWithTheDiscreteAdjointReachesTheClosedFormOptimum) {
  json j = coasting_bodies("mma");
  j["optimization"]["sensitivity"] = {{"method", "adjoint"}};
  j["output"]["responses"].push_back(
      {{"name", "spread_per_step"}, {"measure", "spread"}, {"aggregate", "per_step"}});
  const OptRun r = optimize_case(j);  // an unused per-step response is skipped, not refused
  const Vec& p = r.res.p;
  std::printf("adjoint: %ld evaluations, m = (%.9f, %.9f) [closed form (%.9f, %.9f)], E = %.12f\n",
              r.res.evaluations, p[0], p[1], kM1, kM2, r.res.final.objective);
  EXPECT_TRUE(r.res.converged) << r.res.nlopt_status;
  EXPECT_NEAR(p[0] / kM1, 1, 3e-4);
  EXPECT_NEAR(p[1] / kM2, 1, 3e-4);
  EXPECT_NEAR(r.res.final.objective / kE, 1, 1e-7);
  // de/dm_i = −½/m_i² at the final design from the adjoint's constraint gradient
  const auto& g = r.res.final.constraint_gradient;
  ASSERT_EQ(g.rows(), 1);
  for (int i = 0; i < 2; ++i) EXPECT_NEAR(g(0, i), -0.5 / (p[i] * p[i]), 1e-10) << i;
  json bad = j;
  bad["optimization"]["constraints"] = {{{"response", "spread_per_step"}, {"upper", 0.5}}};
  Case cs = test::make_case(bad);
  try {
    DesignProblem prob(cs, parse_optimization(cs));
    ADD_FAILURE() << "a per-step constraint was accepted with the adjoint";
  } catch (const SetupError& e) {
    EXPECT_NE(std::string(e.what()).find("direct-analytic"), std::string::npos) << e.what();
  }
}

TEST(MethodsCoverage, MultiStartRunsFeasibleRandomStartsAndRanksThem) {
  // lsmbs optimize --starts 3 --seed 7 on the coasting bodies: every start is drawn within the
  // bounds and is feasible by the closed form (spread = (1/m1 + 1/m2)/2 <= 0.5), the starts
  // differ, every start reaches the closed-form optimum (m1, m2) = (1 + sqrt 2, m1/sqrt 2), and
  // the ranking is the children's own results; the same seed gives the same starts
  namespace fs = std::filesystem;
  const std::string dir = testing::TempDir() + "lsmbs_multistart";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string file = dir + "/case.json";
  std::ofstream(file) << coasting_bodies("mma").dump(1);
  auto run = [&](const std::string& out, const std::string& extra) {
    const std::string cmd =
        std::string(LSMBS_CLI) + " optimize " + file + " -q -o " + dir + "/" + out + extra;
    const int rc = std::system(cmd.c_str());
    return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
  };
  ASSERT_EQ(run("a", " --starts 3 --seed 7"), 0);
  ASSERT_EQ(run("b", " --starts 3 --seed 7"), 0);
  auto starts = [&](const std::string& out) {  // rows of starts.csv by column name
    std::ifstream f(dir + "/" + out + "/starts.csv");
    std::string line;
    std::getline(f, line);
    EXPECT_EQ(line,
              "start,exit_code,status,objective,max_violation,feasible,evaluations,wall_seconds,"
              "stop_reason,kkt,converged,judgement,rank,initial.m1,initial.m2,final.m1,final.m2");
    std::vector<std::string> names;
    std::stringstream hs(line);
    for (std::string c; std::getline(hs, c, ',');) names.push_back(c);
    std::vector<std::map<std::string, std::string>> rows;
    while (std::getline(f, line)) {
      std::map<std::string, std::string> cells;
      std::stringstream ss(line);
      size_t i = 0;
      for (std::string c; std::getline(ss, c, ',');) cells[i < names.size() ? names[i++] : "?"] = c;
      EXPECT_EQ(cells.size(), names.size()) << line;
      rows.push_back(cells);
    }
    return rows;
  };
  const auto a = starts("a"), b = starts("b");
  ASSERT_EQ(a.size(), 3u);
  ASSERT_EQ(b.size(), 3u);
  std::vector<double> objectives;
  for (size_t k = 0; k < 3; ++k) {
    auto row = a[k];
    const double m1 = std::stod(row["initial.m1"]), m2 = std::stod(row["initial.m2"]);
    EXPECT_TRUE(m1 >= 0.5 && m1 <= 10 && m2 >= 0.5 && m2 <= 10) << m1 << ", " << m2;
    EXPECT_LE(spread(m1, m2), 0.5) << "start " << k + 1 << " is not feasible";
    EXPECT_EQ(row["initial.m1"], b[k].at("initial.m1")) << "same seed, same starts";
    EXPECT_EQ(row["initial.m2"], b[k].at("initial.m2"));
    if (k > 0) EXPECT_NE(row["initial.m1"], a[k - 1].at("initial.m1")) << "the starts differ";
    EXPECT_EQ(row["status"], "complete");
    const json S =
        json::parse(std::ifstream(dir + "/a/start_" + std::to_string(k + 1) + "/summary.json"));
    EXPECT_NEAR(S["final"]["design"]["m1"].get<double>() / kM1, 1, 3e-4);
    EXPECT_NEAR(S["final"]["design"]["m2"].get<double>() / kM2, 1, 3e-4);
    EXPECT_NEAR(S["initial"]["design"]["m1"].get<double>(), m1, 1e-15 * m1);
    EXPECT_EQ(std::stod(row["objective"]), S["final"]["objective"].get<double>());
    // the final design, the stop reason and the KKT verdict of each start, as its summary says;
    // at the closed-form optimum the KKT conditions hold
    EXPECT_EQ(std::stod(row["final.m1"]), S["final"]["design"]["m1"].get<double>());
    EXPECT_EQ(std::stod(row["final.m2"]), S["final"]["design"]["m2"].get<double>());
    EXPECT_EQ(row["stop_reason"], S["stop_reason"].get<std::string>());
    EXPECT_EQ(row["kkt"], "satisfied") << "stationarity " << S["kkt"]["stationarity"];
    EXPECT_EQ(row["converged"], "1");
    objectives.push_back(std::stod(row["objective"]));
    EXPECT_NEAR(objectives.back() / kE, 1, 1e-6);
  }
  const json S = json::parse(std::ifstream(dir + "/a/summary.json"));
  EXPECT_EQ(S["status"], "complete");
  std::sort(objectives.begin(), objectives.end());
  EXPECT_EQ(S["ranking"]["best"].get<double>(), objectives[0]);
  EXPECT_EQ(S["ranking"]["median"].get<double>(), objectives[1]);
  EXPECT_EQ(S["ranking"]["worst"].get<double>(), objectives[2]);
  EXPECT_EQ(S["options"]["multistart"]["seed"], 7);
  // another seed, other starts; --starts 0 and a --seed without --starts are input errors
  ASSERT_EQ(run("c", " --starts 3 --seed 8"), 0);
  EXPECT_NE(starts("c")[0].at("initial.m1"), a[0].at("initial.m1"));
  EXPECT_EQ(run("d", " --starts 0"), 2);
  EXPECT_EQ(run("e", " --seed 7"), 2);
  // --resume: another seed or number of starts is refused; a start that never began (its
  // folder removed) runs afresh from the stored initial design, the others resume
  EXPECT_EQ(run("a", " --starts 3 --seed 8 --resume"), 2);
  EXPECT_EQ(run("a", " --starts 2 --seed 7 --resume"), 2);
  fs::remove_all(dir + "/a/start_3");
  ASSERT_EQ(run("a", " --starts 3 --seed 7 --resume"), 0);
  const auto r = starts("a");
  ASSERT_EQ(r.size(), 3u);
  EXPECT_EQ(r[2].at("exit_code"), "0");
  EXPECT_EQ(r[2].at("status"), "complete");
  EXPECT_EQ(r[2].at("initial.m1"), a[2].at("initial.m1")) << "the stored start, not a new draw";
  EXPECT_EQ(r[2].at("objective"), a[2].at("objective")) << "the same optimum (a deterministic run)";
  // a start that ends without a summary.json (here its folder holds a user's history.csv, which
  // it refuses to replace: exit 2) is ranked as not run, and the multi-start is partial (exit 1);
  // the ranking read that start's final design from a summary it did not have and crashed
  fs::remove_all(dir + "/a/start_2");
  fs::create_directories(dir + "/a/start_2");
  std::ofstream(dir + "/a/start_2/history.csv") << "a user's file\n";
  EXPECT_EQ(run("a", " --starts 3 --seed 7 --resume"), 1);
  const auto broken = starts("a");
  ASSERT_EQ(broken.size(), 3u);
  EXPECT_EQ(broken[1].at("exit_code"), "2");
  EXPECT_EQ(broken[1].at("status"), "not run");
  EXPECT_EQ(broken[1].at("final.m1"), "nan");
  EXPECT_EQ(broken[1].at("rank"), "");
  EXPECT_TRUE(fs::exists(dir + "/a/start_2/history.csv")) << "the user's file is kept";
}

TEST(MethodsCoverage, MultiStartRanksAnUnconstrainedProblemByItsObjective) {
  // The coasting bodies with the objective alone (no constraint) and the lower bounds at 0.25:
  // E = m1 + 2 m2 + ½ (1/m1 + 1/m2) has its minimum inside the bounds where dE/dm1 = 1 − ½/m1² and
  // dE/dm2 = 2 − ½/m2² vanish, m = (1/√2, ½), E* = 2 + √2. Every start is feasible (there is
  // nothing to violate), every child reaches E*, and the ranking is by objective.
  namespace fs = std::filesystem;
  const std::string dir = testing::TempDir() + "lsmbs_multistart_unconstrained";
  fs::remove_all(dir);
  fs::create_directories(dir);
  json j = coasting_bodies("mma");
  j["optimization"].erase("constraints");
  for (auto& v : j["design"]["variables"]) v["lower"] = 0.25;
  const std::string file = dir + "/case.json";
  std::ofstream(file) << j.dump(1);
  const std::string cmd =
      std::string(LSMBS_CLI) + " optimize " + file + " -q -o " + dir + "/out --starts 2 --seed 7";
  const int rc = std::system(cmd.c_str());
  ASSERT_TRUE(WIFEXITED(rc));
  EXPECT_EQ(WEXITSTATUS(rc), 0) << "both starts completed: the multi-start is complete";
  const double e_star = 2 + std::sqrt(2.0);
  for (int k = 1; k <= 2; ++k) {
    const json C =
        json::parse(std::ifstream(dir + "/out/start_" + std::to_string(k) + "/summary.json"));
    EXPECT_EQ(C["status"], "complete") << k;
    // no constraint: no violation (a number, not null)
    ASSERT_TRUE(C["final"]["max_violation"].is_number()) << C["final"].dump();
    EXPECT_EQ(C["final"]["max_violation"].get<double>(), 0.0);
    EXPECT_NEAR(C["final"]["design"]["m1"].get<double>() * std::sqrt(2.0), 1, 1e-3) << k;
    EXPECT_NEAR(C["final"]["design"]["m2"].get<double>() * 2, 1, 1e-3) << k;
  }
  const json S = json::parse(std::ifstream(dir + "/out/summary.json"));
  EXPECT_EQ(S["status"], "complete");
  ASSERT_TRUE(S.contains("ranking")) << S.dump(1);
  EXPECT_EQ(S["ranking"]["feasible_results"], 2);
  EXPECT_NEAR(S["ranking"]["best"].get<double>() / e_star, 1, 1e-6);
  EXPECT_NEAR(S["ranking"]["worst"].get<double>() / e_star, 1, 1e-6);
  for (const auto& s : S["starts"]) {
    EXPECT_EQ(s["feasible"], true) << s.dump();
    EXPECT_EQ(s["max_violation"], 0.0) << s.dump();
  }
}
