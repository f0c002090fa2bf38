// What an optimization says about its result (optimization/optimizer.hpp): why it stopped, whether
// the final design is a KKT point, and whether a max aggregate moved its extreme step. A user's
// stress-constrained run said "converged": true beside KKT multipliers [0.0] and stationarity 1.0:
// the peak had moved to another time step, a kink in the response.
//
// The reference here is independent of the aggregation: every evaluated design is simulated
// again and the arg-max of the measure over the window is read off its history.
#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "lsmbs/io/optimization_spec.hpp"
#include "lsmbs/optimization/optimizer.hpp"
#include "lsmbs/runs/simulate.hpp"
#include "support/test_models.hpp"

namespace lsmbs {
namespace {

nlohmann::json spring_minimizing_its_peak_side_force() {
  std::ifstream f(std::string(LSMBS_SOURCE_DIR) +
                  "/data/slider_crank_rigid/slider_crank_spring.json");
  nlohmann::json j = nlohmann::json::parse(f);
  j["optimization"] = {{"objective", "max_side_force"}, {"stop", {{"max_evaluations", 12}}}};
  return j;
}

// Time of the largest value of `column` over [t0, t1] in a simulation of the case at p.
double arg_max_time(const nlohmann::json& doc, const Vec& p, const std::string& column, double t0,
                    double t1) {
  Case cs = test::make_case(doc);
  cs.design->apply(p, cs.model->params());
  RunOptions ro;
  ro.design_point = p;
  const SimulationResult r = run_simulation(cs, ro);
  EXPECT_EQ(r.status(), RunStatus::kComplete);
  const auto v = r.column(column);
  double best = -1e300, at = NAN;
  for (size_t n = 0; n < v.size(); ++n)
    if (r.times[n] >= t0 - 1e-12 && r.times[n] <= t1 + 1e-12 && v[n] > best)
      best = v[n], at = r.times[n];
  return at;
}

TEST(OptimizationVerdict, AMaxAggregateWhosePeakMovesIsReportedAndNotConverged) {
  const nlohmann::json doc = spring_minimizing_its_peak_side_force();
  Case cs = test::make_case(doc);
  DesignProblem prob(cs, parse_optimization(cs));
  const OptimizeResult res = optimize(prob, OptimizeOptions{});
  ASSERT_EQ(res.status(), RunStatus::kComplete) << res.report();
  ASSERT_EQ(res.history.size(), 12u);
  int moves = 0;
  double previous = NAN;
  for (size_t k = 0; k < res.history.size(); ++k) {
    const Evaluation& e = res.history[k];
    const double t = arg_max_time(doc, e.p, "cylinder_force.0", 0.1, 0.25);
    ASSERT_EQ(e.extreme_times.count("max_side_force"), 1u);
    EXPECT_EQ(e.extreme_times.at("max_side_force"), t) << "evaluation " << k + 1;
    if (k > 0 && t != previous) ++moves;
    previous = t;
  }
  ASSERT_GT(moves, 0) << "the peak of the side force stays at one step: no kink to report";
  bool said = false;
  for (const auto& w : res.warnings)
    said |= w.find(
                "response 'max_side_force' is a maximum or minimum over time whose extreme "
                "step moved " +
                std::to_string(moves) + " time(s) in 12 evaluations") == 0;
  EXPECT_TRUE(said) << "the moves of the peak are reported with their count";
  // cut off at the evaluation limit: not converged, whatever the objective's last change
  EXPECT_EQ(res.stop_reason, "max_evaluations");
  EXPECT_FALSE(res.converged);
  ASSERT_TRUE(res.kkt.has_value());
  EXPECT_EQ(res.kkt->satisfied(),
            res.kkt->stationarity <= 1e-2 && res.kkt->bound_sign_violation <= 1e-2);
}

TEST(OptimizationVerdict, TheSameProblemWithASmoothAggregateReportsNoMove) {
  // KS of the same measure: no extreme step, nothing to report about one
  nlohmann::json doc = spring_minimizing_its_peak_side_force();
  for (auto& r : doc["output"]["responses"])
    if (r["name"] == "max_side_force") r["aggregate"] = "ks", r["ks"] = 50;
  Case cs = test::make_case(doc);
  DesignProblem prob(cs, parse_optimization(cs));
  const OptimizeResult res = optimize(prob, OptimizeOptions{});
  for (const auto& e : res.history) EXPECT_TRUE(e.extreme_times.empty());
  for (const auto& w : res.warnings)
    EXPECT_EQ(w.find("extreme step moved"), std::string::npos) << w;
}

}  // namespace
}  // namespace lsmbs
