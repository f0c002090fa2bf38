// The paper's initial robot-arm design (§6, Table 5: five ξ = η = 5 super-ellipses with
// a = b = 0.01 m at c_x = 0.26 … 0.74 m) and its Table 4 values, 186.498 g and 0.6037 mm.
// References:
//  - the mass against the closed form ρ t (A_plate − (1 − μ_min) · 5 A_hole), with the
//    super-ellipse's area A = 4ab Γ(1 + 1/ξ)² / Γ(1 + 2/ξ);
//  - the paper's mass and deviation, with the gaps documented in paper_results/README.md and
//    docs/methods.md ("Known difference from the paper"): +1.7 % (the paper's mass implies a
//    void 25 % larger than the five holes' exact area) and +7.3 % (model details the paper
//    leaves open). If one of these moves, the documentation is out of date;
//  - eq. (45) as printed (sum over the constant-speed steps divided by n_cvf − n_cvi) against
//    the shipped `average` (divided by the number of steps): they differ by n/(n − 1).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>

#include "support/test_models.hpp"

using namespace lsmbs;
using json = nlohmann::json;

TEST(PaperTable5, InitialDesignMassAndDeviationWithTheDocumentedGaps) {
  json j = json::parse(
      std::ifstream(std::string(LSMBS_SOURCE_DIR) + "/data/robot_arm/robot_arm_holes.json"));
  j["output"]["responses"].push_back({{"name", "average_eq45"},
                                      {"measure", "tip_deviation"},
                                      {"aggregate", "average_eq45"},
                                      {"window", {{"driver", "theta1"}, {"phase", "constant"}}}});
  j["output"]["vtu_stride"] = 0;
  const Case cs =
      load_case_json(j, "robot_arm_holes.json", std::string(LSMBS_SOURCE_DIR) + "/data/robot_arm");
  const double mu_min = j["design"]["geometry"][0].value("mu_min", 1e-3);
  const auto res = run_simulation(cs);
  ASSERT_TRUE(res.integrator.ok) << res.integrator.message;

  const double xi = 5, A_hole = 4 * 0.01 * 0.01 * std::pow(std::tgamma(1 + 1 / xi), 2) /
                                std::tgamma(1 + 2 / xi);
  const double m_exact = 2700 * 0.0025 * (0.6 * 0.05 - (1 - mu_min) * 5 * A_hole);
  const double m = res.responses.at("plate_mass"), dev = res.responses.at("average_tip_deviation");
  const double dev45 = res.responses.at("average_eq45");
  const int n = res.response_counts.at("average_tip_deviation");
  const double paper_m = 0.186498, paper_dev = 0.6037e-3;
  std::printf(
      "initial design: plate mass %.3f g (exact holes %.3f g: %+.3f %%; paper %.3f g: %+.2f %%)\n"
      "  average tip deviation %.4f mm over %d steps (paper %.4f mm: %+.2f %%); eq. (45) as "
      "printed %.4f mm "
      "(%+.2f %%)\n",
      1e3 * m, 1e3 * m_exact, 100 * (m / m_exact - 1), 1e3 * paper_m, 100 * (m / paper_m - 1),
      1e3 * dev, n, 1e3 * paper_dev, 100 * (dev / paper_dev - 1), 1e3 * dev45,
      100 * (dev45 / paper_dev - 1));
  // the mapping's void area is 0.28 % above the exact one (the logistic's smoothing of curved
  // boundaries, docs/methods.md), i.e. 0.28 % × 5 A_hole / A_plate ≈ 0.02 % of the mass
  EXPECT_NEAR(m / m_exact, 1, 5e-4);
  // documented gaps to Table 4: +1.7 % and +7.3 % (to ±0.1 and ±0.5 points)
  EXPECT_NEAR(100 * (m / paper_m - 1), 1.7, 0.1);
  EXPECT_NEAR(100 * (dev / paper_dev - 1), 7.3, 0.5);
  // constant-speed phase of θ1: [0.25, 2.0944] s → 369 steps of 0.005 s; eq. (45) as printed is
  // larger by n/(n − 1) = 1.0027 — a difference far below the 7 % gap, so Table 4 cannot tell
  // which divisor the authors used
  EXPECT_EQ(n, 369);
  EXPECT_NEAR(dev45 / dev, double(n) / (n - 1), 1e-14);
}
