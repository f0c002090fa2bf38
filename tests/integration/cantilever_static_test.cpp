// Static cantilever plate 0.6 × 0.05 m, 2.5 mm, E = 72 GPa, ν = 0.3, clamped at x = 0, tip
// shear load P on the free edge: the tip deflection against Timoshenko beam theory
//   δ = P L³ / (3 E I) + P L / (κ G A),  κ = 5/6,
// for the mesh used by the robot arm (120 × 10). Prints the mesh-convergence table for both
// integration variants (copied into docs/verification.md).
#include <gtest/gtest.h>

#include <cstdio>

#include "lsmbs/integrators/static_solver.hpp"
#include "support/test_models.hpp"

using namespace lsmbs;
using json = nlohmann::json;

namespace {

constexpr double L = 0.6, H = 0.05, T = 0.0025, E = 72e9, NU = 0.3, P = 1.0;

double timoshenko() {
  const double I = T * H * H * H / 12, A = T * H, G = E / (2 * (1 + NU));
  return P * L * L * L / (3 * E * I) + P * L / (5.0 / 6.0 * G * A);
}

// Tip deflection (centre node of the loaded edge) for an nx × ny mesh.
double tip_deflection(int nx, int ny, const std::string& integration) {
  json j = {{"name", "cantilever"},
            {"bodies", {{{"name", "beam"}, {"type", "flexible"},
                         {"mesh", {{"type", "rectangle"}, {"origin", {0, -H / 2}}, {"size", {L, H}}, {"elements", {nx, ny}}}},
                         {"material", {{"E", E}, {"nu", NU}, {"rho", 2700}}}, {"thickness", T}, {"integration", integration}}}},
            {"joints", {{{"type", "clamp"}, {"flexible", "beam"}, {"node_set", "left"}}}},
            {"simulation", {{"t_end", 1}, {"h", 1}}}};
  // Uniform shear on the free edge: consistent nodal loads P/ny (P/2ny at the corners).
  json forces = json::array();
  for (int k = 0; k <= ny; ++k) {
    const int node = k * (nx + 1) + nx;
    const double f = (k == 0 || k == ny ? 0.5 : 1.0) * P / ny;
    forces.push_back({{"type", "point_force"}, {"point", {{"body", "beam"}, {"node", node}}}, {"force", {0, -f}}});
  }
  j["forces"] = forces;
  Case cs = test::make_case(j);
  State s = cs.initial;
  const auto r = solve_static(*cs.model, cs.model->params(), s);
  EXPECT_TRUE(r.ok) << r.message;
  const int centre = (ny / 2) * (nx + 1) + nx;
  return -(s.q[2 * centre + 1] - cs.initial.q[2 * centre + 1]);
}

}  // namespace

TEST(CantileverStatic, TipDeflectionOfTheRobotArmMeshIsWithinTwoPercentOfTimoshenko) {
  const double ref = timoshenko();
  const double d = tip_deflection(120, 10, "selective-shear");
  std::printf("Timoshenko %.6e m, selective-shear 120x10 %.6e m (%+.3f %%)\n", ref, d, 100 * (d / ref - 1));
  EXPECT_NEAR(d / ref, 1.0, 0.02);
}

TEST(CantileverStatic, MeshConvergenceTable) {
  const double ref = timoshenko();
  std::printf("| mesh | full 2x2 Gauss | selective shear |\n|---|---|---|\n");
  double prev_err = 1e9;
  const int meshes[][2] = {{24, 2}, {60, 5}, {120, 10}, {240, 20}};
  for (const auto& m : meshes) {
    const double full = tip_deflection(m[0], m[1], "full");
    const double sri = tip_deflection(m[0], m[1], "selective-shear");
    std::printf("| %d x %d | %+.3f %% | %+.3f %% |\n", m[0], m[1], 100 * (full / ref - 1), 100 * (sri / ref - 1));
    // Full integration locks (too stiff) on coarse meshes; the selective variant does not.
    EXPECT_LT(full, sri);
    EXPECT_LT(std::abs(sri / ref - 1), 0.03);
    prev_err = std::abs(full / ref - 1);
  }
  EXPECT_LT(prev_err, 0.05) << "full integration converges under refinement";
}
