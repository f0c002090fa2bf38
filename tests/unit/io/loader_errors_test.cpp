// Input errors that had no test: each must throw lsmbs::Error whose message names the JSON path
// (or the command-line option) and what was expected; the command line exits 2 on them.
// Response windows, unknown phases and columns, the optimization section, tables and laws,
// sensitivities without a design or responses, --delta ≤ 0, verify --set with an unknown variable.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <optional>
#include <tuple>

#include "lsmbs/core/error.hpp"
#include "lsmbs/core/text.hpp"
#include "lsmbs/io/case.hpp"
#include "lsmbs/io/optimization_spec.hpp"
#include "lsmbs/mbs/model_builder.hpp"
#include "lsmbs/optimization/problem.hpp"
#include "lsmbs/sensitivity/sensitivity.hpp"
#include "support/test_models.hpp"

using namespace lsmbs;
using json = nlohmann::json;

namespace {

// A driven pendulum with a trapezoid law (phases accelerate, constant, decelerate), a spring as
// design parameter, one response and an optimization section.
json base() {
  return R"({
    "name": "errors",
    "bodies": [{"name": "bob", "type": "rigid", "position": [1, 0], "mass": 1, "inertia": 0.1}],
    "joints": [{"name": "pin", "type": "revolute", "a": {"body": "bob", "at": [-1, 0]}, "b": "ground"},
               {"name": "motor", "type": "rotation_driver", "body": "bob",
                "law": {"type": "trapezoid", "from": 0, "to": 1, "acceleration": 4, "speed": 1}}],
    "forces": [{"name": "spring", "type": "spring_damper", "a": {"body": "bob"}, "b": {"ground": [2, 0]},
                "stiffness": 100, "damping": 1}],
    "simulation": {"t_end": 1.5, "h": 0.01},
    "output": {
      "measures": [{"name": "bob", "type": "position", "point": {"body": "bob"}}],
      "responses": [{"name": "mean_x", "measure": "bob.x", "aggregate": "average"}]
    },
    "design": {"variables": [{"name": "k", "initial": 100, "lower": 10, "upper": 1000}],
               "parameters": [{"parameter": "spring.stiffness", "variable": "k"}]},
    "optimization": {"objective": "mean_x", "constraints": [{"response": "mean_x", "upper": 2}]}
  })"_json;
}

// Expects load_case_json (and, when `optimization`, parse_optimization) to throw an Error whose
// message contains the JSON path and the phrase.
void expect_error(const json& j, const std::string& path, const std::string& phrase,
                  bool optimization = false) {
  try {
    Case cs = test::make_case(j);
    if (optimization) parse_optimization(cs);
    ADD_FAILURE() << "no error; expected " << path << ": " << phrase;
  } catch (const Error& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find(path + ":"), std::string::npos) << "path " << path << " not in: " << msg;
    EXPECT_NE(msg.find(phrase), std::string::npos) << "'" << phrase << "' not in: " << msg;
    std::printf("  %s\n", msg.c_str());
  }
}

json with_response(const json& r) {
  json j = base();
  j["output"]["responses"].push_back(r);
  return j;
}

}  // namespace

TEST(LoaderErrors, ResponseWindows) {
  expect_error(with_response({{"name", "r"},
                              {"measure", "bob.x"},
                              {"aggregate", "max"},
                              {"window", {{"t0", 0.8}, {"t1", 0.2}}}}),
               "/output/responses/1/window/t1", "expected t1 >= t0");
  expect_error(with_response({{"name", "r"},
                              {"measure", "bob.x"},
                              {"aggregate", "max"},
                              {"window", {{"driver", "motor"}, {"phase", "cruise"}}}}),
               "/output/responses/1/window/phase",
               "driver 'motor' has no phase 'cruise' (phases: accelerate, constant, decelerate)");
  expect_error(with_response({{"name", "r"},
                              {"measure", "bob.x"},
                              {"aggregate", "max"},
                              {"window", {{"driver", "engine"}, {"phase", "constant"}}}}),
               "/output/responses/1/window/driver", "unknown driver 'engine'");
  expect_error(with_response({{"name", "r"}, {"measure", "bob.z"}, {"aggregate", "max"}}),
               "/output/responses/1/measure", "unknown measure column 'bob.z'");
  expect_error(with_response({{"name", "r"}, {"measure", "bob.x"}, {"aggregate", "median"}}),
               "/output/responses/1/aggregate", "expected one of");
  expect_error(with_response({{"name", "r"}, {"measure", "bob.x"}, {"aggregate", "ks"}}),
               "/output/responses/1", "missing required key 'ks'");
  expect_error(with_response({{"name", "mean_x"}, {"measure", "bob.x"}, {"aggregate", "max"}}),
               "/output/responses/1/name", "duplicate response name 'mean_x'");
  expect_error(with_response({{"name", "r"},
                              {"measure", "bob.x"},
                              {"aggregate", "max"},
                              {"window", {{"t0", 2}, {"t1", 3}}}}),
               "/output/responses/1/window", "contains no time step of the run");
}

TEST(LoaderErrors, OptimizationSection) {
  auto opt = [](const json& patch) {
    json j = base();
    j["optimization"].merge_patch(patch);
    return j;
  };
  expect_error(opt({{"objective", "mass"}}), "/optimization/objective", "unknown response 'mass'",
               true);
  expect_error(opt({{"optimizer", "bfgs"}}), "/optimization/optimizer", "expected one of", true);
  expect_error(opt({{"move_limit", 0.2}}), "/optimization/move_limit",
               "needs \"optimizer\": \"mma-svanberg\"", true);
  expect_error(opt({{"optimizer", "mma-svanberg"}, {"move_limit", 1.5}}),
               "/optimization/move_limit", "expected a fraction of the variable range in (0, 1]",
               true);
  expect_error(opt({{"optimizer", "mma-svanberg"}, {"move_limit", 0}}), "/optimization/move_limit",
               "expected a positive", true);
  expect_error(opt({{"optimizer", "mma-svanberg"}, {"inner_max_evaluations", 3}}),
               "/optimization/inner_max_evaluations", "the classic MMA has no inner iterations",
               true);
  expect_error(opt({{"sensitivity", {{"method", "adjoint-continuous"}}}}),
               "/optimization/sensitivity/method", "expected one of", true);
  expect_error(opt({{"sensitivity", {{"threads", 3}}}}), "/optimization/sensitivity/threads",
               "expected 1 or 2", true);
  expect_error(opt({{"sensitivity", {{"delta", -1e-6}}}}), "/optimization/sensitivity/delta",
               "expected a positive", true);
  expect_error(opt({{"sensitivity", {{"matrix", "newest"}}}}), "/optimization/sensitivity/matrix",
               "expected last, converged or refined", true);
  expect_error(opt({{"stop", {{"max_evaluations", 0}}}}), "/optimization/stop/max_evaluations", "",
               true);
  expect_error(opt({{"stop", {{"tolerance", 1e-3}}}}), "/optimization/stop/tolerance",
               "unknown key", true);
  expect_error(opt({{"constraints", {{{"response", "mean_x"}, {"upper", 0}}}}}),
               "/optimization/constraints/0/upper", "a zero bound needs \"scale\"", true);
  json no_design = base();
  no_design.erase("design");
  expect_error(no_design, "/design", "optimization needs a design section", true);
}

TEST(LoaderErrors, TablesAndLaws) {
  auto law = [](const json& l) {
    json j = base();
    j["joints"][1]["law"] = l;
    return j;
  };
  const std::string at = "/joints/1/law";
  expect_error(law({{"type", "sine"}}), at + "/type",
               "expected one of \"trapezoid\", \"ramp\", \"table\", \"constant\"");
  expect_error(
      law({{"type", "trapezoid"}, {"from", 0}, {"to", 1}, {"acceleration", -4}, {"speed", 1}}),
      at + "/acceleration", "expected a positive number");
  expect_error(
      law({{"type", "trapezoid"}, {"from", 0}, {"to", 1}, {"acceleration", 4}, {"speed", 0}}),
      at + "/speed", "expected a positive number");
  expect_error(law({{"type", "ramp"}, {"speed", 1}, {"ramp_time", 0}}), at + "/ramp_time",
               "expected a positive number");
  expect_error(law({{"type", "ramp"}, {"speed", 1}}), at, "missing required key 'ramp_time'");
  expect_error(law({{"type", "constant"}}), at, "missing required key 'value'");
  expect_error(law({{"type", "table"}, {"points", {{0, 0}, {0, 1}, {1, 2}}}}), at + "/points",
               "table");
  expect_error(law({{"type", "table"}, {"points", {{0, 0}}}}), at + "/points", "table");
  expect_error(law({{"type", "table"}, {"points", {{0, 0}, {1}}}}), at + "/points/1",
               "expected a pair [x, y]");
  expect_error(law({{"type", "table"}, {"points", {{0, 0}, {1, 1}}}, {"interpolation", "spline"}}),
               at + "/interpolation", "expected one of");
  expect_error(law({{"type", "table"}, {"points", {{0, 0}, {1, 1}}}, {"period", -1}}),
               at + "/period", "expected a non-negative number");
  expect_error(law({{"type", "table"}, {"points", {{0, 0}, {1, 1}}}, {"period", 1}}),
               at + "/points", "a periodic table must end with its first value");
  expect_error(law({{"type", "table"}, {"file", "no_such_table.csv"}}), at + "/file",
               "no_such_table.csv");
  expect_error(law({{"type", "table"}}), at, "missing required key 'points'");
  expect_error(law({{"type", "trapezoid"},
                    {"from", 0},
                    {"to", 1},
                    {"acceleration", 4},
                    {"speed", 1},
                    {"jerk", 2}}),
               at + "/jerk", "unknown key");
}

TEST(LoaderErrors, SensitivitiesNeedADesignAndResponses) {
  {
    json j = base();
    j.erase("design");
    j.erase("optimization");
    Case cs = test::make_case(j);
    try {
      compute_sensitivities(cs, Vec(), SensitivityOptions{});
      FAIL();
    } catch (const SetupError& e) {  // by name; the command line locates it in the case file
      EXPECT_EQ(std::string(locate("c.json", e).what())
                    .find("c.json: /design: sensitivities need a design section"),
                0u)
          << e.what();
    }
  }
  {
    json j = base();
    j["output"].erase("responses");
    j.erase("optimization");
    Case cs = test::make_case(j);
    try {
      compute_sensitivities(cs, cs.design->initial(), SensitivityOptions{});
      FAIL();
    } catch (const SetupError& e) {
      EXPECT_EQ(std::string(locate("c.json", e).what())
                    .find("c.json: /output/responses: sensitivities need at least one response"),
                0u)
          << e.what();
    }
  }
}

// The command line: exit 2 and a message naming the option, nothing written.
TEST(LoaderErrors, CommandLineOptions) {
  namespace fs = std::filesystem;
  const std::string dir = testing::TempDir() + "lsmbs_cli_errors";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string file = dir + "/case.json";
  std::ofstream(file) << base().dump(1);
  auto run = [&](const std::string& args, const std::string& phrase) {
    const std::string out = dir + "/out";
    fs::remove_all(out);
    const std::string cmd =
        std::string(LSMBS_CLI) + " " + args + " -o " + out + " 2> " + dir + "/err.txt";
    const int rc = std::system(cmd.c_str());
    std::ifstream f(dir + "/err.txt");
    const std::string err((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
    EXPECT_TRUE(WIFEXITED(rc) && WEXITSTATUS(rc) == 2) << cmd << " → " << rc << ": " << err;
    EXPECT_NE(err.find(phrase), std::string::npos) << cmd << ": " << err;
    EXPECT_FALSE(fs::exists(out + "/summary.json")) << cmd;
    std::printf("  %s\n", err.substr(0, err.find('\n')).c_str());
  };
  run("sensitivity " + file + " --delta 0", "--delta");
  run("sensitivity " + file + " --delta -1e-6", "--delta");
  run("verify " + file + " --set kk=100", "unknown design variable 'kk'");
  run("sensitivity " + file + " --set kk=100", "--set kk=100: unknown design variable 'kk'");
  run("sensitivity " + file + " --set k=1e5", "--set k=1e5: outside the bounds");
  run("verify " + file + " --set k", "--set k: expected name=value");
}

TEST(LoaderErrors, WrongKindsAndNullsAreNamedOnce) {
  // a stress measure needs a flexible body: the rigid one is named as rigid, not as unknown
  json j = base();
  j["output"]["measures"].push_back({{"name", "s"}, {"type", "stress"}, {"body", "bob"}});
  expect_error(j, "/output/measures/1/body",
               "'bob' is a rigid body; a flexible body is expected here");
  // a null where a number is expected reads "got null", not "got null null"
  json k = base();
  k["simulation"]["h"] = nullptr;
  try {
    Case cs = test::make_case(k);
    ADD_FAILURE() << "a null step was accepted";
  } catch (const Error& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("/simulation/h"), std::string::npos) << msg;
    EXPECT_NE(msg.find("got null"), std::string::npos) << msg;
    EXPECT_EQ(msg.find("null null"), std::string::npos) << msg;
  }
}

// A key given twice in one object: a JSON parser keeps one silently (nlohmann the last), so a
// case with "h": 0.002, "h": 0.001 ran with either. The file is refused, naming the key's path.
TEST(LoaderErrors, DuplicateKeysAreRefusedWithTheirPath) {
  const std::filesystem::path dir = std::filesystem::path(testing::TempDir()) / "duplicate_keys";
  std::filesystem::create_directories(dir);
  std::string text = base().dump(1);
  const std::string h = "\"h\": 0.01";
  ASSERT_NE(text.find(h), std::string::npos);
  text.replace(text.find(h), h.size(), "\"h\": 0.01, \"h\": 0.02");
  // and inside an array of objects: the second joint's law
  const std::string to = "\"to\": 1";
  ASSERT_NE(text.find(to), std::string::npos);
  std::string nested = base().dump(1);
  nested.replace(nested.find(to), to.size(), "\"to\": 1, \"to\": 2");
  for (const auto& [doc, path, key] :
       {std::tuple{text, std::string("/simulation/h"), std::string("'h'")},
        std::tuple{nested, std::string("/joints/1/law/to"), std::string("'to'")}}) {
    const std::string file = (dir / "case.json").string();
    std::ofstream(file) << doc;
    try {
      (void)load_case(file);
      ADD_FAILURE() << "a duplicate key " << path << " was accepted";
    } catch (const Error& e) {
      const std::string msg = e.what();
      EXPECT_NE(msg.find(file + ": " + path + ": the key " + key + " appears twice"),
                std::string::npos)
          << msg;
    }
  }
  // the same document without the repetition loads
  std::ofstream((dir / "case.json").string()) << base().dump(1);
  EXPECT_NO_THROW((void)load_case((dir / "case.json").string()));
}

// A body placed against its driver: the pendulum drawn at 1 rad while its driver's law starts
// from 0 was rotated silently by the initial projection (a skeptical user's four-bar crank at
// 90°, whose flexible coupler was then torn). A placement error the projection may correct (1 mm
// on a 2 m model) still loads, and the projection places the body exactly.
TEST(LoaderErrors, BodiesPlacedAgainstTheirDriversAreRefused) {
  json j = base();
  j["bodies"][0]["angle"] = 1.0;
  expect_error(j, "/bodies/0",
               "body 'bob' does not satisfy the joints and drivers at t = 0: projecting the "
               "initial state onto them rotates it by -1 rad");
  json ok = base();
  ok["bodies"][0]["position"] = {1.001, 0.0};
  Case cs = test::make_case(ok);
  EXPECT_EQ(cs.initial.q[0], 1.001);  // the case's placement; the run projects it
}

// simulation.force_floor is documented and the integrator has it (GeneralizedAlphaOptions), but
// the loader refused it as an unknown key.
TEST(LoaderErrors, ForceFloorIsReadAndChecked) {
  json j = base();
  j["simulation"]["force_floor"] = 0.25;
  EXPECT_EQ(test::make_case(j).simulation.force_floor, 0.25);
  j["simulation"]["force_floor"] = -1;
  expect_error(j, "/simulation/force_floor", "expected a non-negative number, got -1");
}

// The cap on a rectangle mesh was refused as "expected two positive integers".
TEST(LoaderErrors, RectangleMeshCapIsStated) {
  json j = base();
  j["bodies"].push_back(
      {{"name", "plate"},
       {"type", "flexible"},
       {"mesh", {{"type", "rectangle"}, {"size", {1, 0.1}}, {"elements", {3000, 2000}}}},
       {"material", {{"E", 1e9}, {"nu", 0.3}, {"rho", 1000}}},
       {"thickness", 0.01}});
  expect_error(j, "/bodies/1/mesh/elements",
               "[3000, 2000] is 6000000 elements; a rectangle mesh has at most 5000000 (nx × ny)");
  j["bodies"][1]["mesh"]["elements"] = {2.5, 2};
  expect_error(j, "/bodies/1/mesh/elements", "expected two positive integers [nx, ny]");
}

namespace {

// A clamped 1 m × 0.2 m plate with a hole at (cx, 0.1) of radius r, both design variables.
json plate_with_hole() {
  return R"({
    "name": "plate",
    "bodies": [{"name": "p", "type": "flexible",
                "mesh": {"type": "rectangle", "origin": [0, 0], "size": [1, 0.2], "elements": [10, 2]},
                "material": {"E": 1e9, "nu": 0.3, "rho": 1000}, "thickness": 0.01}],
    "joints": [{"name": "c", "type": "clamp", "flexible": "p", "node_set": "left"}],
    "simulation": {"t_end": 0.002, "h": 0.001},
    "output": {"measures": [{"name": "m", "type": "mass", "body": "p"}],
               "responses": [{"name": "mass", "measure": "m", "aggregate": "final"}]},
    "design": {"variables": [{"name": "r", "initial": 0.05, "lower": 0.01, "upper": 0.08},
                             {"name": "cx", "initial": 0.5, "lower": 0.2, "upper": 3}],
               "geometry": [{"body": "p", "features": [
                 {"name": "hole", "type": "circle", "cx": "cx", "cy": 0.1, "r": "r"}]}]}
  })"_json;
}

}  // namespace

// A feature that overlaps no element of its body has no effect, and nothing said so. One that no
// variable moves is refused at its JSON path; one that a variable moves is a warning
// (Design::features_outside), since an optimizer may move it in.
TEST(LoaderErrors, FeaturesOutsideTheirBodyAreRefusedOrWarned) {
  json ring = plate_with_hole();
  ring["design"]["geometry"][0]["features"].push_back({{"name", "ring"},
                                                       {"type", "circle"},
                                                       {"cx", 5},
                                                       {"cy", 5},
                                                       {"r", 0.1},
                                                       {"non_design", true}});
  expect_error(ring, "/design/geometry/0/features/1",
               "non-design feature 'ring' lies wholly outside body 'p' (it overlaps no element), "
               "and no design variable moves it: it has no effect");
  json fixed = plate_with_hole();  // a hole in another unit: millimetres on a plate in metres
  fixed["design"]["geometry"][0]["features"].push_back({{"name", "mm"},
                                                        {"type", "ellipse"},
                                                        {"cx", 500},
                                                        {"cy", 100},
                                                        {"a", 1},
                                                        {"b", 1},
                                                        {"d", 50}});
  expect_error(fixed, "/design/geometry/0/features/1",
               "feature 'mm' lies wholly outside body 'p' (it overlaps no element)");
  // a ring that overlaps the plate's edge by 1 cm has an effect: it loads
  json edge = plate_with_hole();
  edge["design"]["geometry"][0]["features"].push_back({{"name", "ring"},
                                                       {"type", "circle"},
                                                       {"cx", 1.04},
                                                       {"cy", 0.1},
                                                       {"r", 0.05},
                                                       {"non_design", true}});
  EXPECT_NO_THROW(test::make_case(edge));
  // a design hole that starts off the plate (cx = 2.5) but may move in: loads, and warns there
  json moving = plate_with_hole();
  moving["design"]["variables"][1]["initial"] = 2.5;
  Case cs = test::make_case(moving);
  Vec p = cs.design->initial();
  EXPECT_EQ(cs.design->features_outside(p),
            "body 'p': level-set feature 'hole' lies wholly outside the body at this design "
            "(overlapping no element), with no effect on it until a design variable moves it in "
            "(check the centre and size against the mesh, in the body's frame)");
  // the plate's last element spans x in [0.9, 1]: a hole of r = 0.05 at x = 1.04 overlaps it,
  // at x = 1.06 it does not (the circle's distance is exact)
  p[0] = 0.05;
  p[1] = 1.04;
  EXPECT_EQ(cs.design->features_outside(p), "");
  p[1] = 1.06;
  EXPECT_NE(cs.design->features_outside(p), "");
  p[1] = 0.5;
  EXPECT_EQ(cs.design->features_outside(p), "");
  // A hole whose centre may only move within x in [2, 3] never reaches the plate (x <= 1): the
  // warning said "until a design variable moves it in", which no value within the bounds does.
  // The shape lies within r <= 0.08 of its centre; the nearest element centre, (0.95, 0.05), lies
  // 1.05 from the box, beyond 0.08 + the element's circumradius 0.0707: refused.
  json never = plate_with_hole();
  never["design"]["variables"][1] = {{"name", "cx"}, {"initial", 2.5}, {"lower", 2}, {"upper", 3}};
  expect_error(never, "/design/geometry/0/features/0",
               "feature 'hole' lies wholly outside body 'p' (it overlaps no element), and no "
               "values of its design variables within their bounds bring it in: it has no effect");
  // from x = 1.05 on, (0.95, 0.05) lies 0.112 from the box: 0.112 - 0.08 is within the
  // circumradius, so the hole may come in: accepted, and warned at this design as above
  never["design"]["variables"][1]["lower"] = 1.05;
  EXPECT_NE(test::make_case(never).design->features_outside(Vec2(0.05, 2.5)), "");
}

// A design variable that nothing is bound to has a zero gradient at every design and an
// optimizer leaves it where it starts: said by the runs that differentiate or optimize
// (Design::idle_variables), not refused (a study of fixed features needs one variable).
TEST(LoaderErrors, DesignVariablesThatDriveNothingAreNamed) {
  EXPECT_EQ(test::make_case(plate_with_hole()).design->idle_variables(), "");
  json idle = plate_with_hole();
  idle["design"]["variables"].push_back(
      {{"name", "t"}, {"initial", 1}, {"lower", 0}, {"upper", 2}});
  EXPECT_EQ(test::make_case(idle).design->idle_variables(),
            "design variable 't' drives nothing: no feature parameter (with a nonzero scale) and "
            "no entry of \"parameters\" is bound to it, so the gradient is zero there whatever "
            "the design and an optimizer leaves it where it starts");
  // a binding with scale 0 drives nothing either; a model parameter binding does
  json zero = plate_with_hole();
  zero["design"]["geometry"][0]["features"][0]["r"] = {
      {"variable", "r"}, {"scale", 0}, {"offset", 0.05}};
  EXPECT_NE(test::make_case(zero).design->idle_variables().find("variable 'r' drives nothing"),
            std::string::npos);
  zero["design"]["parameters"] = {{{"parameter", "p.thickness"}, {"variable", "r"}}};
  EXPECT_EQ(test::make_case(zero).design->idle_variables(), "");
}

// Text that is not UTF-8 in a case file: the parser's message gave a byte, line and column, and
// echoed the broken bytes to the terminal; the message names the JSON path of the string.
TEST(LoaderErrors, CaseStringsThatAreNotUtf8AreNamedByTheirPath) {
  const std::filesystem::path dir = std::filesystem::path(testing::TempDir()) / "utf8";
  std::filesystem::create_directories(dir);
  const std::string file = (dir / "case.json").string();
  std::string text = base().dump(1);
  auto with = [&](const std::string& from, const std::string& to) {
    std::string t = text;
    const auto at = t.find(from);
    EXPECT_NE(at, std::string::npos) << from;
    return t.replace(at, from.size(), to);
  };
  const std::pair<std::string, std::string> bad[] = {
      {with("\"errors\"", "\"err\xC3ors\""),
       file + ": /name: the string is not valid UTF-8 (byte "},
      {with("\"name\": \"pin\"", "\"name\": \"p\xFFn\""),
       file + ": /joints/0/name: the string is not valid UTF-8"},
      {with("\"stiffness\"", "\"stiff\xED\xA0\x80ness\""),  // an encoded surrogate
       file + ": /forces/0: a key of this object is not valid UTF-8"},
      {with("\"errors\"", "\"errors\" \xFF"), file + ": byte "},
  };
  for (const auto& [doc, message] : bad) {
    std::ofstream(file, std::ios::binary) << doc;
    try {
      (void)load_case(file);
      ADD_FAILURE() << "accepted: " << message;
    } catch (const Error& e) {
      const std::string msg = e.what();
      EXPECT_EQ(msg.find(message), 0u) << msg;
      EXPECT_EQ(invalid_utf8_at(msg), std::string::npos) << "the message echoes the bytes: " << msg;
    }
  }
}

// The command line: every value given once, seeds that do not wrap, options named by their flags,
// UTF-8 in --set. Exit 2, nothing written, before any simulation.
TEST(LoaderErrors, CommandLineRefusesReplacedWrappedAndMisnamedValues) {
  namespace fs = std::filesystem;
  const std::string dir = testing::TempDir() + "lsmbs_cli_values";
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string file = dir + "/case.json";
  std::ofstream(file) << base().dump(1);
  auto run = [&](const std::string& args, const std::string& phrase) {
    const std::string out = dir + "/out";
    fs::remove_all(out);
    const std::string cmd =
        std::string(LSMBS_CLI) + " " + args + " -o " + out + " 2> " + dir + "/err.txt";
    const int rc = std::system(cmd.c_str());
    std::ifstream f(dir + "/err.txt");
    const std::string err((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
    EXPECT_TRUE(WIFEXITED(rc) && WEXITSTATUS(rc) == 2) << cmd << " → " << rc << ": " << err;
    EXPECT_NE(err.find(phrase), std::string::npos) << cmd << ": " << err;
    EXPECT_FALSE(fs::exists(out + "/summary.json")) << cmd;
    std::printf("  %s\n", err.substr(0, err.find('\n')).c_str());
  };
  // options of methods that do not run (recorded in summary.json as if used; --delta 0.5 with
  // direct-analytic left gradients.csv byte for byte as it was)
  run("sensitivity " + file + " --method direct-analytic --delta 0.5",
      "--delta: an option of the methods semi-analytical, semi-analytical-central, "
      "adjoint-semi-analytical, fd-forward, fd-central, and --method direct-analytic does not use "
      "it");
  run("sensitivity " + file + " --method fd-central --matrix last", "--matrix: an option of the");
  run("sensitivity " + file + " --rtol 1e-6",
      "--rtol: an option of the methods idas, idas-adjoint");
  run("simulate " + file + " --max-order 3", "--max-order: an option of IDAS (--integrator idas)");
  // a key given twice inside one --set value, as in a case file (the last one won silently)
  run("simulate " + file + " --set '/simulation={\"t_end\": 0.02, \"h\": 0.001, \"h\": 0.002}'",
      "appears twice in this object");
  // one value set twice, in every spelling (the last won, and summary.json kept only it)
  run("simulate " + file + " --set /simulation/h=1e-3 --set /simulation/h=2e-3",
      "--set /simulation/h=1e-3 and --set /simulation/h=2e-3 set the same value (/simulation/h): "
      "the later one would replace the earlier without a word; give each value once");
  run("sensitivity " + file + " --set k=200 --set k=300",
      "--set k=200 and --set k=300 set the same value (/design/variables/0/initial)");
  run("optimize " + file + " --set k=200 --set /design/variables/0/initial=300",
      "--set k=200 and --set /design/variables/0/initial=300 set the same value "
      "(/design/variables/0/initial)");
  run("verify " + file + " --set k=200 --set k=300",
      "--set k=200 and --set k=300 set the same value");
  run("simulate " + file +
          " --set '/simulation={\"t_end\": 1.5, \"h\": 0.01}' --set /simulation/h=0.005",
      "overlap (/simulation/h is part of /simulation)");
  run("optimize " + file + " --starts 2 --set k=200",
      "--set k=200: --starts draws the initial value of design variable 'k' at random in every "
      "start");
  // seeds and integers: no wrap, no octal
  run("optimize " + file + " --starts 2 --seed -1",
      "--seed: expected a non-negative integer, got '-1'");
  run("optimize " + file + " --starts 2 --seed 1.5",
      "--seed: expected a non-negative integer (decimal digits), got '1.5'");
  run("optimize " + file + " --starts 2 --seed 18446744073709551616",
      "--seed: expected a non-negative integer in [0, 18446744073709551615]");
  run("sensitivity " + file + " --check --check-seed -1",
      "--check-seed: expected a non-negative integer, got '-1'");
  run("sensitivity " + file + " --check --check-seed 4294967296",
      "--check-seed: expected a non-negative integer in [0, 4294967295]");
  run("sensitivity " + file + " --threads 0x2", "--threads: expected an integer (decimal digits)");
  // the library's field names, now the flags, checked before any simulation
  run("optimize " + file + " --check-fail 1e-9",
      "--check-fail: expected a finite relative disagreement >= --check-warn (0.001), got 1e-09");
  run("sensitivity " + file + " --check --check-delta 2",
      "--check-delta: expected a relative step in (0, 1), got 2");
  run("sensitivity " + file + " --check-delta 0.1",
      "--check-delta: an option of the gradient "
      "check; give --check");
  run("optimize " + file + " --no-check --check-warn 0.1",
      "--check-warn: an option of the gradient check, which --no-check skips");
  run("static " + file + " --t inf", "--t: expected a finite time");
  run("sensitivity " + file + " --adjoint-memory inf", "--adjoint-memory");
  // bytes that are not UTF-8: an internal error after the whole run, before
  run("simulate " + file + " --set \"$(printf '/name=ab\\377c')\"",
      "--set '/name=ab\\xffc': not valid UTF-8 text (byte 9)");
  run("simulate " + file + " --set \"$(printf 'k=\\351')\"", "not valid UTF-8 text");
  const std::string latin1 = dir + "/caf\xe9.json";  // a file name summary.json cannot record
  std::ofstream(latin1) << base().dump(1);
  run("simulate \"$(printf '" + dir + "/caf\\351.json')\"",
      "caf\\xe9.json': the case file's name is not valid UTF-8 (summary.json records it)");
  // whole numbers and indices: " 150" was read by stod, "00" was an internal error
  run("simulate " + file + " --set 'k= 150'", "--set k= 150: expected a finite number after '='");
  run("simulate " + file + " --set '/output/measures/00={}'",
      "/output/measures is an array of 1 entries; expected an index below 1");
}

// A checkpoint (optimize --resume) holds every double as its 16 hexadecimal digits. The reader
// took a prefix: "3ff8000000000000zz" read as 1.5, "3ff8" as a tiny subnormal. Exactly 16 digits
// now, or the evaluation is damaged (the command line refuses the checkpoint, exit 2).
TEST(LoaderErrors, CheckpointDoublesAreExactlySixteenHexDigits) {
  Evaluation e;
  e.p = Vec::Constant(2, 1.5);
  e.objective = -0.1;
  e.objective_gradient = Vec::Constant(2, 3.0);
  e.constraint_gradient = Mat::Zero(0, 2);
  e.max_violation = NAN;
  const json j = evaluation_to_json(e);
  const Evaluation back = evaluation_from_json(j);  // exact round trip
  EXPECT_EQ(back.p, e.p);
  EXPECT_EQ(back.objective, e.objective);
  EXPECT_TRUE(std::isnan(back.max_violation));
  const std::string objective = j["objective"];
  ASSERT_EQ(objective.size(), 16u);
  for (const std::string bad : {objective + "zz", objective.substr(0, 4), " " + objective,
                                "0x" + objective.substr(2), std::string("")}) {
    json d = j;
    d["objective"] = bad;
    EXPECT_THROW((void)evaluation_from_json(d), std::exception) << "'" << bad << "'";
  }
}

TEST(LoaderErrors, CellsBelongToRectangleMeshes) {
  json j = base();
  j["bodies"].push_back({{"name", "plate"},
                         {"type", "flexible"},
                         {"mesh", {{"type", "gmsh"}, {"file", "plate.msh"}, {"cells", "tri3"}}},
                         {"material", {{"E", 1e9}, {"nu", 0.3}, {"rho", 1000}}},
                         {"thickness", 0.01}});
  expect_error(j, "/bodies/1/mesh/cells", "applies to rectangle meshes");
  j["bodies"][1]["mesh"] = {{"type", "rectangle"},
                            {"origin", {0, 0}},
                            {"size", {1, 0.1}},
                            {"elements", {4, 1}},
                            {"cells", "tri6"}};
  expect_error(j, "/bodies/1/mesh/cells", "expected one of");
}

// A hub drawn 0.001 rad off its driver's start, with a flexible arm welded to it: projecting the
// start onto the joints rotates the hub back and strains the arm (1e-3): refused at the hub, naming
// the strain, since the strained arm then vibrates (4.6 times the tool's deflection of the arm
// drawn in place, a complete run). Drawn within round-off, the case loads.
TEST(LoaderErrors, APlacementWhoseProjectionStrainsAFlexibleBodyIsRefused) {
  auto arm = [](double hub_angle) {
    return json::parse(R"({
      "name": "arm",
      "bodies": [
        {"name": "hub", "type": "rigid", "position": [0, 0], "angle": 0, "mass": 0, "inertia": 0},
        {"name": "arm", "type": "flexible",
         "mesh": {"type": "rectangle", "origin": [0, -0.015], "size": [0.4, 0.03], "elements": [20, 2]},
         "material": {"E": 70e9, "nu": 0.33, "rho": 2700}, "thickness": 0.005}],
      "joints": [
        {"name": "pivot", "type": "revolute", "a": {"body": "hub", "at": [0, 0]}, "b": "ground"},
        {"name": "motor", "type": "rotation_driver", "body": "hub",
         "law": {"type": "ramp", "from": 0, "speed": 1, "ramp_time": 0.1}},
        {"name": "root", "type": "rigid_connection", "rigid": "hub", "flexible": "arm", "node_set": "left"}],
      "simulation": {"t_end": 0.01, "h": 0.01}})")
        .patch(
            json::array({{{"op", "replace"}, {"path", "/bodies/0/angle"}, {"value", hub_angle}}}));
  };
  expect_error(arm(1e-3), "/bodies/0", "which strains flexible body 'arm'");
  EXPECT_NO_THROW(test::make_case(arm(1e-15)));
}

namespace {

// base()'s pendulum built in code, as the loader builds it from the document: ModelBuilder calls,
// then the study's measures and responses. `angle`: the bob's angle at t = 0; `twice`: a second
// pin at the same point (redundant constraints); `velocity`: the bob's given velocity.
Study pendulum_in_code(double angle, bool twice = false, std::optional<Vec2> velocity = {}) {
  ModelBuilder b;
  RigidBodyOptions bob;
  bob.position = Vec2(1, 0);
  bob.angle = angle;
  bob.mass = 1;
  bob.inertia = 0.1;
  bob.velocity = velocity;
  b.rigid_body("bob", bob);
  b.revolute("pin", Point::at("bob", Vec2(-1, 0)));  // "b": "ground": at a's initial position
  if (twice) b.revolute("pin2", Point::at("bob", Vec2(-1, 0)));
  b.rotation_driver("motor", "bob", std::make_shared<TrapezoidLaw>(0, 1, 4, 1, 0));
  SpringOptions spring;
  spring.stiffness = 100;
  spring.damping = 1;
  b.spring_damper("spring", Point::at("bob"), Point::ground(Vec2(2, 0)), spring);
  GeneralizedAlphaOptions o;
  o.t_end = 1.5;
  o.h = 0.01;
  Study s(b, o);
  s.add_measure(std::make_unique<PositionMeasure>("bob", b.resolve(Point::at("bob"))));
  s.add_response("mean_x", "bob.x", ResponseSpec::Kind::kAverage);
  return s;
}

// The reason of the case file's error for the same model (without the "file: path: " prefix).
std::pair<std::string, std::string> case_error(const json& j) {
  try {
    test::make_case(j);
  } catch (const Error& e) {
    const std::string prefix = e.file() + ": " + e.json_path() + ": ";
    return {e.json_path(), std::string(e.what()).substr(prefix.size())};
  }
  return {"", "no error"};
}

}  // namespace

// A study built in code meets the start checks of a case file (Study::prepare): the same refusals
// with the same words, naming the entity (the loader turns the name into the JSON path); a study
// that passes gets the case file's initial state.
TEST(StudyPrepare, AStudyBuiltInCodeMeetsTheChecksOfACaseFile) {
  {  // placed against its driver
    Study s = pendulum_in_code(1.0);
    json j = base();
    j["bodies"][0]["angle"] = 1.0;
    const auto [path, reason] = case_error(j);
    EXPECT_EQ(path, "/bodies/0");
    try {
      s.prepare();
      ADD_FAILURE() << "a study placed against its driver was accepted";
    } catch (const SetupError& e) {
      EXPECT_EQ(e.entity(), "bob");
      EXPECT_EQ(e.reason(), reason);
    }
  }
  {  // redundant constraints: the second pin
    Study s = pendulum_in_code(0.0, true);
    json j = base();
    j["joints"].push_back(
        {{"name", "pin2"}, {"type", "revolute"}, {"a", {{"body", "bob"}, {"at", {-1, 0}}}}});
    const auto [path, reason] = case_error(j);
    EXPECT_EQ(path, "/joints");
    try {
      s.prepare();
      ADD_FAILURE() << "redundant constraints were accepted";
    } catch (const SetupError& e) {
      EXPECT_EQ(e.subject(), "joints");
      EXPECT_EQ(e.reason(), reason);
    }
  }
  {  // a given velocity the pin contradicts (the bob's centre moves along x, away from the pin)
    Study s = pendulum_in_code(0.0, false, Vec2(1, 0));
    json j = base();
    j["bodies"][0]["velocity"] = {1, 0};
    const auto [path, reason] = case_error(j);
    EXPECT_EQ(path, "/bodies/0/velocity");
    try {
      s.prepare();
      ADD_FAILURE() << "a velocity against the joints was accepted";
    } catch (const SetupError& e) {
      EXPECT_EQ(e.entity(), "bob");
      EXPECT_EQ(e.field(), "velocity");
      EXPECT_EQ(e.reason(), reason);
    }
  }
  {  // an option out of range, and a response window without a step
    Study s = pendulum_in_code(0.0);
    s.simulation.h = -1;
    EXPECT_THROW(s.prepare(), SetupError);
    Study w = pendulum_in_code(0.0);
    w.add_response("late", "bob.x", ResponseSpec::Kind::kAverage, 2.0, 3.0);
    try {
      w.prepare();
      ADD_FAILURE() << "a window after t_end was accepted";
    } catch (const SetupError& e) {
      EXPECT_EQ(e.subject(), "responses.1.window");
    }
  }
  // a study that passes starts where the case file's starts, bit for bit
  Study s = pendulum_in_code(0.0);
  s.prepare();
  const Case cs = test::make_case(base());
  ASSERT_EQ(s.initial.q.size(), cs.initial.q.size());
  for (Eigen::Index i = 0; i < s.initial.q.size(); ++i) {
    EXPECT_EQ(s.initial.q[i], cs.initial.q[i]) << i;
    EXPECT_EQ(s.initial.v[i], cs.initial.v[i]) << i;
  }
}

// A B-spline feature's control points: each [x, y] of numbers or variables, at least 4, a simple
// closed curve at the initial design; the length-scale constraints refuse its member size.
TEST(LoaderErrors, BSplineFeaturesNameTheBadControlPoint) {
  auto with = [](const json& points) {
    json j = plate_with_hole();
    j["design"]["geometry"][0]["features"][0] = {
        {"name", "free"}, {"type", "bspline"}, {"control_points", points}};
    return j;
  };
  const json square = json::array({{0.4, 0.05}, {0.6, 0.05}, {0.6, 0.15}, {"cx", 0.15}});
  EXPECT_NO_THROW(test::make_case(with(square)));
  expect_error(with(json::array({{0.4, 0.05}, {0.6, 0.05}, {0.6, 0.15}})),
               "/design/geometry/0/features/0/control_points",
               "expected at least 4 control points [x, y] of a closed curve");
  json bad = square;
  bad[2] = json::array({0.6});
  expect_error(with(bad), "/design/geometry/0/features/0/control_points/2",
               "expected a control point [x, y]");
  bad = square;
  bad[1][1] = "nope";
  expect_error(with(bad), "/design/geometry/0/features/0/control_points/1/1",
               "unknown design variable 'nope'");
  // a bow tie: the curve crosses itself at the initial design
  const json bow = json::array({{0.4, 0.05}, {0.6, 0.15}, {0.6, 0.05}, {0.4, 0.15}});
  expect_error(with(bow), "/design/geometry/0/features/0",
               "feature 'free' at the initial design: the curve crosses itself");
  // the length-scale constraints: a member size (on by default) is refused, the rest holds
  json ls = with(square);
  ls["optimization"] = {{"objective", "mass"}, {"length_scale", json::object()}};
  const Case cs = test::make_case(ls);
  try {
    DesignProblem P(conditions_of(cs), parse_optimization(cs));
    ADD_FAILURE() << "a B-spline with a member-size constraint was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("optimization.length_scale.min_member"),
              std::string::npos);
    EXPECT_NE(std::string(e.what()).find("feature 'free' is a B-spline"), std::string::npos);
  }
  ls["optimization"]["length_scale"] = {{"min_member", 0}};
  const Case cs2 = test::make_case(ls);
  EXPECT_NO_THROW(DesignProblem(conditions_of(cs2), parse_optimization(cs2)));
}

// A misspelt required key is named with the key it replaces: the entry is read in the order of
// its required keys, so the misspelling itself would only be reported after them.
TEST(LoaderErrors, AMissingKeyNamesItsMisspelling) {
  json j = base();
  j["forces"][0].erase("stiffness");
  j["forces"][0]["stifness"] = 100;
  expect_error(j, "/forces/0", "missing required key 'stiffness' (the entry has 'stifness'");
  json r = base();
  r["simulation"].erase("h");
  r["simulation"]["hh"] = 0.01;  // one letter is too short to guess from
  try {
    test::make_case(r);
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_EQ(std::string(e.what()).find("misspelling"), std::string::npos) << e.what();
  }
}
