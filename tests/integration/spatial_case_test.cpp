// The shipped spatial case (data/spatial/slider_crank_spatial.json, "dimension": 3) read from
// its file and run as a user runs it, against independent references:
//  - the driven slider follows the closed-form loop closure of the spatial slider-crank,
//    y = r cos θ + √(L² − e² − r² sin² θ), and the measured joint translation is y − y(0);
//  - the rod's axis stays a unit vector (the frame constraints) along the rod's two joints;
//  - every sensitivity method on the motor's peak torque and the mean kinetic energy with
//    respect to the rod's mass and the spring's stiffness: direct-analytic, adjoint and
//    semi-analytical against central differences, and against IDAS (GGL, BDF) within the
//    discretization difference;
//  - a spatial case's errors name the JSON path, and a driver that starts away from the
//    assembly is refused as in planar cases (the projection would rotate the crank by 0.5 rad).
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>

#include "lsmbs/io/case.hpp"
#include "lsmbs/runs/simulate.hpp"
#include "lsmbs/runs/static.hpp"
#include "support/gradients.hpp"

using namespace lsmbs;
using json = nlohmann::json;
using M = SensitivityOptions::Method;

namespace {

const std::string kCase = std::string(LSMBS_SOURCE_DIR) + "/data/spatial/slider_crank_spatial.json";

std::string load_error(const json& j) {
  try {
    load_case_json(j, "bad.json", ".");
  } catch (const std::exception& e) {
    return e.what();
  }
  return "no error";
}

// Direct-analytic and adjoint gradients at the initial design against fd-central (δ 1e-5),
// per response to 1e-6.
void expect_direct_and_adjoint_match_central_differences(const Case& cs) {
  const Vec p = cs.design->initial();
  SensitivityOptions fo;
  fo.method = M::kFdCentral;
  fo.delta = 1e-5;
  const auto ref = compute_sensitivities(cs, p, fo);
  ASSERT_TRUE(ref.ok) << ref.message;
  for (M m : {M::kDirectAnalytic, M::kAdjoint}) {
    SensitivityOptions o;
    o.method = m;
    const auto r = compute_sensitivities(cs, p, o);
    ASSERT_TRUE(r.ok) << r.message;
    const auto d = compare_gradients(r.responses, ref.responses, GradientNorm::kPerResponse);
    std::printf("%s against fd-central: %.2e (%s)\n", SensitivityOptions::name(m), d.worst,
                d.where.c_str());
    EXPECT_LT(d.worst, 1e-6) << SensitivityOptions::name(m) << " " << d.where;
  }
}

}  // namespace

TEST(SpatialCase, TheSliderFollowsTheClosedFormLoopClosure) {
  const Case cs = load_case(kCase);
  const SimulationResult r = run_simulation(cs);
  ASSERT_TRUE(r.integrator.ok) << r.integrator.message;
  const auto y = r.column("slider.y"), th = r.column("crank_angle"), s = r.column("stroke");
  const auto ax = r.column("rod_axis.x"), ay = r.column("rod_axis.y"), az = r.column("rod_axis.z");
  const double crank = 0.1, rod = 0.3, e = 0.2;
  double err = 0, stroke_err = 0, unit_err = 0;
  for (size_t i = 0; i < y.size(); ++i) {
    const double ref = crank * std::cos(th[i]) +
                       std::sqrt(rod * rod - e * e - std::pow(crank * std::sin(th[i]), 2));
    err = std::max(err, std::abs(y[i] - ref));
    stroke_err = std::max(stroke_err, std::abs(s[i] - (y[i] - y[0])));
    unit_err = std::max(unit_err, std::abs(std::hypot(ax[i], ay[i], az[i]) - 1));
  }
  EXPECT_GT(th.back(), 2 * 2 * std::numbers::pi);  // more than two turns
  EXPECT_LT(err, 1e-10);
  EXPECT_LT(stroke_err, 1e-10);
  EXPECT_LT(unit_err, 1e-10);
}

// The final stroke of a driven mechanism is kinematic: its gradient is zero, for every method
// (checked in absolute terms; relative errors of zero say nothing). The other two responses are
// compared with relative errors.
TEST(SpatialCase, EverySensitivityMethodAgrees) {
  json j = json::parse(std::ifstream(kCase));
  ASSERT_EQ(j["output"]["responses"].size(), 2u);
  const std::string dir = std::string(LSMBS_SOURCE_DIR) + "/data/spatial";
  json with_stroke = j;
  with_stroke["output"]["responses"].push_back(
      {{"name", "final_stroke"}, {"measure", "stroke"}, {"aggregate", "final"}});
  Case full = load_case_json(with_stroke, kCase, dir);
  for (const auto m : {M::kDirectAnalytic, M::kAdjoint, M::kSemiAnalytical, M::kIdas}) {
    const auto g = test::gradients(full, m);
    for (const auto& r : g.responses)
      if (r.name == "final_stroke") EXPECT_LT(r.gradient.cwiseAbs().maxCoeff(), 1e-12);
  }
  Case cs = load_case_json(j, kCase, dir);
  const auto direct = test::gradients(cs, M::kDirectAnalytic);
  const auto fd = test::gradients(cs, M::kFdCentral);
  const auto adjoint = test::gradients(cs, M::kAdjoint);
  const auto semi = test::gradients(cs, M::kSemiAnalytical);
  const auto idas = test::gradients(cs, M::kIdas);
  std::string where;
  const double e_fd = test::worst_relative(direct, fd, test::Norm::kPerValue, &where);
  std::printf("direct vs central differences %.2e (%s)\n", e_fd, where.c_str());
  EXPECT_LT(e_fd, 1e-4);
  EXPECT_LT(test::worst_relative(adjoint, direct), 1e-9);
  EXPECT_LT(test::worst_relative(semi, direct), 1e-6);
  const double e_idas = test::worst_relative(direct, idas, test::Norm::kPerValue, &where);
  std::printf("direct vs IDAS %.2e (%s)\n", e_idas, where.c_str());
  EXPECT_LT(e_idas, 5e-3);  // h = 0.5 ms against IDAS at 1e-9: the discretization's difference
}

TEST(SpatialCase, BadSpatialInputNamesTheJsonPath) {
  json j = json::parse(std::ifstream(kCase));
  json bad = j;
  bad["bodies"][1]["orientation"][0][0] = 0.5;
  EXPECT_NE(load_error(bad).find("/bodies/1"), std::string::npos) << load_error(bad);
  EXPECT_NE(load_error(bad).find("orientation"), std::string::npos);
  bad = j;
  bad["joints"][2].erase("axis_b");
  EXPECT_NE(load_error(bad).find("/joints/2"), std::string::npos) << load_error(bad);
  bad = j;
  bad["joints"][4]["joint"] = "pin";
  EXPECT_NE(load_error(bad).find("spherical joint has no rotation"), std::string::npos)
      << load_error(bad);
  bad = j;  // the placement check: the motor's law starts 0.5 rad away from the assembled crank
  bad["joints"][4]["law"]["from"] = 0.5;
  EXPECT_NE(load_error(bad).find("body 'crank' does not satisfy the joints and drivers at t = 0: "
                                 "projecting the initial state onto them rotates it by 0.5 rad"),
            std::string::npos)
      << load_error(bad);
  bad = j;
  bad["dimension"] = 4;
  EXPECT_NE(load_error(bad).find("/dimension"), std::string::npos) << load_error(bad);
  bad = j;
  bad["bodies"][0]["type"] = "flexible";
  EXPECT_NE(load_error(bad).find("/bodies/0/type: plane-stress flexible bodies are planar"),
            std::string::npos)
      << load_error(bad);
  bad = j;  // a matrix rounded to 3 digits: the size of the error and the way out are named
  for (auto& row : bad["bodies"][1]["orientation"])
    for (auto& x : row) x = std::round(x.get<double>() * 1000) / 1000;
  EXPECT_NE(load_error(bad).find("{\"axis\": [x, y, z], \"angle\": rad}"), std::string::npos)
      << load_error(bad);
  bad =
      j;  // a second bearing on the crank's axis: redundant rows named once each, no planar advice
  bad["joints"].push_back({{"name", "bearing2"},
                           {"type", "revolute"},
                           {"a", "ground"},
                           {"b", "crank"},
                           {"at", {0, 0, 0}},
                           {"axis", {1, 0, 0}}});
  const std::string redundant = load_error(bad);
  EXPECT_NE(redundant.find("redundant or conflicting"), std::string::npos) << redundant;
  EXPECT_EQ(redundant.find("lock_rotation"), std::string::npos) << redundant;
  for (size_t a = redundant.find("constraint '"); a != std::string::npos;
       a = redundant.find("constraint '", a + 1)) {
    const std::string entry = redundant.substr(a, redundant.find(')', a) - a);
    EXPECT_EQ(redundant.find(entry, a + 1), std::string::npos) << "named twice: " << entry;
  }
  bad = j;
  bad["gravity"] = {0, -9.81};
  EXPECT_NE(load_error(bad).find("/gravity"), std::string::npos) << load_error(bad);
  bad = j;
  bad["output"]["measures"][0]["at"] = {0, 1};
  EXPECT_NE(load_error(bad).find("/output/measures/0/at"), std::string::npos) << load_error(bad);
}

// A body with mass but no principal moments, held at its centre of mass by a spherical joint:
// nothing determines its rotation. The run stops before the first step and says why, with the
// moments, instead of "has no mass" for one of its axis coordinates.
TEST(SpatialCase, ABodyWithoutMomentsOnABallJointIsNamedWithItsMoments) {
  const json j = R"({
    "name": "point_mass_ball", "dimension": 3, "gravity": [0, 0, -9.81],
    "bodies": [{"name": "ball", "type": "rigid", "mass": 1, "inertia": [0, 0, 0],
                "position": [0, 0, 0]}],
    "joints": [{"name": "socket", "type": "spherical", "a": "ground", "b": "ball", "at": [0, 0, 0]}],
    "simulation": {"t_end": 0.01, "h": 0.001},
    "output": {"measures": [{"name": "e", "type": "kinetic_energy"}]}
  })"_json;
  std::string message = "no error";
  try {
    const SimulationResult r = run_simulation(load_case_json(j, "ball.json", "."));
    message = r.integrator.ok ? "ran" : r.integrator.message;
  } catch (const std::exception& e) {
    message = e.what();
  }
  EXPECT_NE(message.find("spatial body 'ball' (e"), std::string::npos) << message;
  EXPECT_NE(message.find("has no rotational inertia about an axis that its joints leave free "
                         "(principal moments I1, I2, I3 = 0, 0, 0 kg m²)"),
            std::string::npos)
      << message;
}

// The misspelt optional-looking key of a joint is named with the required key it replaces.
TEST(SpatialCase, AMisspeltAxisIsNamed) {
  json j = json::parse(std::ifstream(kCase));
  j["joints"][0]["axes"] = j["joints"][0]["axis"];
  j["joints"][0].erase("axis");
  EXPECT_NE(load_error(j).find("/joints/0: missing required key 'axis' (the entry has 'axes': a "
                               "misspelling of it?)"),
            std::string::npos)
      << load_error(j);
}

// The solid cantilever of data/spatial: its tip's mean over three periods against Timoshenko's
// static deflection, the largest drop against twice it (a suddenly applied load), and the
// gradients in E and ρ: direct and adjoint against central differences.
TEST(SpatialCase, TheSolidCantileverMeetsBeamTheoryAndItsGradientsAgree) {
  const Case cs = load_case(std::string(LSMBS_SOURCE_DIR) + "/data/spatial/solid_cantilever.json");
  const SimulationResult r = run_simulation(cs);
  ASSERT_TRUE(r.integrator.ok) << r.integrator.message;
  const double I = 1.0 / 12, E = 1e7, G = E / 2, L = 10;
  const double delta = L * L * L * L / (8 * E * I) + L * L / (2 * 5.0 / 6 * G);
  // the mean of δ(1 − cos ω₁t) over [0, T]: δ(1 − sin(ω₁T)/(ω₁T)), ω₁ Euler–Bernoulli's
  const double w1 = std::pow(1.8751040687, 2) * std::sqrt(E * I / std::pow(L, 4)), T = 0.6;
  const double window_mean = delta * (1 - std::sin(w1 * T) / (w1 * T));
  const double mean = -r.responses.at("mean_tip_z"), drop = -r.responses.at("max_tip_drop");
  std::printf(
      "solid cantilever: mean tip %.5e (reference %.5e), largest drop %.5e, Timoshenko "
      "%.5e\n",
      mean, window_mean, drop, delta);
  EXPECT_NEAR(mean / window_mean, 1, 0.02);
  EXPECT_NEAR(drop / (2 * delta), 1, 0.05);
  expect_direct_and_adjoint_match_central_differences(cs);
}

// Faces of a solid that share an edge tie its nodes once; a node tied to two bodies, a rigid
// body where a solid is expected and the reverse, and an unknown node set are named.
TEST(SpatialCase, SolidConnectionsOnFacesSharingAnEdgeAndMisnamedBodies) {
  json j = json::parse(
      std::ifstream(std::string(LSMBS_SOURCE_DIR) + "/data/spatial/solid_cantilever.json"));
  json both = j;  // a plate clamped on two adjacent faces: no redundant equations
  both["joints"].push_back({{"name", "side"},
                            {"type", "solid_connection"},
                            {"solid", "beam"},
                            {"node_set", "ymin"},
                            {"body", "ground"}});
  EXPECT_EQ(load_error(both), "no error");
  json two = j;  // the tip face to a rigid body, then the top face (sharing an edge) to the ground
  two["bodies"].push_back({{"name", "hub"},
                           {"type", "rigid"},
                           {"mass", 1},
                           {"inertia", {1, 1, 1}},
                           {"position", {10, 0, 0}}});
  two["joints"].push_back({{"name", "tip"},
                           {"type", "solid_connection"},
                           {"solid", "beam"},
                           {"node_set", "xmax"},
                           {"body", "hub"}});
  two["joints"].push_back({{"name", "top"},
                           {"type", "solid_connection"},
                           {"solid", "beam"},
                           {"node_set", "zmax"},
                           {"body", "ground"}});
  EXPECT_NE(load_error(two).find("/joints/2/node_set: "), std::string::npos) << load_error(two);
  EXPECT_NE(load_error(two).find("is tied by 'tip' to another body already"), std::string::npos)
      << load_error(two);
  json torque = j;
  torque["forces"] = {{{"name", "t"}, {"type", "torque"}, {"body", "beam"}, {"torque", {0, 0, 1}}}};
  EXPECT_NE(load_error(torque).find("'beam' is a solid body; a rigid body is expected here"),
            std::string::npos)
      << load_error(torque);
  json set = j;
  set["joints"][0]["node_set"] = "left";
  EXPECT_NE(load_error(set).find("has no node set 'left' (it has xmax, xmin, ymax, ymin, zmax, "
                                 "zmin)"),
            std::string::npos)
      << load_error(set);
}

// data/spatial/solid_arm.json: a 3D plate designed by a 3D level set (two through-holes and a
// pocket). Its mass against the closed-form volume of the plate less the holes and the pocket
// (ρ (V − π r₁² t − π r₂² t − A d), A the super-ellipse's area), within the logistic band's
// stated bias; ∂m/∂r and ∂m/∂d against their closed forms; every response's gradient by the
// direct, adjoint and semi-analytical methods against central differences.
TEST(SpatialCase, TheSolidArmsDesignedPlateHasItsClosedFormMassAndAgreeingGradients) {
  const Case cs = load_case(std::string(LSMBS_SOURCE_DIR) + "/data/spatial/solid_arm.json");
  ASSERT_TRUE(cs.design);
  ASSERT_EQ(cs.design->solid_bodies.size(), 1u);
  const Vec p = cs.design->initial();
  const double rho = 2700, t = 0.01, r1 = p[0], r2 = p[1], d = p[2];
  const double A = 4 * 0.05 * 0.025 * std::pow(std::tgamma(1.25), 2) / std::tgamma(1.5);
  const double m = rho * (0.4 * t * 0.08 - M_PI * (r1 * r1 + r2 * r2) * t - A * d);
  // the tip's sag (6e-6 m) is a small difference of positions near 0.4 m: central differences
  // need a step of 1e-4 (relative) to rise above the Newton iterations' round-off (at 1e-6 they
  // disagree with one another by 2.6e-5; at 1e-4 and 1e-5 by 5e-7)
  SensitivityOptions fo;
  fo.method = M::kFdCentral;
  fo.delta = 1e-4;
  const auto ref = compute_sensitivities(cs, p, fo);
  ASSERT_TRUE(ref.ok) << ref.message;
  const auto& mass = ref.responses[0];
  ASSERT_EQ(mass.name, "plate_mass");
  const double dm[3] = {-rho * 2 * M_PI * r1 * t, -rho * 2 * M_PI * r2 * t, -rho * A};
  std::printf(
      "plate mass %.6e kg (closed form %.6e, rel %.1e); dm/dp %.4e %.4e %.4e (closed form "
      "%.4e %.4e %.4e)\n",
      mass.values[0], m, mass.values[0] / m - 1, mass.gradient(0, 0), mass.gradient(0, 1),
      mass.gradient(0, 2), dm[0], dm[1], dm[2]);
  EXPECT_NEAR(mass.values[0] / m, 1, 3e-3);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(mass.gradient(0, k) / dm[k], 1, 3e-2) << k;
  for (M method : {M::kDirectAnalytic, M::kAdjoint, M::kSemiAnalytical}) {
    SensitivityOptions o;
    o.method = method;
    const auto g = compute_sensitivities(cs, p, o);
    ASSERT_TRUE(g.ok) << g.message;
    const auto diff = compare_gradients(g.responses, ref.responses, GradientNorm::kPerResponse);
    std::printf("%-16s against fd-central: %.2e (%s)\n", SensitivityOptions::name(method),
                diff.worst, diff.where.c_str());
    EXPECT_LT(diff.worst, 2e-6) << diff.where;
  }
}

// The solid cantilever on Gmsh's hexahedra (data/spatial/meshes/beam_hex.msh, the box's cells in
// Gmsh's numbering, clamped and measured on its physical surfaces "root" and "tip"): the same
// responses as the box mesh to round-off, so the Gmsh node order is the element's.
TEST(SpatialCase, TheSolidCantileverOnAGmshMeshIsTheBoxOne) {
  const std::string dir = std::string(LSMBS_SOURCE_DIR) + "/data/spatial";
  json j = json::parse(std::ifstream(dir + "/solid_cantilever.json"));
  const SimulationResult box = run_simulation(load_case_json(j, "box.json", dir));
  j["bodies"][0]["mesh"] = {{"type", "gmsh"}, {"file", "meshes/beam_hex.msh"}};
  j["joints"][0]["node_set"] = "root";
  j["output"]["measures"][0]["node_set"] = "tip";
  j.erase("design");
  const SimulationResult gmsh = run_simulation(load_case_json(j, "gmsh.json", dir));
  ASSERT_TRUE(box.integrator.ok && gmsh.integrator.ok);
  for (const char* r : {"mean_tip_z", "max_tip_drop"}) {
    std::printf("%s: box %.12e, Gmsh %.12e\n", r, box.responses.at(r), gmsh.responses.at(r));
    EXPECT_NEAR(gmsh.responses.at(r) / box.responses.at(r), 1, 1e-9) << r;
  }
  // the formulation is a brick's: given for a mesh of tetrahedra only, it is refused
  j["bodies"][0]["mesh"] = {{"type", "gmsh"}, {"file", "meshes/cube_tets.msh"}};
  j["bodies"][0]["formulation"] = "full";
  std::string e = "no error";
  try {
    load_case_json(j, "tets.json", dir);
  } catch (const std::exception& x) {
    e = x.what();
  }
  EXPECT_NE(e.find("/bodies/0/formulation: applies to hexahedra"), std::string::npos) << e;
}

// A bar of a solid body hanging from the ground under its weight (ν = 0, so the stress is
// uniaxial: the nominal stress σ = ρg(L − s) at height s above the free end). Linear theory gives
// the elongation ρgL²/(2E) and the strain energy ρ²g²AL³/(6E); St Venant–Kirchhoff's
// σ = E(u′ + 3u′²/2 + u′³/2) stiffens it to second order in ρgL/E: u′ = σ/E − 3/2 (σ/E)²,
// elongation ρgL²/(2E) − (ρg/E)²L³/2, and ψ = E/2 (u′ + u′²/2)² = σ²/(2E) (1 − 2σ/E), energy
// ρ²g²AL³/(6E) − A(ρg)³L⁴/(4E²). Linear elements under consistent loads have exact nodal
// displacements and the element-mean stress, so n of them miss A/(2E)·L·(ρgL/n)²/12 of the
// energy. Released from rest, the gradients of the two measures with respect to E and ρ
// (direct, adjoint) agree with central differences.
TEST(SpatialCase, AHangingSolidBarsElongationAndStrainEnergyMeetTheClosedForms) {
  const double E = 1e7, rho = 1000, g = 9.81, L = 1, A = 0.01;
  json j = {{"dimension", 3},
            {"gravity", {0, 0, -g}},
            {"bodies",
             {{{"name", "bar"},
               {"type", "solid"},
               {"mesh",
                {{"type", "box"},
                 {"origin", {-0.05, -0.05, -L}},
                 {"size", {0.1, 0.1, L}},
                 {"elements", {1, 1, 16}}}},
               {"material", {{"E", E}, {"nu", 0}, {"rho", rho}}}}}},
            {"joints",
             {{{"name", "hang"},
               {"type", "solid_connection"},
               {"solid", "bar"},
               {"node_set", "zmax"},
               {"body", "ground"}}}},
            {"simulation", {{"t_end", 0.02}, {"h", 5e-4}}},
            {"output",
             {{"measures",
               {{{"name", "stretch"},
                 {"type", "elongation"},
                 {"body", "bar"},
                 {"a", "zmin"},
                 {"b", "zmax"}},
                {{"name", "W"}, {"type", "strain_energy"}}}},
              {"responses",
               {{{"name", "mean_stretch"}, {"measure", "stretch"}, {"aggregate", "average"}},
                {{"name", "final_W"}, {"measure", "W"}, {"aggregate", "final"}}}}}},
            {"design",
             {{"variables",
               {{{"name", "E"}, {"initial", E}, {"lower", E / 2}, {"upper", 2 * E}},
                {{"name", "rho"}, {"initial", rho}, {"lower", rho / 2}, {"upper", 2 * rho}}}},
              {"parameters",
               {{{"parameter", "bar.E"}, {"variable", "E"}},
                {{"parameter", "bar.rho"}, {"variable", "rho"}}}}}}};
  const Case cs = load_case_json(j, "hanging_bar.json", ".");
  const StaticRunResult st = run_static(cs);
  ASSERT_TRUE(st.solver.ok) << st.solver.message;
  const double w = rho * g, n = 16;
  const double stretch = w * L * L / (2 * E) - (w / E) * (w / E) * L * L * L / 2;
  const double W = w * w * A * L * L * L / (6 * E) - A * w * w * w * std::pow(L, 4) / (4 * E * E) -
                   A / (2 * E) * L * std::pow(w * L / n, 2) / 12;
  std::printf("hanging bar: elongation %.6e (closed form %.6e), strain energy %.6e (%.6e)\n",
              st.responses.at("mean_stretch"), stretch, st.responses.at("final_W"), W);
  EXPECT_NEAR(st.responses.at("mean_stretch") / stretch, 1, 1e-5);
  EXPECT_NEAR(st.responses.at("final_W") / W, 1, 1e-5);
  expect_direct_and_adjoint_match_central_differences(cs);
}

// IDAS (GGL, BDF) on a designed solid: a plate clamped at one end, a hole drilled through it
// (its radius and position the design variables, a 3D level set), its tip loaded by a force
// ramped up smoothly (1 − cos) so that no mode beyond the integrators' resolution is excited.
// IDAS differentiates the continuous problem, direct-analytic the generalized-α solution: the
// two gradients of the mean tip deflection approach each other at the scheme's second order as
// h is halved, and direct-analytic agrees with central differences.
TEST(SpatialCase, IdasOnADesignedSolidAgreesWithTheDirectMethodAsHShrinks) {
  json j = {{"dimension", 3},
            {"gravity", {0, 0, 0}},
            {"bodies",
             {{{"name", "plate"},
               {"type", "solid"},
               {"mesh",
                {{"type", "box"},
                 {"origin", {0, -0.02, -0.005}},
                 {"size", {0.2, 0.04, 0.01}},
                 {"elements", {8, 2, 1}}}},
               {"material", {{"E", 7e10}, {"nu", 0.3}, {"rho", 2700}}}},
              {{"name", "tip"},
               {"type", "rigid"},
               {"mass", 0.2},
               {"inertia", {1e-5, 1e-5, 1e-5}},
               {"position", {0.21, 0, 0}}}}},
            {"joints",
             {{{"name", "clamp"},
               {"type", "solid_connection"},
               {"solid", "plate"},
               {"node_set", "xmin"},
               {"body", "ground"}},
              {{"name", "tie"},
               {"type", "solid_connection"},
               {"solid", "plate"},
               {"node_set", "xmax"},
               {"body", "tip"}}}},
            {"forces",
             {{{"name", "push"},
               {"type", "point_force"},
               {"body", "tip"},
               {"at", {0.21, 0, 0}},
               // −20 (1 − cos(π t / 0.025)) / 2 N, then −20 N: a natural cubic spline through it
               {"fz",
                {{"type", "table"},
                 {"points",
                  {{0, 0},
                   {0.005, -1.91},
                   {0.01, -6.91},
                   {0.015, -13.09},
                   {0.02, -18.09},
                   {0.025, -20},
                   {0.03, -20}}}}}}}},
            {"simulation", {{"t_end", 0.03}, {"h", 5e-4}}},
            {"output",
             {{"measures",
               {{{"name", "tipz"},
                 {"type", "node_set_position"},
                 {"body", "plate"},
                 {"node_set", "xmax"}}}},
              {"responses",
               {{{"name", "mean_tip_z"}, {"measure", "tipz.z"}, {"aggregate", "average"}}}}}},
            {"design",
             {{"variables",
               {{{"name", "r"}, {"initial", 0.01}, {"lower", 0.004}, {"upper", 0.014}},
                {{"name", "cx"}, {"initial", 0.08}, {"lower", 0.05}, {"upper", 0.15}}}},
              {"geometry",
               {{{"body", "plate"},
                 {"subgrid", 8},
                 {"features",
                  {{{"name", "hole"},
                    {"type", "through_hole"},
                    {"face", "zmax"},
                    {"profile", "circle"},
                    {"cx", "cx"},
                    {"cy", 0},
                    {"r", "r"}}}}}}}}}};
  Case cs = load_case_json(j, "designed_plate.json", ".");
  const Vec p = cs.design->initial();
  SensitivityOptions fo;
  fo.method = M::kFdCentral;
  fo.delta = 1e-4;
  const auto ref = compute_sensitivities(cs, p, fo);
  ASSERT_TRUE(ref.ok) << ref.message;
  const auto direct = compute_sensitivities(cs, p, {});
  ASSERT_TRUE(direct.ok) << direct.message;
  const auto dfd = compare_gradients(direct.responses, ref.responses, GradientNorm::kPerResponse);
  std::printf("designed plate, direct-analytic against fd-central: %.2e\n", dfd.worst);
  EXPECT_LT(dfd.worst, 1e-5);
  double previous = 0;
  for (double h : {1e-3, 5e-4, 2.5e-4}) {
    cs.simulation.h = h;
    SensitivityOptions io;
    io.method = M::kIdas;
    const auto ri = compute_sensitivities(cs, p, io);
    ASSERT_TRUE(ri.ok) << ri.message;
    const auto rd = compute_sensitivities(cs, p, {});
    ASSERT_TRUE(rd.ok) << rd.message;
    const double d =
        compare_gradients(rd.responses, ri.responses, GradientNorm::kPerResponse).worst;
    std::printf("h = %.2e: d(mean tip z)/d(r, cx) direct %.6e %.6e, IDAS %.6e %.6e: %.2e\n", h,
                rd.responses[0].gradient(0, 0), rd.responses[0].gradient(0, 1),
                ri.responses[0].gradient(0, 0), ri.responses[0].gradient(0, 1), d);
    if (previous > 0) EXPECT_GT(previous / d, 2.5);
    previous = d;
  }
  EXPECT_LT(previous, 1e-3);
}

// Designs of solid bodies refuse what planar designs refuse, with the JSON path: a
// super-ellipsoid's orientation that is no rotation (it would resize the shape), a feature
// outside the part that no value within its variables' bounds brings in (one they can bring in is
// accepted), measures on node sets a body lacks (the sets it has are named); two coinciding
// features are reported as in planar designs (their min has a kink: a one-sided gradient).
TEST(SpatialCase, SolidDesignsRefuseWhatPlanarDesignsRefuse) {
  const json base =
      json::parse(std::ifstream(std::string(LSMBS_SOURCE_DIR) + "/data/spatial/solid_arm.json"));
  json bad = base;
  json& features = bad["design"]["geometry"][0]["features"];
  features[0] = {{"name", "blob"}, {"type", "super_ellipsoid"},
                 {"cx", 0.1},      {"cy", 0},
                 {"cz", 0},        {"a", "r1"},
                 {"b", 0.01},      {"c", 0.01},
                 {"xi", 4},        {"orientation", {{1, 0, 0}, {0, 1, 0}, {0, 0, 2}}}};
  std::string e = load_error(bad);
  EXPECT_NE(e.find("/design/geometry/0/features/0/orientation"), std::string::npos) << e;
  EXPECT_NE(e.find("expected a rotation"), std::string::npos) << e;
  bad = base;  // a sphere 1 m away whose centre moves by at most 0.3 m: never in
  bad["design"]["variables"].push_back(
      {{"name", "sx"}, {"initial", 1.2}, {"lower", 0.9}, {"upper", 1.2}});
  bad["design"]["geometry"][0]["features"].push_back(
      {{"name", "far"}, {"type", "sphere"}, {"cx", "sx"}, {"cy", 0}, {"cz", 0}, {"r", 0.01}});
  e = load_error(bad);
  EXPECT_NE(e.find("'far' lies wholly outside body 'plate'"), std::string::npos) << e;
  EXPECT_NE(e.find("no values of its design variables within their bounds bring it in"),
            std::string::npos)
      << e;
  bad["design"]["variables"].back()["lower"] = 0.35;  // now it can reach the plate: accepted
  EXPECT_EQ(load_error(bad), "no error");
  bad = base;
  bad["output"]["measures"].push_back({{"name", "stretch"},
                                       {"type", "elongation"},
                                       {"body", "plate"},
                                       {"a", "xmin"},
                                       {"b", "tip"}});
  e = load_error(bad);
  EXPECT_NE(e.find("/output/measures/3/b"), std::string::npos) << e;
  EXPECT_NE(e.find("(it has xmax, xmin, ymax, ymin, zmax, zmin)"), std::string::npos) << e;
  json twins = base;  // hole 2 drawn on hole 1: the same circle, two variables
  twins["design"]["geometry"][0]["features"][1]["cx"] = 0.1;
  twins["design"]["variables"][1]["initial"] = 0.02;
  const Case cs = load_case_json(twins, "twins.json", ".");
  const std::string w = cs.design->coincident_features(cs.design->initial());
  EXPECT_NE(w.find("body 'plate': two level-set features coincide"), std::string::npos) << w;
  const Case ok = load_case(std::string(LSMBS_SOURCE_DIR) + "/data/spatial/solid_arm.json");
  EXPECT_EQ(ok.design->coincident_features(ok.design->initial()), "");
}
