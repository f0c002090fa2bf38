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
  const Vec p = cs.design->initial();
  SensitivityOptions fo;
  fo.method = M::kFdCentral;
  fo.delta = 1e-5;
  const auto ref = compute_sensitivities(cs, p, fo);
  ASSERT_TRUE(ref.ok) << ref.message;
  for (M m : {M::kDirectAnalytic, M::kAdjoint}) {
    SensitivityOptions o;
    o.method = m;
    const auto g = compute_sensitivities(cs, p, o);
    ASSERT_TRUE(g.ok) << g.message;
    const auto d = compare_gradients(g.responses, ref.responses, GradientNorm::kPerResponse);
    EXPECT_LT(d.worst, 1e-6) << SensitivityOptions::name(m) << " " << d.where;
  }
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
}
