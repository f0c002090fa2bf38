// Service conditions: one design evaluated under several conditions, their responses named
// "<condition>.<response>" and combined (sum, KS, exact max). References: the closed form of a
// mass on a spring, x(T) = L0 + A cos(ω T), ω = sqrt(k/m), dx(T)/dk = −A sin(ωT) T / (2 sqrt(k m)),
// for each condition's payload; central differences of whole runs of the combined responses;
// the same evaluation one condition after the other.
#include "lsmbs/sensitivity/conditions.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "lsmbs/core/error.hpp"
#include "lsmbs/io/case.hpp"
#include "lsmbs/io/optimization_spec.hpp"
#include "lsmbs/optimization/problem.hpp"
#include "lsmbs/runs/sensitivity.hpp"
#include "lsmbs/runs/simulate.hpp"
#include "support/test_models.hpp"

using namespace lsmbs;
using json = nlohmann::json;

namespace {

constexpr double kA = 0.01, kL0 = 0.5, kT = 1.0, kK = 200.0;
constexpr double kLight = 2.0, kHeavy = 5.0;

// A block on a slide held by a spring (stiffness: the design variable k), released at L0 + A
// from rest; two conditions differ by the block's mass, one also by its end time.
json oscillator() {
  return json::parse(R"({
    "name": "payloads",
    "bodies": [{"name": "block", "type": "rigid", "position": [0.51, 0], "mass": 1}],
    "joints": [{"name": "slide", "type": "prismatic", "a": {"body": "block"}, "direction": [1, 0]}],
    "forces": [{"name": "spring", "type": "spring_damper", "a": {"body": "block"},
                "b": {"ground": [0, 0]}, "stiffness": 200, "free_length": 0.5}],
    "simulation": {"t_end": 1.0, "h": 0.001, "rho_inf": 0.9, "tol_r": 1e-12},
    "output": {"measures": [{"name": "block", "type": "position", "point": {"body": "block"}}],
               "responses": [{"name": "x_end", "measure": "block.x", "aggregate": "final"}]},
    "design": {"variables": [{"name": "k", "initial": 200, "lower": 50, "upper": 400}],
               "parameters": [{"parameter": "spring.stiffness", "variable": "k"}]},
    "conditions": [{"name": "light", "set": {"/bodies/block/mass": 2.0}},
                   {"name": "heavy", "set": {"/bodies/0/mass": 5.0}}],
    "combined": [{"name": "sum", "aggregate": "sum", "of": "x_end", "weights": [1, 2]},
                 {"name": "envelope", "aggregate": "ks", "of": ["light.x_end", "heavy.x_end"],
                  "ks": 2000},
                 {"name": "worst", "aggregate": "max", "of": "x_end"}]
  })");
}

double x_end(double k, double m) { return kL0 + kA * std::cos(std::sqrt(k / m) * kT); }
double dx_dk(double k, double m) {
  const double w = std::sqrt(k / m);
  return -kA * std::sin(w * kT) * kT / (2 * std::sqrt(k * m));
}

const ResponseSensitivity& named(const std::vector<ResponseSensitivity>& rs,
                                 const std::string& name) {
  for (const auto& r : rs)
    if (r.name == name) return r;
  throw std::runtime_error("no response " + name);
}

}  // namespace

TEST(Conditions, ResponsesAreEachConditionsClosedFormAndTheirCombinations) {
  const Case cs = test::make_case(oscillator());
  ASSERT_EQ(cs.conditions.size(), 2u);
  const Conditions c = conditions_of(cs);
  EXPECT_EQ(c.response_names(),
            (std::vector<std::string>{"light.x_end", "heavy.x_end", "sum", "envelope", "worst"}));
  SensitivityOptions o;
  o.method = SensitivityOptions::Method::kDirectAnalytic;
  const Vec p = cs.design->initial();
  const auto r = compute_sensitivities(c, p, o, thread_executor(2));
  ASSERT_TRUE(r.ok) << r.message;
  const double xl = x_end(kK, kLight), xh = x_end(kK, kHeavy);
  // generalized-α's phase error after ~1.6 periods at ω h ≈ 0.01: below 2e-3 A
  EXPECT_NEAR(named(r.responses, "light.x_end").values[0], xl, 2e-3 * kA);
  EXPECT_NEAR(named(r.responses, "heavy.x_end").values[0], xh, 2e-3 * kA);
  EXPECT_NEAR(named(r.responses, "light.x_end").gradient(0, 0), dx_dk(kK, kLight),
              5e-3 * std::abs(dx_dk(kK, kLight)));
  EXPECT_NEAR(named(r.responses, "heavy.x_end").gradient(0, 0), dx_dk(kK, kHeavy),
              5e-3 * std::abs(dx_dk(kK, kHeavy)));
  // the combinations of the computed terms, exactly as defined
  const double gl = named(r.responses, "light.x_end").gradient(0, 0),
               gh = named(r.responses, "heavy.x_end").gradient(0, 0);
  const double vl = named(r.responses, "light.x_end").values[0],
               vh = named(r.responses, "heavy.x_end").values[0];
  EXPECT_EQ(named(r.responses, "sum").values[0], vl + 2 * vh);
  EXPECT_DOUBLE_EQ(named(r.responses, "sum").gradient(0, 0), gl + 2 * gh);
  EXPECT_EQ(named(r.responses, "worst").values[0], std::max(vl, vh));
  EXPECT_EQ(named(r.responses, "worst").gradient(0, 0), vl > vh ? gl : gh);
  const double ks = named(r.responses, "envelope").values[0];
  EXPECT_GE(ks, std::max(vl, vh));
  EXPECT_LE(ks, std::max(vl, vh) + std::log(2.0) / 2000);  // the stated error bound
  const double wl = 1 / (1 + std::exp(2000 * (vh - vl)));
  EXPECT_NEAR(named(r.responses, "envelope").gradient(0, 0), wl * gl + (1 - wl) * gh,
              1e-12 * std::abs(gl));
}

// Every method's gradient of every gathered response against central differences of whole runs
// of the combined responses (plain simulations of each condition at k ± δ, gathered).
TEST(Conditions, EveryMethodsGradientsAreTheCentralDifferencesOfTheCombinedResponses) {
  const Case cs = test::make_case(oscillator());
  const Conditions c = conditions_of(cs);
  const Vec p = cs.design->initial();
  const double d = 1e-3 * p[0];
  auto values_at = [&](double k) {
    std::vector<SensitivityResult> runs(c.size());
    for (size_t i = 0; i < c.size(); ++i) {
      SensitivityCounts counts;
      runs[i].responses = simulate_responses(*c.studies[i], Vec::Constant(1, k), counts);
    }
    return gather(c, runs);
  };
  const auto plus = values_at(p[0] + d), minus = values_at(p[0] - d);
  // relative to the derivatives' scale A T / (2 sqrt(k m)): the heavy condition's derivative
  // nearly vanishes at k = 200 (sin ωT = 0.04), where the difference's truncation is not small
  // relative to the value itself
  const double scale = kA * kT / (2 * std::sqrt(kK * kLight));
  using M = SensitivityOptions::Method;
  for (M m : {M::kDirectAnalytic, M::kSemiAnalyticalCentral, M::kAdjoint, M::kFdCentral}) {
    SensitivityOptions o;
    o.method = m;
    const auto r = compute_sensitivities(c, p, o, thread_executor(2));
    ASSERT_TRUE(r.ok) << SensitivityOptions::name(m) << ": " << r.message;
    for (const auto& name : c.response_names()) {
      const double fd = (named(plus, name).values[0] - named(minus, name).values[0]) / (2 * d);
      const double g = named(r.responses, name).gradient(0, 0);
      EXPECT_NEAR(g, fd, 1e-5 * scale) << SensitivityOptions::name(m) << " " << name;
    }
  }
}

// The conditions of an evaluation give the same numbers whoever runs them: one after the other,
// or at once on two threads (bit for bit).
TEST(Conditions, ResultsDoNotDependOnHowTheConditionsRun) {
  const Case cs = test::make_case(oscillator());
  const Conditions c = conditions_of(cs);
  SensitivityOptions o;
  const auto a = compute_sensitivities(c, cs.design->initial(), o, thread_executor(1));
  const auto b = compute_sensitivities(c, cs.design->initial(), o, thread_executor(2));
  ASSERT_EQ(a.responses.size(), b.responses.size());
  for (size_t i = 0; i < a.responses.size(); ++i) {
    EXPECT_EQ(a.responses[i].name, b.responses[i].name);
    EXPECT_EQ(std::memcmp(a.responses[i].values.data(), b.responses[i].values.data(),
                          sizeof(double) * a.responses[i].values.size()),
              0);
    EXPECT_EQ(std::memcmp(a.responses[i].gradient.data(), b.responses[i].gradient.data(),
                          sizeof(double) * a.responses[i].gradient.size()),
              0);
  }
}

// The assignment of conditions to ranks, against the longest-processing-time schedule worked by
// hand: the three engine speeds of slider_crank_3holes_coarse_speeds.json (320, 220 and 170 steps)
// on 2 ranks put the 2000 rpm run alone (320 against 220 + 170 = 390; round robin: 490), on 3 ranks
// one each; equal costs go round robin; the costliest task starts first on a pool of threads.
TEST(Conditions, TasksGoToRanksLongestFirst) {
  ConditionTasks t;
  t.n = 3;
  t.cost = {320, 220, 170};
  EXPECT_EQ(assign_tasks(t, 2), (std::vector<int>{0, 1, 1}));
  EXPECT_EQ(assign_tasks(t, 3), (std::vector<int>{0, 1, 2}));
  EXPECT_EQ(assign_tasks(t, 1), (std::vector<int>{0, 0, 0}));
  t.cost = {170, 220, 320};
  EXPECT_EQ(costliest_first(t), (std::vector<int>{2, 1, 0}));
  EXPECT_EQ(assign_tasks(t, 2), (std::vector<int>{1, 1, 0}));
  t.n = 5;
  t.cost.clear();
  EXPECT_EQ(assign_tasks(t, 2), (std::vector<int>{0, 1, 0, 1, 0}));
  EXPECT_EQ(costliest_first(t), (std::vector<int>{0, 1, 2, 3, 4}));
}

// An optimization over the conditions: a constraint on an exact max is one constraint per
// condition; the objective may be a sum; an exact max is refused as the objective.
TEST(Conditions, ADesignProblemOverConditionsConstrainsEachConditionOfAnExactMax) {
  json j = oscillator();
  j["optimization"] = {{"objective", "sum"},
                       {"constraints", {{{"response", "worst"}, {"upper", 0.51}}}}};
  const Case cs = test::make_case(j);
  const OptimizationSpec spec = parse_optimization(cs);
  DesignProblem prob(conditions_of(cs), spec);
  EXPECT_EQ(prob.num_constraints(), 2);
  EXPECT_EQ(prob.constraint_names(), (std::vector<std::string>{"light.x_end", "heavy.x_end"}));
  const Evaluation& e = prob.evaluate(cs.design->initial());
  ASSERT_TRUE(e.ok) << e.message;
  EXPECT_NEAR(e.constraints[0], x_end(kK, kLight), 2e-3 * kA);
  EXPECT_NEAR(e.constraints[1], x_end(kK, kHeavy), 2e-3 * kA);
  EXPECT_NEAR(e.objective, x_end(kK, kLight) + 2 * x_end(kK, kHeavy), 6e-3 * kA);
  j["optimization"]["objective"] = "worst";
  const Case bad = test::make_case(j);
  EXPECT_THROW(DesignProblem(conditions_of(bad), parse_optimization(bad)), SetupError);
}

// A response that does not depend on the motion (a body's mass) is the same under every
// condition: it is evaluated once, in the first condition, under its own name.
TEST(Conditions, AMassIsEvaluatedOnceUnderItsOwnName) {
  json j = json::parse(
      std::ifstream(std::string(LSMBS_SOURCE_DIR) + "/examples/getting_started/flexible_arm.json"));
  j["simulation"]["t_end"] = 0.1;
  j["bodies"][1]["mesh"]["elements"] = {20, 2};
  j["conditions"] = {{{"name", "light"}, {"set", {{"/forces/tool/mass", 0.2}}}},
                     {{"name", "heavy"}, {"set", {{"/forces/tool/mass", 1.0}}}}};
  const Case cs = load_case_json(j, "<test>", std::string(LSMBS_SOURCE_DIR) + "/examples");
  const Conditions c = conditions_of(cs);
  EXPECT_EQ(c.response_names(),
            (std::vector<std::string>{"arm_mass", "light.rms_deflection", "heavy.rms_deflection"}));
  EXPECT_EQ(cs.conditions[1].cs->responses.size(), 1u) << "the mass is not evaluated again";
  SensitivityOptions o;
  const auto r = compute_sensitivities(c, cs.design->initial(), o, thread_executor(2));
  ASSERT_TRUE(r.ok) << r.message;
  // the base case's own mass, and the heavier tool deflects more
  json base = j;
  base.erase("conditions");
  const Case one = load_case_json(base, "<test>", std::string(LSMBS_SOURCE_DIR) + "/examples");
  const auto single = compute_sensitivities(one, one.design->initial(), o);
  EXPECT_EQ(named(r.responses, "arm_mass").values[0],
            named(single.responses, "arm_mass").values[0]);
  EXPECT_GT(named(r.responses, "heavy.rms_deflection").values[0],
            named(r.responses, "light.rms_deflection").values[0]);
}

// Input errors name the condition, the value it sets and the JSON path.
TEST(Conditions, InputErrorsNameTheConditionAndItsValue) {
  auto error_of = [](const json& j) {
    try {
      test::make_case(j);
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  json j = oscillator();
  j["conditions"][0]["set"] = {{"/bodies/block/mass", -1.0}};
  std::string e = error_of(j);
  EXPECT_NE(e.find("/conditions/0: condition 'light': /bodies/0/mass: expected a non-negative "
                   "number"),
            std::string::npos)
      << e;
  EXPECT_NE(e.find("set by the condition as /bodies/block/mass"), std::string::npos) << e;
  j = oscillator();
  j["conditions"][1]["set"] = {{"/forces/nospring/stiffness", 1.0}};
  e = error_of(j);
  EXPECT_NE(e.find("/forces has no entry named 'nospring'"), std::string::npos) << e;
  j = oscillator();
  j["conditions"][1]["set"] = {{"/design/variables/0/upper", 1.0}};
  e = error_of(j);
  EXPECT_NE(e.find("/design is one for all conditions"), std::string::npos) << e;
  j = oscillator();
  j["combined"][0]["of"] = {"light.x_end", "heavy.y"};
  e = error_of(j);
  EXPECT_NE(e.find("/combined/0: \"of\": unknown response 'heavy.y'"), std::string::npos) << e;
  j = oscillator();
  j["conditions"][1]["name"] = "light";
  EXPECT_NE(error_of(j).find("duplicate condition 'light'"), std::string::npos);
}

// The command line's sensitivity and simulate on a case with conditions: every gathered response
// in summary.json, each condition's run in its own folder.
TEST(Conditions, TheCommandLineReportsEveryConditionsResponses) {
  namespace fs = std::filesystem;
  const std::string dir = testing::TempDir() + "lsmbs_conditions";
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::ofstream(dir + "/case.json") << oscillator().dump(1);
  auto run = [&](const std::string& args) {
    const std::string cmd = std::string(LSMBS_CLI) + " " + args + " -q";
    const int rc = std::system(cmd.c_str());
    return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
  };
  ASSERT_EQ(run("sensitivity " + dir + "/case.json -o " + dir + "/s"), 0);
  const json S = json::parse(std::ifstream(dir + "/s/summary.json"));
  for (const char* name : {"light.x_end", "heavy.x_end", "sum", "envelope", "worst"}) {
    EXPECT_TRUE(S["responses"].contains(name)) << name;
    EXPECT_TRUE(S["gradients"][name].contains("k")) << name;
  }
  EXPECT_NEAR(S["responses"]["heavy.x_end"].get<double>(), x_end(kK, kHeavy), 2e-3 * kA);
  EXPECT_NEAR(S["conditions"]["combined"][1]["error_bound"].get<double>(), std::log(2.0) / 2000,
              1e-15);
  ASSERT_EQ(run("simulate " + dir + "/case.json -o " + dir + "/r"), 0);
  const json R = json::parse(std::ifstream(dir + "/r/summary.json"));
  EXPECT_EQ(R["status"], "complete");
  EXPECT_EQ(R["responses"]["light.x_end"], S["responses"]["light.x_end"]);
  EXPECT_TRUE(fs::exists(dir + "/r/conditions/heavy/history.csv"));
  const json H = json::parse(std::ifstream(dir + "/r/conditions/heavy/summary.json"));
  EXPECT_EQ(H["responses"]["x_end"], S["responses"]["heavy.x_end"]);
}

// A condition may set a body's level-set offset, and only that of the design: a variant of the
// design (the robust formulation's eroded one). Its mass is its own, reported under its name, and
// smaller than the nominal design's by the material a grown hole removes; its gradients are
// central differences of whole runs like every other condition's.
TEST(Conditions, AnErodedVariantOfTheDesignHasItsOwnMass) {
  json j = json::parse(
      std::ifstream(std::string(LSMBS_SOURCE_DIR) + "/examples/getting_started/flexible_arm.json"));
  j["simulation"]["t_end"] = 0.1;
  j["bodies"][1]["mesh"]["elements"] = {20, 2};
  j["conditions"] = {{{"name", "eroded"}, {"set", {{"/design/geometry/0/offset", 0.002}}}},
                     {{"name", "nominal"}}};
  const Case cs = load_case_json(j, "<test>", std::string(LSMBS_SOURCE_DIR) + "/examples");
  const Conditions c = conditions_of(cs);
  EXPECT_EQ(c.response_names(),
            (std::vector<std::string>{"eroded.arm_mass", "eroded.rms_deflection", "arm_mass",
                                      "nominal.rms_deflection"}));
  SensitivityOptions o;
  const Vec p = cs.design->initial();
  const auto r = compute_sensitivities(c, p, o, thread_executor(2));
  ASSERT_TRUE(r.ok) << r.message;
  EXPECT_LT(named(r.responses, "eroded.arm_mass").values[0],
            named(r.responses, "arm_mass").values[0]);
  GradientCheckOptions g;
  const auto check = check_gradients(c, p, r.responses, g, thread_executor(2));
  ASSERT_TRUE(check.ok) << check.message;
  EXPECT_LT(check.worst, g.warn) << check.report();
  // any other value of the design is refused
  j["conditions"][0]["set"] = {{"/design/geometry/0/subgrid", 4}};
  try {
    load_case_json(j, "<test>", std::string(LSMBS_SOURCE_DIR) + "/examples");
    ADD_FAILURE() << "a condition set the design's subgrid";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("it may set only /design/geometry/<entry>/offset"),
              std::string::npos)
        << e.what();
  }
}
