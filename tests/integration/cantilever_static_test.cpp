// Static cantilever plate 0.6 × 0.05 m, 2.5 mm, E = 72 GPa, ν = 0.3, clamped at x = 0, tip
// shear load P on the free edge: the tip deflection against Timoshenko beam theory
//   δ = P L³ / (3 E I) + P L / (κ G A),  κ = 5/6,
// for the mesh used by the robot arm (120 × 10), and the mesh convergence of both integration
// variants: second order towards one limit, which lies within 0.2 % of beam theory (a fully
// clamped root edge and a uniform edge shear are not beam theory's assumptions).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

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

// The rectangle's "tri3" mesh as a Gmsh MSH 4.1 ASCII file: node k at (i, j) has tag k + 1 (the
// rectangle's numbering), each quad (i, j) split along its diagonal from the lower left, the left
// edge's nodes in the physical line "left".
std::string write_gmsh(int nx, int ny, const std::string& dir) {
  const std::string path = dir + "/cantilever_tri3.msh";
  std::FILE* f = std::fopen(path.c_str(), "w");
  auto id = [&](int i, int j) { return j * (nx + 1) + i + 1; };
  const int nn = (nx + 1) * (ny + 1), ne = 2 * nx * ny;
  std::fprintf(f,
               "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$PhysicalNames\n1\n1 1 \"left\"\n"
               "$EndPhysicalNames\n$Entities\n0 1 1 0\n1 %.17g %.17g 0 %.17g %.17g 0 1 1 0\n"
               "1 0 %.17g 0 %.17g %.17g 0 0 0\n$EndEntities\n",
               0.0, -H / 2, 0.0, H / 2, -H / 2, L, H / 2);
  std::fprintf(f, "$Nodes\n1 %d 1 %d\n2 1 0 %d\n", nn, nn, nn);
  for (int k = 1; k <= nn; ++k) std::fprintf(f, "%d\n", k);
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i)
      std::fprintf(f, "%.17g %.17g 0\n", L * i / nx, -H / 2 + H * j / ny);
  std::fprintf(f, "$EndNodes\n$Elements\n2 %d 1 %d\n1 1 1 %d\n", ne + ny, ne + ny, ny);
  int tag = 1;
  for (int j = 0; j < ny; ++j) std::fprintf(f, "%d %d %d\n", tag++, id(0, j), id(0, j + 1));
  std::fprintf(f, "2 1 2 %d\n", ne);
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      std::fprintf(f, "%d %d %d %d\n", tag++, id(i, j), id(i + 1, j), id(i + 1, j + 1));
      std::fprintf(f, "%d %d %d %d\n", tag++, id(i, j), id(i + 1, j + 1), id(i, j + 1));
    }
  std::fprintf(f, "$EndElements\n");
  std::fclose(f);
  return path;
}

// The cantilever "beam" clamped on its left edge, an nx × ny rectangle mesh of `cells`, no load.
json cantilever(int nx, int ny, const std::string& integration = "selective-shear",
                const std::string& cells = "quad4") {
  return {{"name", "cantilever"},
          {"bodies",
           {{{"name", "beam"},
             {"type", "flexible"},
             {"mesh",
              {{"type", "rectangle"},
               {"origin", {0, -H / 2}},
               {"size", {L, H}},
               {"elements", {nx, ny}},
               {"cells", cells}}},
             {"material", {{"E", E}, {"nu", NU}, {"rho", 2700}}},
             {"thickness", T},
             {"integration", integration}}}},
          {"joints", {{{"type", "clamp"}, {"flexible", "beam"}, {"node_set", "left"}}}},
          {"simulation", {{"t_end", 1}, {"h", 1}}}};
}

// Tip deflection (centre node of the loaded edge) for an nx × ny mesh of `cells` (quadrilaterals,
// or each split into two triangles: the same nodes). With `gmsh_dir`, the same triangles are
// written as a Gmsh MSH 4.1 file (the left edge a physical line "left") and read back.
double tip_deflection(int nx, int ny, const std::string& integration,
                      const std::string& cells = "quad4", const std::string& gmsh_dir = "") {
  json j = cantilever(nx, ny, integration, cells);
  // Uniform shear on the free edge: consistent nodal loads P/ny (P/2ny at the corners).
  json forces = json::array();
  for (int k = 0; k <= ny; ++k) {
    const int node = k * (nx + 1) + nx;
    const double f = (k == 0 || k == ny ? 0.5 : 1.0) * P / ny;
    forces.push_back({{"type", "point_force"},
                      {"point", {{"body", "beam"}, {"node", node}}},
                      {"force", {0, -f}}});
  }
  j["forces"] = forces;
  if (!gmsh_dir.empty())
    j["bodies"][0]["mesh"] = {{"type", "gmsh"}, {"file", write_gmsh(nx, ny, gmsh_dir)}};
  Case cs = test::make_case(j);
  State s = cs.initial;
  const auto r = solve_static(*cs.model, cs.model->params(), s);
  EXPECT_TRUE(r.ok) << r.message;
  const int centre = (ny / 2) * (nx + 1) + nx;
  return -(s.q[2 * centre + 1] - cs.initial.q[2 * centre + 1]);
}

}  // namespace

TEST(CantileverStatic, TipDeflectionOfTheRobotArmMeshIsWithinPointFourPercentOfTimoshenko) {
  const double ref = timoshenko();
  const double d = tip_deflection(120, 10, "selective-shear");
  std::printf("Timoshenko %.6e m, selective-shear 120x10 %.6e m (%+.3f %%)\n", ref, d,
              100 * (d / ref - 1));
  // the mesh-converged limit is 0.15 % stiffer than beam theory and this mesh 0.12 % stiffer
  // than that limit (test below): 0.4 % bounds both with room for neither to double
  EXPECT_NEAR(d / ref, 1.0, 0.004);
}

TEST(CantileverStatic, MeshConvergenceIsSecondOrderTowardsBeamTheory) {
  const double ref = timoshenko();
  std::printf("| mesh | full 2x2 Gauss | selective shear |\n|---|---|---|\n");
  const int meshes[][2] = {{24, 2}, {60, 5}, {120, 10}, {240, 20}, {480, 40}};
  std::vector<double> full, sri;
  for (const auto& m : meshes) {
    full.push_back(tip_deflection(m[0], m[1], "full") / ref - 1);
    sri.push_back(tip_deflection(m[0], m[1], "selective-shear") / ref - 1);
    std::printf("| %d x %d | %+.3f %% | %+.3f %% |\n", m[0], m[1], 100 * full.back(),
                100 * sri.back());
    // full integration locks (too stiff) on coarse meshes; the selective variant much less
    EXPECT_LT(full.back(), sri.back());
  }
  for (const auto* e : {&full, &sri}) {
    const auto& v = *e;
    // successive differences δ_h − δ_h/2 fall about fourfold (second order) once h ≤ 10 mm
    // (60 × 5; 24 × 2, two elements across the height, is not yet asymptotic). The clamped
    // corners are stress singularities of plane elasticity, which take the observed order a
    // little below 2 (measured 1.94 full, 1.85–1.88 selective): 2 ± 0.25.
    for (size_t i = 1; i + 2 < v.size(); ++i) {
      const double order = std::log2((v[i] - v[i + 1]) / (v[i + 1] - v[i + 2]));
      std::printf("%s: observed order %.3f\n", e == &full ? "full" : "selective shear", order);
      EXPECT_NEAR(order, 2.0, 0.25);
    }
  }
  // Richardson extrapolation of the two finest meshes: both variants converge to one limit, within
  // 0.2 % of beam theory (the clamped root edge without Poisson contraction stiffens the plate)
  const double lim_full = full[4] + (full[4] - full[3]) / 3,
               lim_sri = sri[4] + (sri[4] - sri[3]) / 3;
  std::printf("extrapolated limits: full %+.4f %%, selective shear %+.4f %%\n", 100 * lim_full,
              100 * lim_sri);
  EXPECT_NEAR(lim_full, lim_sri, 1e-4);
  EXPECT_LT(std::abs(lim_sri), 2e-3);
}

// The three-node triangle (fem/tri_element.hpp) on the same nodes: constant-strain triangles are
// stiff in bending, so on each mesh the deflection lies below the quadrilateral's, but they
// converge to the same limit (Richardson extrapolation of the two finest meshes, at the observed
// order); read from a Gmsh file of the same triangles, the deflection is the rectangle's to
// round-off (the reader and the element registry, not the mesher, made the body).
TEST(CantileverStatic, TrianglesConvergeToTheQuadrilateralsLimitAndReadTheSameFromGmsh) {
  const double ref = timoshenko();
  const int meshes[][2] = {{60, 5}, {120, 10}, {240, 20}};
  std::vector<double> tri, quad;
  for (const auto& m : meshes) {
    tri.push_back(tip_deflection(m[0], m[1], "selective-shear", "tri3") / ref - 1);
    quad.push_back(tip_deflection(m[0], m[1], "selective-shear") / ref - 1);
    std::printf("%d x %d: tri3 %+.3f %%, quad4 %+.3f %%\n", m[0], m[1], 100 * tri.back(),
                100 * quad.back());
    EXPECT_LT(tri.back(), quad.back());
  }
  const double order = std::log2((tri[0] - tri[1]) / (tri[1] - tri[2]));
  const double lim_tri = tri[2] + (tri[2] - tri[1]) / (std::pow(2.0, order) - 1),
               lim_quad = quad[2] + (quad[2] - quad[1]) / 3;
  std::printf("tri3: observed order %.3f, extrapolated %+.4f %%; quad4 %+.4f %%\n", order,
              100 * lim_tri, 100 * lim_quad);
  EXPECT_NEAR(order, 2.0, 0.3);
  EXPECT_NEAR(lim_tri, lim_quad, 2e-3);
  const double from_gmsh = tip_deflection(60, 5, "selective-shear", "tri3", testing::TempDir());
  EXPECT_NEAR(from_gmsh / ref - 1, tri[0], 1e-12);
}

// The static convergence test is row by row, as the dynamic Newton iteration's: a body far away
// that carries a huge force (1e12 N through its pin) must not loosen the test on the cantilever.
// With one global force scale (the largest row's), the cantilever under a load that bends it
// well into the nonlinear range (tip ≈ 7.5 % of its length) was accepted after Newton iterations
// that left its residual at ~1e2 N (tol_r × 1e12). Reference: the cantilever alone.
TEST(StaticSolver, AHugeForceOnAnotherBodyDoesNotLoosenTheConvergenceOfTheRest) {
  auto solve = [](bool anchor) {
    const int nx = 24, ny = 2;
    json j = cantilever(nx, ny);
    j["forces"] = {{{"type", "point_force"},
                    {"point", {{"body", "beam"}, {"node", ny / 2 * (nx + 1) + nx}}},
                    {"force", {0, -1200.0}}}};
    if (anchor) {
      j["bodies"].push_back({{"name", "anchor"},
                             {"type", "rigid"},
                             {"position", {2, 0}},
                             {"mass", 1},
                             {"inertia", 1}});
      j["joints"].push_back(
          {{"type", "revolute"}, {"a", {{"body", "anchor"}, {"at", {0, 0}}}}, {"b", "ground"}});
      j["joints"].push_back({{"type", "rotation_driver"},
                             {"body", "anchor"},
                             {"law", {{"type", "constant"}, {"value", 0}}}});
      j["forces"].push_back({{"type", "point_force"},
                             {"point", {{"body", "anchor"}, {"at", {0, 0}}}},
                             {"force", {0, -1e12}}});
    }
    Case cs = test::make_case(j);
    State s = cs.initial;
    const auto r = solve_static(*cs.model, cs.model->params(), s);
    EXPECT_TRUE(r.ok) << r.message;
    const int tip = ny / 2 * (nx + 1) + nx;
    return Vec2(s.q.segment<2>(cs.model->flexible_bodies()[0]->node_dof(tip)));
  };
  const Vec2 alone = solve(false), with_anchor = solve(true);
  std::printf("tip alone (%.12e, %.12e), with the anchor (%.12e, %.12e)\n", alone.x(), alone.y(),
              with_anchor.x(), with_anchor.y());
  EXPECT_LT(-(alone.y()) / L, 0.3);
  EXPECT_GT(-(alone.y()) / L, 0.05);  // well into the geometrically nonlinear range
  EXPECT_LT((with_anchor - alone).norm(), 1e-9 * L);
}
