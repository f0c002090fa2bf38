// Invalid case files fail with the file, the JSON path and what was expected.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <set>

#include "lsmbs/core/error.hpp"
#include "lsmbs/io/model_kinds.hpp"
#include "lsmbs/io/sha256.hpp"
#include "support/test_models.hpp"

using namespace lsmbs;
using json = nlohmann::json;

namespace {

json minimal() {
  return R"({
    "name": "pendulum",
    "gravity": [0, -9.81],
    "bodies": [{"name": "bob", "type": "rigid", "position": [1, 0], "mass": 1, "inertia": 0.1}],
    "joints": [{"name": "pin", "type": "revolute", "a": {"body": "bob", "at": [-1, 0]}, "b": "ground"}],
    "simulation": {"t_end": 0.1, "h": 0.01}
  })"_json;
}

// Returns the error message of loading `j` (empty if it loads).
std::string error_of(const json& j) {
  try {
    test::make_case(j);
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(CaseLoader, ConstraintForceMeasureInAnyOrderLoadsAndDuplicatesAreRefused) {
  // a constraint_force measure is a placeholder until the model is final: measures after it
  // used to dereference it (segfault) while checking for duplicate names
  for (int first : {0, 1}) {
    json j = minimal();
    json cf = {{"name", "pin_force"}, {"type", "constraint_force"}, {"joint", "pin"}};
    json ang = {{"name", "theta"}, {"type", "angle"}, {"body", "bob"}};
    json pos = {{"name", "p"}, {"type", "position"}, {"point", {{"body", "bob"}}}};
    j["output"]["measures"] =
        first == 0 ? json::array({cf, ang, pos}) : json::array({ang, cf, pos});
    const Case cs = test::make_case(j);
    ASSERT_EQ(cs.measures.size(), 3u);
    for (const auto& m : cs.measures) EXPECT_TRUE(m != nullptr);
    j["output"]["measures"].push_back({{"name", "pin_force"}, {"type", "angle"}, {"body", "bob"}});
    EXPECT_NE(error_of(j).find("duplicate measure name 'pin_force'"), std::string::npos)
        << error_of(j);
  }
}

TEST(CaseLoader, MinimalCaseLoads) {
  const Case cs = test::make_case(minimal());
  EXPECT_EQ(cs.model->nq(), 3);
  EXPECT_EQ(cs.model->nc(), 2);
}

struct BadInput {
  const char* label;
  const char* json_patch;  // RFC 6902 patch applied to minimal()
  const char* expected;    // substring of the message
};

class CaseLoaderErrors : public ::testing::TestWithParam<BadInput> {};

TEST_P(CaseLoaderErrors, MessageNamesThePathAndWhatWasExpected) {
  const auto& p = GetParam();
  const json j = minimal().patch(json::parse(p.json_patch));
  const std::string msg = error_of(j);
  ASSERT_FALSE(msg.empty()) << p.label << ": no error raised";
  EXPECT_NE(msg.find("<test>"), std::string::npos) << msg;
  EXPECT_NE(msg.find(p.expected), std::string::npos) << p.label << ": " << msg;
}

INSTANTIATE_TEST_SUITE_P(
    Table, CaseLoaderErrors,
    ::testing::Values(
        BadInput{"unknown key", R"([{"op":"add","path":"/bodies/0/thickess","value":1}])",
                 "/bodies/0/thickess: unknown key"},
        BadInput{"negative mass", R"([{"op":"replace","path":"/bodies/0/mass","value":-1}])",
                 "/bodies/0/mass: expected a non-negative number"},
        BadInput{"wrong type", R"([{"op":"replace","path":"/bodies/0/mass","value":"heavy"}])",
                 "/bodies/0/mass: expected a number, got string"},
        BadInput{"unknown body type",
                 R"([{"op":"replace","path":"/bodies/0/type","value":"soft"}])",
                 "/bodies/0/type: expected one of \"rigid\", \"flexible\""},
        BadInput{"unknown body in joint",
                 R"([{"op":"replace","path":"/joints/0/a/body","value":"bobb"}])",
                 "/joints/0/a/body: unknown body 'bobb'"},
        BadInput{"missing time step", R"([{"op":"remove","path":"/simulation/h"}])",
                 "/simulation: missing required key 'h'"},
        BadInput{"zero time step", R"([{"op":"replace","path":"/simulation/h","value":0}])",
                 "/simulation/h: expected a positive number"},
        BadInput{"rho_inf out of range",
                 R"([{"op":"add","path":"/simulation/rho_inf","value":1.5}])",
                 "/simulation/rho_inf: expected a value in [0, 1]"},
        BadInput{"duplicate names", R"([{"op":"replace","path":"/joints/0/name","value":"bob"}])",
                 "/joints/0/name: duplicate name 'bob'"},
        BadInput{"point not an object", R"([{"op":"replace","path":"/joints/0/a","value":3}])",
                 "/joints/0/a: expected a point object"},
        BadInput{"vector of wrong size",
                 R"([{"op":"replace","path":"/bodies/0/position","value":[1,2,3]}])",
                 "/bodies/0/position: expected an array of two numbers"},
        BadInput{
            "unconstrained massless body",
            R"([{"op":"replace","path":"/bodies/0/mass","value":0},{"op":"replace","path":"/bodies/0/inertia","value":0},{"op":"remove","path":"/joints/0"}])",
            "rigid body 'bob' has no mass and no joint"},
        BadInput{"no bodies", R"([{"op":"replace","path":"/bodies","value":[]}])",
                 "/bodies: expected at least one body"},
        BadInput{"unknown joint type",
                 R"([{"op":"replace","path":"/joints/0/type","value":"hinge"}])",
                 "/joints/0/type: expected one of"},
        BadInput{"t_end not a multiple of h",
                 R"([{"op":"replace","path":"/simulation/h","value":0.03}])",
                 "/simulation/h: t_end = "},
        BadInput{
            "response window after the run",
            R"([{"op":"add","path":"/output","value":{"measures":[{"name":"a","type":"angle","body":"bob"}],"responses":[{"name":"r","measure":"a","aggregate":"average","window":{"t0":0.5,"t1":0.6}}]}}])",
            "/output/responses/0/window: the window"},
        BadInput{
            "response window between two steps",
            R"([{"op":"add","path":"/output","value":{"measures":[{"name":"a","type":"angle","body":"bob"}],"responses":[{"name":"r","measure":"a","aggregate":"max","window":{"t0":0.051,"t1":0.059}}]}}])",
            "contains no time step"},
        BadInput{
            "negative node-set tolerance",
            R"([{"op":"add","path":"/bodies/-","value":{"name":"p","type":"flexible","mesh":{"type":"rectangle","size":[1,0.1],"elements":[2,1]},"material":{"E":1e9,"nu":0.3,"rho":1000},"thickness":0.001,"node_sets":{"tip":{"line_x":1,"tolerance":-1}}}}])",
            "/bodies/1/node_sets/tip/tolerance: expected a positive number"},
        BadInput{"unknown ordering",
                 R"([{"op":"add","path":"/simulation/ordering","value":"metis"}])",
                 "/simulation/ordering: expected one of \"amd\", \"nested_dissection\""},
        BadInput{
            "negative thickness",
            R"([{"op":"add","path":"/bodies/-","value":{"name":"p","type":"flexible","mesh":{"type":"rectangle","size":[1,0.1],"elements":[2,1]},"material":{"E":1e9,"nu":0.3,"rho":1000},"thickness":-0.001}}])",
            "/bodies/1/thickness: expected a positive number"},
        BadInput{
            "empty node set",
            R"([{"op":"add","path":"/bodies/-","value":{"name":"p","type":"flexible","mesh":{"type":"rectangle","size":[1,0.1],"elements":[2,1]},"material":{"E":1e9,"nu":0.3,"rho":1000},"thickness":0.001,"node_sets":{"far":{"line_x":5}}}}])",
            "/bodies/1/node_sets/far: the selector selects no node"},
        BadInput{
            "unknown node set",
            R"([{"op":"add","path":"/bodies/-","value":{"name":"p","type":"flexible","mesh":{"type":"rectangle","size":[1,0.1],"elements":[2,1]},"material":{"E":1e9,"nu":0.3,"rho":1000},"thickness":0.001}},{"op":"add","path":"/joints/-","value":{"type":"clamp","flexible":"p","node_set":"middle"}}])",
            "/joints/1/node_set: body 'p' has no node set 'middle'"},
        BadInput{
            "Poisson ratio",
            R"([{"op":"add","path":"/bodies/-","value":{"name":"p","type":"flexible","mesh":{"type":"rectangle","size":[1,0.1],"elements":[2,1]},"material":{"E":1e9,"nu":0.5,"rho":1000},"thickness":0.001}}])",
            "/bodies/1/material/nu: expected Poisson's ratio in [0, 0.5)"},
        BadInput{
            "torque on a flexible body",
            R"([{"op":"add","path":"/bodies/-","value":{"name":"p","type":"flexible","mesh":{"type":"rectangle","size":[1,0.1],"elements":[2,1]},"material":{"E":1e9,"nu":0.3,"rho":1000},"thickness":0.001}},{"op":"add","path":"/forces","value":[{"type":"torque","body":"p","torque":1}]}])",
            "/forces/0/body: 'p' is a flexible body; a rigid body is expected here"},
        BadInput{
            "torque on an unknown body",
            R"([{"op":"add","path":"/forces","value":[{"type":"torque","body":"bobb","torque":1}]}])",
            "/forces/0/body: unknown rigid body 'bobb'"},
        BadInput{
            "torque and law both given",
            R"([{"op":"add","path":"/forces","value":[{"type":"torque","body":"bob","torque":1,"law":{"type":"constant","value":2}}]}])",
            "/forces/0: expected either \"torque\": T or \"law\": {...} (one of them)"},
        BadInput{"torque without torque or law",
                 R"([{"op":"add","path":"/forces","value":[{"type":"torque","body":"bob"}]}])",
                 "/forces/0: expected either \"torque\": T or \"law\""},
        BadInput{
            "torque given as a string",
            R"([{"op":"add","path":"/forces","value":[{"type":"torque","body":"bob","torque":"big"}]}])",
            "/forces/0/torque: expected a number, got string"},
        BadInput{
            "torque with a misspelt key",
            R"([{"op":"add","path":"/forces","value":[{"type":"torque","body":"bob","torque":1,"sacle":2}]}])",
            "/forces/0/sacle: unknown key"},
        BadInput{
            "torque law of unknown type",
            R"([{"op":"add","path":"/forces","value":[{"type":"torque","body":"bob","law":{"type":"sine"}}]}])",
            "/forces/0/law/type: expected one of \"trapezoid\", \"ramp\", \"table\", \"constant\""},
        BadInput{
            "rotational spring to an unknown body",
            R"([{"op":"add","path":"/forces","value":[{"type":"rotational_spring_damper","a":"bob","b":"rob","stiffness":1}]}])",
            "/forces/0/b: unknown rigid body 'rob'"},
        BadInput{
            "rotational spring on itself",
            R"([{"op":"add","path":"/forces","value":[{"type":"rotational_spring_damper","a":"bob","b":"bob","stiffness":1}]}])",
            "/forces/0/b: a rotational spring cannot connect a body to itself"},
        BadInput{
            "rotational spring without b",
            R"([{"op":"add","path":"/forces","value":[{"type":"rotational_spring_damper","a":"bob","stiffness":1}]}])",
            "/forces/0: missing required key 'b'"},
        BadInput{
            "rotational spring with negative stiffness",
            R"([{"op":"add","path":"/forces","value":[{"type":"rotational_spring_damper","a":"bob","b":"ground","stiffness":-1}]}])",
            "/forces/0/stiffness: expected a non-negative number, got -1"},
        BadInput{
            "rotational spring with a misspelt key",
            R"([{"op":"add","path":"/forces","value":[{"type":"rotational_spring_damper","a":"bob","b":"ground","stiffness":1,"free_angel":0}]}])",
            "/forces/0/free_angel: unknown key"},
        BadInput{
            "periodic table whose ends differ",
            R"([{"op":"add","path":"/forces","value":[{"type":"torque","body":"bob","law":{"type":"table","points":[[0,0],[1,1],[2,0.5]],"period":2}}]}])",
            "/forces/0/law/points: table: a periodic table must end with its first value: s(x0) = "
            "0 but s(x0 + period) = 0.5"},
        BadInput{
            "periodic table longer than its period",
            R"([{"op":"add","path":"/forces","value":[{"type":"torque","body":"bob","law":{"type":"table","points":[[0,0],[1,1],[3,0]],"period":2}}]}])",
            "/forces/0/law/points: table: the points span 3, more than the period 2"},
        BadInput{
            "angular velocity of a flexible body",
            R"([{"op":"add","path":"/bodies/-","value":{"name":"p","type":"flexible","mesh":{"type":"rectangle","size":[1,0.1],"elements":[2,1]},"material":{"E":1e9,"nu":0.3,"rho":1000},"thickness":0.001}},{"op":"add","path":"/output","value":{"measures":[{"name":"w","type":"angular_velocity","body":"p"}]}}])",
            "/output/measures/0/body: 'p' is a flexible body; a rigid body is expected here"},
        BadInput{
            "velocity of a point on an unknown body",
            R"([{"op":"add","path":"/output","value":{"measures":[{"name":"v","type":"velocity","point":{"body":"rob"}}]}}])",
            "/output/measures/0/point/body: unknown body 'rob'"},
        BadInput{
            "velocity measure with a misspelt key",
            R"([{"op":"add","path":"/output","value":{"measures":[{"name":"v","type":"velocity","piont":{"body":"bob"}}]}}])",
            "/output/measures/0: missing required key 'point'"},
        BadInput{
            "duplicate measure name after a constraint force",
            R"([{"op":"add","path":"/output","value":{"measures":[{"name":"f","type":"constraint_force","joint":"pin"},{"name":"f","type":"angular_velocity","body":"bob"}]}}])",
            "/output/measures/1/name: duplicate measure name 'f'"}),
    [](const auto& info) {
      std::string s = info.param.label;
      for (char& c : s)
        if (!isalnum(static_cast<unsigned char>(c))) c = '_';
      return s;
    });

namespace {
json with_design() {
  json j = minimal();
  j["bodies"].push_back(
      R"({"name": "p", "type": "flexible", "mesh": {"type": "rectangle", "size": [0.1, 0.02], "elements": [10, 2]},
                             "material": {"E": 1e9, "nu": 0.3, "rho": 1000}, "thickness": 0.001})"_json);
  j["design"] = R"({"variables": [{"name": "r", "initial": 0.005, "lower": 0.001, "upper": 0.008}],
                    "geometry": [{"body": "p", "features": [{"name": "hole", "type": "circle", "cx": 0.05, "cy": 0.01, "r": "r"}]}]})"_json;
  return j;
}
}  // namespace

namespace {

// Void mass of the designed plate "p": the solid plate's mass minus the designed one.
double void_mass(const Case& cs) {
  return 1000 * 0.001 * 0.1 * 0.02 - cs.model->find_flexible("p")->mass(cs.model->params());
}

// Mass of the designed plate "p" at the one-variable design p = [r].
double mass_at(const Case& cs, double r) {
  Vec p(1);
  p[0] = r;
  ModelParams pp = cs.model->params();
  cs.design->apply(p, pp, nullptr);
  return cs.model->find_flexible("p")->mass(pp);
}

// Area added to a convex hole by the logistic smoothing H(φ/ε) of a distance φ (ε = band × the
// sub-cell size): the void fraction 1 − H differs from the sharp one by an odd function of φ,
// whose first moment ∫ φ (1 − H − 1_{φ<0}) dφ = π²ε²/6 weights the boundary's curvature; with
// ∮ κ ds = 2π that is π³ε²/3 whatever the shape.
double band_area(double element, double subgrid = 8, double band = 0.5) {
  const double eps = band * element / subgrid;
  return std::pow(M_PI, 3) * eps * eps / 3;
}

}  // namespace

TEST(CaseLoader, DesignSectionSetsTheInitialMaterialField) {
  // the circle's void mass ρ t π r² (1 − μ_min), on the 10 mm mesh of with_design() and on 2.5 mm
  const double rho_t = 1000 * 0.001, r = 0.005, mu_min = 1e-3, area = M_PI * r * r;
  const Case coarse = test::make_case(with_design());
  ASSERT_TRUE(coarse.design);
  json j = with_design();
  j["bodies"][1]["mesh"]["elements"] = {40, 8};
  const Case fine = test::make_case(j);
  const double m10 = void_mass(coarse), m25 = void_mass(fine), ref = rho_t * area * (1 - mu_min);
  std::printf(
      "circle r = 5 mm: void mass %+.3f %% (10 mm mesh), %+.3f %% (2.5 mm) of the closed form; "
      "with the "
      "band's area: %+.4f %%, %+.4f %%\n",
      100 * (m10 / ref - 1), 100 * (m25 / ref - 1),
      100 * (m10 / (ref + rho_t * (1 - mu_min) * band_area(0.01)) - 1),
      100 * (m25 / (ref + rho_t * (1 - mu_min) * band_area(0.0025)) - 1));
  // the logistic band adds π²ε²/(3r²) to the area: 5.1 % with ε = 0.625 mm (10 mm elements),
  // 0.32 % with 0.156 mm; what remains is the sub-cell quadrature (measured ≤ 1.1e-5): 2e-4
  EXPECT_NEAR(m25 / ref, 1.0, 0.02);
  EXPECT_NEAR(m10 / (ref + rho_t * (1 - mu_min) * band_area(0.01)), 1.0, 2e-4);
  EXPECT_NEAR(m25 / (ref + rho_t * (1 - mu_min) * band_area(0.0025)), 1.0, 2e-4);
}

TEST(CaseLoader, SuperEllipseHoleHasItsClosedFormArea) {
  // eq. (43), |x/a|^ξ + |y/b|^η ≤ 1: area 4ab Γ(1 + 1/ξ) Γ(1 + 1/η) / Γ(1 + 1/ξ + 1/η), here on a
  // 2.5 mm mesh, rotated by 0.4 rad, loaded through the design section
  json j = with_design();
  j["bodies"][1]["mesh"]["elements"] = {40, 8};
  j["design"]["geometry"][0]["features"] = json::array({{{"name", "se"},
                                                         {"type", "super_ellipse"},
                                                         {"cx", 0.05},
                                                         {"cy", 0.01},
                                                         {"a", 0.012},
                                                         {"b", 0.006},
                                                         {"xi", 4},
                                                         {"eta", 3},
                                                         {"angle", 0.4}}});
  const Case cs = test::make_case(j);
  const double area = 4 * 0.012 * 0.006 * std::tgamma(1 + 1 / 4.0) * std::tgamma(1 + 1 / 3.0) /
                      std::tgamma(1 + 1 / 4.0 + 1 / 3.0);
  const double m = void_mass(cs), ref = 1000 * 0.001 * area * (1 - 1e-3);
  const double with_band = 1000 * 0.001 * (area + band_area(0.0025)) * (1 - 1e-3);
  std::printf(
      "super-ellipse: void mass %.6e kg, closed form %.6e kg (%+.3f %%), with the band's area "
      "%+.4f %%\n",
      m, ref, 100 * (m / ref - 1), 100 * (m / with_band - 1));
  // the band adds 0.10 %; the rest is the sub-cell quadrature and the rounded corners of the
  // super-ellipse, where κ is large (measured 4e-5): 5e-4
  EXPECT_NEAR(m / ref, 1.0, 0.005);
  EXPECT_NEAR(m / with_band, 1.0, 5e-4);
}

TEST(CaseLoader, BadDesignBindingsNameTheJsonPath) {
  struct Bad {
    const char* patch;
    const char* expected;
  };
  const Bad bad[] = {
      {R"([{"op":"replace","path":"/design/geometry/0/features/0/r","value":"rr"}])",
       "/design/geometry/0/features/0/r: unknown design variable 'rr'"},
      {R"([{"op":"replace","path":"/design/variables/0/initial","value":0.01}])",
       "/design/variables/0/initial: initial value 0.01 is outside its bounds"},
      {R"([{"op":"replace","path":"/design/variables/0/lower","value":-0.001}])",
       "feature 'hole' is degenerate within the design bounds: radius r must be non-negative"},
      {R"([{"op":"replace","path":"/design/geometry/0/body","value":"bob"}])",
       "/design/geometry/0/body: 'bob' is a rigid body; a flexible body is expected here"},
      {R"([{"op":"add","path":"/design/geometry/0/region","value":{"and":["hole","slot"]}}])",
       "/design/geometry/0/region/and/1: unknown feature 'slot'"},
      {R"([{"op":"add","path":"/design/parameters","value":[{"parameter":"bob.massive","variable":"r"}]}])",
       "/design/parameters/0/parameter: unknown model parameter 'bob.massive'"},
  };
  for (const auto& b : bad) {
    const std::string msg = error_of(with_design().patch(json::parse(b.patch)));
    EXPECT_NE(msg.find(b.expected), std::string::npos) << b.patch << "\n  got: " << msg;
  }
}

TEST(CaseLoader, DesignVariableBoundToAModelParameter) {
  json j = with_design();
  j["design"]["variables"].push_back(
      R"({"name": "m", "initial": 2.5, "lower": 1, "upper": 5})"_json);
  j["design"]["parameters"] =
      R"([{"parameter": "bob.mass", "variable": "m", "scale": 2, "offset": 0.1}])"_json;
  const Case cs = test::make_case(j);
  EXPECT_DOUBLE_EQ(cs.model->params().scalars[cs.model->parameter_index("bob.mass")], 5.1);
}

TEST(Sha256, MatchesTheFipsTestVectors) {
  EXPECT_EQ(sha256_hex("abc"), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  EXPECT_EQ(sha256_hex(""), "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
  EXPECT_EQ(sha256_hex("abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq"),
            "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");
}

TEST(CaseLoader, TorqueAndRotationalSpringParameters) {
  json j = minimal();
  j["bodies"].push_back(
      R"({"name": "arm", "type": "rigid", "position": [0, 1], "angle": 0.25, "mass": 1, "inertia": 0.1})"_json);
  j["bodies"][0]["angle"] = 1.0;
  j["forces"] = R"([
    {"name": "motor", "type": "torque", "body": "bob", "law": {"type": "ramp", "speed": 2, "ramp_time": 0.5}},
    {"name": "fixed", "type": "torque", "body": "arm", "torque": -3, "scale": 0.5},
    {"name": "shaft", "type": "rotational_spring_damper", "a": "bob", "b": "arm", "stiffness": 10, "damping": 0.5},
    {"name": "anchor", "type": "rotational_spring_damper", "a": "arm", "b": "ground", "stiffness": 7, "free_angle": -0.5}
  ])"_json;
  const Case cs = test::make_case(j);
  const Model& m = *cs.model;
  auto par = [&](const std::string& n) {
    const int i = m.parameter_index(n);
    EXPECT_GE(i, 0) << n;
    return i >= 0 ? m.params().scalars[i] : NAN;
  };
  EXPECT_EQ(par("motor.scale"), 1.0);
  EXPECT_EQ(par("fixed.scale"), 0.5);
  EXPECT_EQ(par("shaft.stiffness"), 10.0);
  EXPECT_EQ(par("shaft.damping"), 0.5);
  EXPECT_EQ(par("shaft.free_angle"), 1.0 - 0.25) << "default: the initial relative angle θa − θb";
  EXPECT_EQ(par("anchor.damping"), 0.0);
  EXPECT_EQ(par("anchor.free_angle"), -0.5);
  // the torque law: r_θ = −scale T(t), T = speed·t²/(2 ramp_time) during the ramp
  State s = cs.initial;
  s.t = 0.3;
  Vec R;
  const double k = 1;
  m.residual(s, m.params(), k, 0, R);
  const int th = m.find_rigid("bob")->dof0 + 2, th_arm = m.find_rigid("arm")->dof0 + 2;
  EXPECT_NEAR(R[th], -(2 * 0.3 * 0.3 / (2 * 0.5)), 1e-15)
      << "the springs are at their free angles, bob has no load";
  EXPECT_NEAR(R[th_arm], 3 * 0.5 + 7 * (0.25 + 0.5), 1e-14);
}

TEST(CaseLoader, PeriodicTableFileErrorNamesTheJsonPathAndTheFile) {
  const std::string f = testing::TempDir() + "bad_period.csv";
  {
    std::FILE* out = std::fopen(f.c_str(), "w");
    std::fputs("0, 1\n1, 2\n2, 1.5\n", out);
    std::fclose(out);
  }
  json j = minimal();
  j["forces"] = json::array({{{"type", "torque"},
                              {"body", "bob"},
                              {"law", {{"type", "table"}, {"file", f}, {"period", 2}}}}});
  const std::string msg = error_of(j);
  EXPECT_NE(msg.find("<test>: /forces/0/law/file: " + f +
                     ": table: a periodic table must end with its first value"),
            std::string::npos)
      << msg;
}

TEST(CaseLoader, RedundantOrConflictingConstraintsAreRefusedNamingTheJoints) {
  // independent reference: the slider-crank has 10 independent constraint equations; a second
  // copy of a bearing adds 2 dependent ones, a second prismatic joint along y locks the piston's
  // rotation twice (1 dependent) — both seen at load time, naming the added joint
  const std::string file =
      std::string(LSMBS_SOURCE_DIR) + "/data/slider_crank_rigid/slider_crank_spring.json";
  const json base = json::parse(std::ifstream(file));
  EXPECT_EQ(error_of(base), "");
  json dup = base;
  json bearing = base["joints"][0];
  bearing["name"] = "main_bearing_2";
  dup["joints"].push_back(bearing);
  const std::string e1 = error_of(dup);
  EXPECT_NE(e1.find("/joints: 2 of the 10 constraint equations are redundant"), std::string::npos)
      << e1;
  EXPECT_NE(e1.find("'main_bearing_2'"), std::string::npos) << e1;
  json two = base;
  two["joints"].push_back({{"name", "cyl2"},
                           {"type", "prismatic"},
                           {"a", {{"body", "piston"}, {"at", {0, 0}}}},
                           {"direction", {0, 1}}});
  const std::string e2 = error_of(two);
  EXPECT_NE(e2.find("1 of the 10 constraint equations"), std::string::npos) << e2;
  EXPECT_NE(e2.find("'cyl2'"), std::string::npos) << e2;
}

TEST(CaseLoader, NonDesignFeatureStaysSolidWithExactDerivatives) {
  // A circular hole of radius r = 5 mm (variable) and a non-design disc of 2 mm at its centre
  // (OR-ed with the region): the void is the annulus π(r² − 2²) (the logistic band adds
  // π³ε²/3 to the convex hole and takes as much from the convex disc), ∂(void mass)/∂r is the
  // hole's closed form ρ t 2πr (1 − μ_min), which the disc does not touch. A disc that covers
  // part of the hole's boundary takes that part off the derivative: ∂m/∂r is then checked
  // against central differences of the mapped mass.
  json j = with_design();
  j["bodies"][1]["mesh"]["elements"] = {40, 8};
  j["design"]["geometry"][0]["features"].push_back({{"name", "keep"},
                                                    {"type", "circle"},
                                                    {"cx", 0.05},
                                                    {"cy", 0.01},
                                                    {"r", 0.002},
                                                    {"non_design", true}});
  const Case cs = test::make_case(j);
  const double rho_t = 1000 * 0.001, r = 0.005, mu_min = 1e-3;
  const double ref = rho_t * M_PI * (r * r - 0.002 * 0.002) * (1 - mu_min);
  const double m = void_mass(cs);
  std::vector<SpMat> dmu;
  ModelParams params = cs.model->params();
  cs.design->apply(cs.design->initial(), params, &dmu);
  Vec g;
  Design::mass_gradient(cs.design->bodies[0], dmu[0], params, g);
  const double dref = rho_t * 2 * M_PI * r * (1 - mu_min);
  std::printf("annulus: void mass %+.4f %% of the closed form, -dm/dr %+.4f %%\n",
              100 * (m / ref - 1), 100 * (-g[0] / dref - 1));
  EXPECT_NEAR(m / ref, 1.0, 1e-3);
  EXPECT_NEAR(-g[0] / dref, 1.0, 1e-3);

  // a non-design disc of 4 mm centred on the hole's boundary (x = 55 mm)
  j["design"]["geometry"][0]["features"][1]["cx"] = 0.055;
  j["design"]["geometry"][0]["features"][1]["r"] = 0.004;
  const Case c2 = test::make_case(j);
  ModelParams p2 = c2.model->params();
  c2.design->apply(c2.design->initial(), p2, &dmu);
  Design::mass_gradient(c2.design->bodies[0], dmu[0], p2, g);
  const double h = 1e-6, fd = (mass_at(c2, r + h) - mass_at(c2, r - h)) / (2 * h);
  std::printf("disc on the boundary: dm/dr %.6e, central difference %.6e, hole alone %.6e\n", g[0],
              fd, -dref);
  EXPECT_NEAR(g[0] / fd, 1.0, 1e-4);
  EXPECT_GT(g[0], -0.9 * dref) << "the disc does not take its part of the boundary";

  // errors: a non-design hole, a region naming a non-design feature, only non-design features
  json only = j;
  only["design"]["geometry"][0]["features"][0]["non_design"] = true;
  EXPECT_THROW(test::make_case(only), Error) << "every feature non_design left the body void";
  json bad = j;
  bad["design"]["geometry"][0]["features"][1]["hole"] = true;
  EXPECT_THROW(test::make_case(bad), Error);
  bad = j;
  bad["design"]["geometry"][0]["region"] = {{"and", {"hole", "keep"}}};
  try {
    test::make_case(bad);
    ADD_FAILURE() << "a region naming a non-design feature was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("/design/geometry/0/region: feature 'keep' is non_design"),
              std::string::npos)
        << e.what();
  }
}

// Two hole features that coincide (a second circle of the same radius on the first, a skeptical
// user's case; linked symmetric features at their common position are the same): the exact AND
// is min(D1, D2) with D1 = D2, its derivative with respect to r1 is one-sided (all of the hole's
// boundary, or none of it), and central differences of the mapped mass average the two: the
// exact gradient is −ρ t 2πr (1 − μ_min) on one side and 0 on the other, the central difference
// half of it. The design point is reported; 2 mm apart, with "ks", or with the two circles
// crossing, nothing is.
TEST(CaseLoader, CoincidentFeaturesAreReportedWithTheirOneSidedGradient) {
  json j = with_design();
  j["bodies"][1]["mesh"]["elements"] = {40, 8};
  j["design"]["geometry"][0]["features"].push_back(
      {{"name", "twin"}, {"type", "circle"}, {"cx", 0.05}, {"cy", 0.01}, {"r", 0.005}});
  const Case cs = test::make_case(j);
  const Vec p0 = cs.design->initial();
  const std::string w = cs.design->coincident_features(p0);
  std::printf("%s\n", w.c_str());
  EXPECT_NE(w.find("two level-set features coincide"), std::string::npos) << w;
  std::vector<SpMat> dmu;
  ModelParams params = cs.model->params();
  cs.design->apply(p0, params, &dmu);
  Vec g;
  Design::mass_gradient(cs.design->bodies[0], dmu[0], params, g);
  const double h = 1e-6, fd = (mass_at(cs, 0.005 + h) - mass_at(cs, 0.005 - h)) / (2 * h);
  const double one_side = -1000 * 0.001 * 2 * M_PI * 0.005 * (1 - 1e-3);
  std::printf("coincident: dm/dr %.6e, central difference %.6e, one side %.6e\n", g[0], fd,
              one_side);
  EXPECT_NEAR(fd / (0.5 * one_side), 1.0, 2e-3);  // the average of the two sides
  EXPECT_TRUE(std::abs(g[0] / one_side - 1) < 2e-3 || std::abs(g[0]) < 1e-3 * std::abs(one_side))
      << "the exact combination's derivative is one side's";

  for (const auto& [what, edit] : std::vector<std::pair<std::string, std::function<void(json&)>>>{
           {"2 mm apart", [](json& c) { c["design"]["geometry"][0]["features"][1]["cx"] = 0.052; }},
           {"ks",
            [](json& c) {
              c["design"]["geometry"][0]["region"] = {{"and", {"hole", "twin"}}, {"ks", 2000}};
            }},
           {"crossing",
            [](json& c) { c["design"]["geometry"][0]["features"][1]["cx"] = 0.0575; }}}) {
    json k = j;
    edit(k);
    const Case ck = test::make_case(k);
    EXPECT_EQ(ck.design->coincident_features(ck.design->initial()), "") << what;
  }
}

// The table of model kinds (io/model_kinds.hpp) is what the loader reads joints, forces, measures
// and feature parameters with: its feature parameters are the geometry's own, in the order the
// level set takes them (Feature::parameter_names); every other kind has a reader; names are unique;
// an unknown type is refused with the table's types, and a key no kind reads with its path.
TEST(ModelKinds, TheTableIsTheLoadersVocabulary) {
  std::set<std::pair<std::string, std::string>> seen;
  for (const ModelKind& k : model_kinds()) {
    EXPECT_TRUE(seen.insert({k.section, k.type}).second) << k.section << " " << k.type;
    std::set<std::string> keys;
    for (const KindKey& key : k.keys) EXPECT_TRUE(keys.insert(key.name).second) << key.name;
    EXPECT_FALSE(k.doc.empty()) << k.type;
    if (k.section == "features") {
      bool ok = false;
      std::vector<std::string> params;
      for (const KindKey& key : k.keys)
        if (key.type == KeyType::kParameter) params.push_back(key.name);
      EXPECT_EQ(params, Feature::parameter_names(Feature::parse_type(k.type, &ok))) << k.type;
      EXPECT_TRUE(ok) << k.type;
    } else {
      EXPECT_TRUE(static_cast<bool>(k.read)) << k.type;
    }
  }
  for (const char* section : {"joints", "forces", "measures", "features"})
    EXPECT_FALSE(kind_types(section).empty()) << section;
  // the spatial table: unique names and keys, a reader each, and documented in the spatial
  // section of docs/case-format.md (every kind and every key)
  std::ifstream doc(std::string(LSMBS_SOURCE_DIR) + "/docs/case-format.md");
  const std::string text((std::istreambuf_iterator<char>(doc)), std::istreambuf_iterator<char>());
  const size_t from = text.find("## Spatial cases"), to = text.find("\n## ", from + 1);
  ASSERT_NE(from, std::string::npos);
  const std::string spatial_doc = text.substr(from, to - from);
  std::set<std::pair<std::string, std::string>> spatial_seen;
  for (const ModelKind& k : spatial_model_kinds()) {
    EXPECT_TRUE(spatial_seen.insert({k.section, k.type}).second) << k.section << " " << k.type;
    EXPECT_TRUE(static_cast<bool>(k.read)) << k.type;
    EXPECT_FALSE(k.doc.empty()) << k.type;
    // a table row of the section that starts with the type and names every key
    bool documented = false;
    for (size_t row = spatial_doc.find("| `" + k.type + "` |");
         row != std::string::npos && !documented;
         row = spatial_doc.find("| `" + k.type + "` |", row + 1)) {
      const std::string line = spatial_doc.substr(row, spatial_doc.find('\n', row) - row);
      documented = true;
      for (const KindKey& key : k.keys)
        documented = documented && line.find("`" + key.name + "`") != std::string::npos;
    }
    EXPECT_TRUE(documented) << "docs/case-format.md, Spatial cases: no row of " << k.type
                            << " names all its keys";
  }
  json j = R"({"name": "m", "bodies": [{"name": "b", "type": "rigid", "mass": 1, "inertia": 1}],
               "joints": [{"name": "pin", "type": "hinge", "a": {"body": "b"}}],
               "simulation": {"t_end": 0.1, "h": 0.01}})"_json;
  try {
    test::make_case(j);
    ADD_FAILURE() << "an unknown joint type loaded";
  } catch (const Error& e) {
    EXPECT_EQ(e.json_path(), "/joints/0/type");
    for (const auto& t : kind_types("joints"))
      EXPECT_NE(std::string(e.what()).find('"' + t + '"'), std::string::npos) << t;
  }
  j["joints"][0] = {{"name", "pin"}, {"type", "revolute"}, {"a", {{"body", "b"}}}, {"bee", 1}};
  try {
    test::make_case(j);
    ADD_FAILURE() << "an unknown key loaded";
  } catch (const Error& e) {
    EXPECT_EQ(e.json_path(), "/joints/0/bee");
  }
}

// A design built in code (Design::add_variable, add_geometry with a GeometrySpec, bind) is the
// case file's: the hole-and-kept-disc geometry of NonDesignFeatureStaysSolidWithExactDerivatives
// written as Design calls on the case's own body maps to the same μ_e and ∂μ/∂p, bit for bit; a
// feature degenerate within the bounds, one off its body that nothing moves and a parameter bound
// twice are refused naming the feature or the field, as the loader words them.
TEST(DesignInCode, AddGeometryMapsAsTheCaseFile) {
  json j = with_design();
  j["bodies"][1]["mesh"]["elements"] = {40, 8};
  j["design"]["geometry"][0]["features"].push_back({{"name", "keep"},
                                                    {"type", "circle"},
                                                    {"cx", 0.05},
                                                    {"cy", 0.01},
                                                    {"r", 0.002},
                                                    {"non_design", true}});
  const Case cs = test::make_case(j);
  const auto& file_features = cs.design->bodies[0].map->level_set().features();
  const FlexibleBody& body = *cs.design->bodies[0].body;
  Design d;
  const auto& v = cs.design->variables[0];
  d.add_variable(v.name, v.initial, v.lower, v.upper);
  GeometrySpec spec;
  spec.features.push_back(file_features[0]);  // the hole, its parameters as the file binds them
  spec.non_design.push_back(
      Feature("keep", Feature::Type::kCircle,
              {Design::constant(0.05), Design::constant(0.01), Design::constant(0.002)}, false));
  spec.options = cs.design->bodies[0].map->options();
  d.add_geometry(body, spec);
  Vec mu_file, mu_code;
  SpMat dmu_file, dmu_code;
  cs.design->bodies[0].map->map(cs.design->initial(), mu_file, &dmu_file);
  d.bodies[0].map->map(d.initial(), mu_code, &dmu_code);
  ASSERT_EQ(mu_file.size(), mu_code.size());
  EXPECT_EQ((mu_file - mu_code).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(SpMat(dmu_file - dmu_code).norm(), 0.0);

  // refusals, with the loader's words
  Design twice;
  twice.add_variable(v.name, v.initial, v.lower, v.upper);
  twice.add_geometry(body, spec);
  try {
    twice.add_geometry(body, spec);
    ADD_FAILURE() << "a body with two geometries was accepted";
  } catch (const SetupError& e) {
    EXPECT_EQ(e.subject(), "design.geometry");
  }
  GeometrySpec flat = spec;
  flat.features = {Feature("flat", Feature::Type::kCircle,
                           {Design::constant(0.05), Design::constant(0.01), d.variable(v.name, -1)},
                           true)};  // r = −p: negative over the whole range
  Design degenerate;
  degenerate.add_variable(v.name, v.initial, v.lower, v.upper);
  try {
    degenerate.add_geometry(body, flat);
    ADD_FAILURE() << "a degenerate feature was accepted";
  } catch (const SetupError& e) {
    EXPECT_EQ(e.entity(), "flat");
    EXPECT_NE(e.reason().find("is degenerate within the design bounds"), std::string::npos)
        << e.reason();
  }
  GeometrySpec far = spec;
  far.non_design = {Feature("far", Feature::Type::kCircle,
                            {Design::constant(5), Design::constant(5), Design::constant(0.002)},
                            false)};
  Design outside;
  outside.add_variable(v.name, v.initial, v.lower, v.upper);
  try {
    outside.add_geometry(body, far);
    ADD_FAILURE() << "a feature off its body that nothing moves was accepted";
  } catch (const SetupError& e) {
    EXPECT_EQ(e.entity(), "far");
    EXPECT_NE(e.reason().find("lies wholly outside body"), std::string::npos) << e.reason();
  }
  Design bound;
  bound.add_variable("k", 1, 0.5, 2);
  bound.bind(0, "k", 1, 0, "x.stiffness");
  try {
    bound.bind(0, "k", 1, 0, "x.stiffness");
    ADD_FAILURE() << "a parameter bound twice was accepted";
  } catch (const SetupError& e) {
    EXPECT_EQ(e.field(), "parameter");
    EXPECT_EQ(e.reason(), "parameter 'x.stiffness' is bound twice");
  }
  try {
    bound.add_variable("k", 1, 2, 0.5);
    ADD_FAILURE() << "a duplicate variable was accepted";
  } catch (const SetupError& e) {
    EXPECT_EQ(e.field(), "name");
  }
}
