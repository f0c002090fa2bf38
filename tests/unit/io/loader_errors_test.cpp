// Input errors that had no test: each must throw lsmbs::Error whose message names the JSON path
// (or the command-line option) and what was expected; the command line exits 2 on them.
// Response windows, unknown phases and columns, the optimization section, tables and laws,
// sensitivities without a design or responses, --delta ≤ 0, verify --set with an unknown variable.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <tuple>

#include "lsmbs/core/error.hpp"
#include "lsmbs/io/case.hpp"
#include "lsmbs/io/optimization_spec.hpp"
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
