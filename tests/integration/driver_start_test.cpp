// A driver's law gives the run its initial velocities and accelerations (integrators/
// initial_state.hpp): a crank driven at a constant 150 rad/s by a linear table from t = 0 turns
// at 150 rad/s from the first step (closed form θ = 150 t, ω = 150). With the law's speed at
// t = 0 taken as 0 the crank started at rest and generalized-α rang: 0, 297, 10.8, 278.6 rad/s.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "lsmbs/core/error.hpp"
#include "lsmbs/runs/simulate.hpp"
#include "support/test_models.hpp"

namespace lsmbs {
namespace {

nlohmann::json crank_driven_by_a_linear_table() {
  std::ifstream f(std::string(LSMBS_SOURCE_DIR) +
                  "/data/slider_crank_rigid/slider_crank_rigid.json");
  nlohmann::json j = nlohmann::json::parse(f);
  for (auto& jt : j["joints"])
    if (jt["name"] == "crank_drive")
      jt["law"] = {
          {"type", "table"}, {"points", {{0, 0}, {10, 1500}}}, {"interpolation", "linear"}};
  j["simulation"]["t_end"] = 0.01;
  j["output"]["measures"].push_back(
      {{"name", "crank_speed"}, {"type", "angular_velocity"}, {"body", "crank"}});
  return j;
}

TEST(DriverStart, ALinearTableFromTZeroTurnsTheCrankAtItsSpeedFromTheFirstStep) {
  const Case cs = test::make_case(crank_driven_by_a_linear_table());
  const SimulationResult r = run_simulation(cs);
  ASSERT_EQ(r.status(), RunStatus::kComplete) << r.report();
  const auto omega = r.column("crank_speed"), angle = r.column("crank_angle");
  ASSERT_EQ(omega.size(), r.times.size());
  for (size_t n = 0; n < omega.size(); ++n) {
    EXPECT_NEAR(omega[n], 150.0, 1e-8) << "t = " << r.times[n];
    EXPECT_NEAR(angle[n], 150.0 * r.times[n], 1e-10) << "t = " << r.times[n];
  }
}

TEST(DriverStart, GivenVelocitiesAreJudgedAgainstTheLawsSpeedAtTZero) {
  // the crank's own speed, given: consistent with the law (it was refused, blaming a joint)
  nlohmann::json j = crank_driven_by_a_linear_table();
  j["bodies"][0]["angular_velocity"] = 150.0;
  const Case ok = test::make_case(j);
  const SimulationResult r = run_simulation(ok);
  ASSERT_EQ(r.status(), RunStatus::kComplete) << r.report();
  EXPECT_NEAR(r.column("crank_speed").front(), 150.0, 1e-8);
  // a speed the law does not have: refused, and the message says what the driver demands
  j["bodies"][0]["angular_velocity"] = 100.0;
  try {
    (void)test::make_case(j);
    ADD_FAILURE() << "a given crank speed of 100 rad/s against a law of 150 rad/s was accepted";
  } catch (const Error& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("/bodies/0/angular_velocity"), std::string::npos) << msg;
    EXPECT_NE(msg.find("the laws move their drivers: constraint 'crank_drive'"), std::string::npos)
        << msg;
    EXPECT_NE(msg.find("ds/dt = 150"), std::string::npos) << msg;
  }
}

}  // namespace
}  // namespace lsmbs
