// Responses of the derived measures (a point in a rigid body's frame, its velocity there, the
// distance from a line through two points, a linear combination) have exact design gradients in
// every method: each method against central differences of whole simulations (fd-central), on
// the spring slider-crank (design: the spring's stiffness and damping).
#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "lsmbs/sensitivity/gradient_check.hpp"
#include "lsmbs/sensitivity/sensitivity.hpp"
#include "support/test_models.hpp"

namespace lsmbs {
namespace {

using Method = SensitivityOptions::Method;

nlohmann::json spring_with_derived_measures() {
  std::ifstream f(std::string(LSMBS_SOURCE_DIR) +
                  "/data/slider_crank_rigid/slider_crank_spring.json");
  nlohmann::json j = nlohmann::json::parse(f);
  const nlohmann::json piston = {{"body", "piston"}},
                       crank = {{"body", "crank"}, {"at", {0.02, 0}}};
  j["output"]["measures"] = {{{"name", "piston_in_crank"},
                              {"type", "frame_position"},
                              {"point", piston},
                              {"frame", crank}},
                             {{"name", "piston_v_in_crank"},
                              {"type", "frame_velocity"},
                              {"point", piston},
                              {"frame", crank}},
                             {{"name", "rod_mid_off_line"},
                              {"type", "line_distance"},
                              {"point", {{"body", "rod"}, {"at", {0.0678, 0.01}}}},
                              {"a", {{"body", "crank"}, {"at", {0.045, 0}}}},
                              {"b", piston}},
                             {{"name", "mix"},
                              {"type", "combination"},
                              {"constant", 0.1},
                              {"terms",
                               {{{"measure", "piston_in_crank.y"}, {"weight", 3.0}},
                                {{"measure", "rod_mid_off_line"}, {"weight", -2.0}}}}}};
  j["output"]["responses"] = {
      {{"name", "mean_y_in_crank"}, {"measure", "piston_in_crank.y"}, {"aggregate", "average"}},
      {{"name", "final_x_in_crank"}, {"measure", "piston_in_crank.x"}, {"aggregate", "final"}},
      {{"name", "speed_in_crank"}, {"measure", "piston_v_in_crank.x"}, {"aggregate", "rms"}},
      {{"name", "off_line"}, {"measure", "rod_mid_off_line"}, {"aggregate", "integral"}},
      {{"name", "mix_end"}, {"measure", "mix"}, {"aggregate", "final"}}};
  return j;
}

TEST(DerivedMeasures, EveryMethodAgreesWithCentralDifferences) {
  const Case cs = test::make_case(spring_with_derived_measures());
  const Vec p = cs.design->initial();
  SensitivityOptions ref_o;
  ref_o.method = Method::kFdCentral;
  ref_o.delta = 1e-5;
  const auto ref = compute_sensitivities(cs, p, ref_o);
  ASSERT_TRUE(ref.ok) << ref.message;
  // fd-central at a relative step of 1e-5 carries its own error, ~1e-7 of the gradient here
  for (Method m : {Method::kDirectAnalytic, Method::kSemiAnalyticalCentral, Method::kAdjoint}) {
    SensitivityOptions o;
    o.method = m;
    const auto r = compute_sensitivities(cs, p, o);
    ASSERT_TRUE(r.ok) << SensitivityOptions::name(m) << ": " << r.message;
    const auto d = compare_gradients(r.responses, ref.responses, GradientNorm::kPerResponse);
    std::printf("%-24s against fd-central: %.2e (%s)\n", SensitivityOptions::name(m), d.worst,
                d.where.c_str());
    EXPECT_LT(d.worst, 1e-5) << SensitivityOptions::name(m) << " " << d.where;
  }
  // IDAS differentiates the continuous problem: its own discretization error on this run
  SensitivityOptions io;
  io.method = Method::kIdas;
  const auto ri = compute_sensitivities(cs, p, io);
  ASSERT_TRUE(ri.ok) << ri.message;
  const auto di = compare_gradients(ri.responses, ref.responses, GradientNorm::kPerResponse);
  std::printf("%-24s against fd-central: %.2e (%s)\n", "idas", di.worst, di.where.c_str());
  EXPECT_LT(di.worst, 2e-2) << di.where;
}

TEST(DerivedMeasures, RefusalsNameTheirKey) {
  auto refused = [](nlohmann::json j, const std::string& words) {
    try {
      (void)test::make_case(j);
      ADD_FAILURE() << "accepted; expected: " << words;
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(words), std::string::npos) << e.what();
    }
  };
  nlohmann::json j = spring_with_derived_measures();
  j["output"]["measures"][0]["frame"] = {{"ground", {0, 0}}};
  refused(j, "/output/measures/0/frame/body: expected a rigid body");
  j = spring_with_derived_measures();
  j["output"]["measures"][3]["terms"][0]["measure"] = "piston_v_in_crank.x";
  refused(j,
          "/output/measures/3/terms/1/measure: 'rod_mid_off_line' is in m, the terms before it "
          "in m/s");
  j = spring_with_derived_measures();
  j["output"]["measures"][3]["terms"][0]["measure"] = "nothing.x";
  refused(j, "unknown measure column 'nothing.x'");
  j = spring_with_derived_measures();
  j["output"]["measures"].push_back(
      {{"name", "f"}, {"type", "constraint_force"}, {"joint", "cylinder"}});
  j["output"]["measures"].push_back(
      {{"name", "g"}, {"type", "combination"}, {"terms", {{{"measure", "f.0"}}}}});
  refused(j, "'f.0' is a constraint force");
}

}  // namespace
}  // namespace lsmbs
