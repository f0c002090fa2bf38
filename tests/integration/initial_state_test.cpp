// Initial states from data (io/initial_state_file.hpp): a run that starts from an earlier run's
// final_state.json, and a flexible body started from nodal displacements and velocities.
//  * A spring oscillator restarted from its state at t = 0.3 s follows the closed form
//    x(t) = 1 + 0.1 cos(ωt) to t = 0.7 s, as the uninterrupted run does.
//  * A free plate given a rigid rotation's velocities node by node moves as one given
//    "angular_velocity" (the builder's rigid field): the same run to round-off; given a uniform
//    velocity it translates, x(t) = X + v t at every node.
//  * Velocities that contradict a clamp are refused at /initial_state/nodes/0.
//  * A clamped plate under gravity started from `lsmbs static`'s equilibrium stays there (it
//    sags 0.15 mm more in 10 ms from the placed shape); gradients then say the start is fixed data.
//  * Sensitivities stay exact: a clamped plate with a design hole, started from a bending velocity
//    field, gives every method's gradient of its tip response against central differences.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <numbers>
#include <sstream>
#include <string>

#include "lsmbs/io/case.hpp"
#include "lsmbs/io/initial_state_file.hpp"
#include "lsmbs/io/sha256.hpp"
#include "lsmbs/runs/simulate.hpp"
#include "lsmbs/runs/static.hpp"
#include "lsmbs/sensitivity/gradient_check.hpp"
#include "lsmbs/sensitivity/sensitivity.hpp"

namespace lsmbs {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;
using Method = SensitivityOptions::Method;

std::string dir() {
  const std::string d = testing::TempDir() + "lsmbs_initial_state";
  fs::create_directories(d);
  return d;
}

// a body of 1 kg on a prismatic joint along x and a spring of k = 4π² N/m (period 1 s) from the
// origin, free length 1 m, placed at x = 1.1 m: x(t) = 1 + 0.1 cos(2πt)
json oscillator(double t_end) {
  const double k = 4 * std::numbers::pi * std::numbers::pi;
  return {
      {"name", "oscillator"},
      {"bodies",
       {{{"name", "m"},
         {"type", "rigid"},
         {"mass", 1.0},
         {"inertia", 1.0},
         {"position", {1.1, 0.0}}}}},
      {"joints",
       {{{"name", "slide"}, {"type", "prismatic"}, {"a", {{"body", "m"}}}, {"direction", {1, 0}}}}},
      {"forces",
       {{{"name", "s"},
         {"type", "spring_damper"},
         {"a", {{"ground", {0, 0}}}},
         {"b", {{"body", "m"}}},
         {"stiffness", k},
         {"free_length", 1.0}}}},
      {"simulation", {{"t_end", t_end}, {"h", 1e-4}, {"rho_inf", 1.0}}},
      {"output",
       {{"measures", {{{"name", "x"}, {"type", "position"}, {"point", {{"body", "m"}}}}}},
        {"responses", {{{"name", "x_end"}, {"measure", "x.x"}, {"aggregate", "final"}}}}}}};
}

double x_end(const Case& cs, const std::string& out) {
  fs::remove_all(out);
  fs::create_directories(out);
  RunOptions ro;
  ro.out_dir = out;
  const auto r = run_simulation(cs, ro);
  EXPECT_TRUE(r.integrator.ok) << r.integrator.message;
  return r.responses.at("x_end");
}

TEST(InitialState, RestartFromAnEarlierRunsFinalStateFollowsTheClosedForm) {
  const std::string d = dir();
  const double w = 2 * std::numbers::pi;
  const double first = x_end(load_case_json(oscillator(0.3), "<osc>", d), d + "/first");
  EXPECT_NEAR(first, 1 + 0.1 * std::cos(w * 0.3), 1e-7);
  json next = oscillator(0.4);
  next["initial_state"] = {{"from", "first/final_state.json"}};
  const Case restarted = load_case_json(next, "<osc restarted>", d);
  const double second = x_end(restarted, d + "/second");
  const double whole = x_end(load_case_json(oscillator(0.7), "<osc>", d), d + "/whole");
  std::printf("x(0.7): restarted %.12f, uninterrupted %.12f, closed form %.12f\n", second, whole,
              1 + 0.1 * std::cos(w * 0.7));
  EXPECT_NEAR(second, 1 + 0.1 * std::cos(w * 0.7), 1e-7);
  EXPECT_NEAR(second, whole, 1e-7);
  // the state file is an input of the run: its hash is in the Case and in summary.json
  {
    std::ifstream in(d + "/first/final_state.json", std::ios::binary);
    std::stringstream bytes;
    bytes << in.rdbuf();
    const std::string path = (fs::path(d) / "first/final_state.json").string();
    ASSERT_EQ(restarted.input_files.count(path), 1u);
    EXPECT_EQ(restarted.input_files.at(path), sha256_hex(bytes.str()));
    const json S = json::parse(std::ifstream(d + "/second/summary.json"));
    EXPECT_EQ(S["input_files_sha256"][path], sha256_hex(bytes.str()));
  }
  // the restarted run's initial velocity is the first run's final one: ẋ = -0.1 ω sin(0.3 ω)
  EXPECT_NEAR(restarted.initial.v[0], -0.1 * w * std::sin(w * 0.3), 1e-6);

  // a state of another model, or of a run that did not complete, is refused by name
  json other = oscillator(0.4);
  other["bodies"][0]["name"] = "n";
  other["joints"][0]["a"]["body"] = "n";
  other["forces"][0]["b"]["body"] = "n";
  other["output"]["measures"][0]["point"]["body"] = "n";
  other["initial_state"] = {{"from", "first/final_state.json"}};
  try {
    load_case_json(other, "<other>", d);
    ADD_FAILURE() << "a state without the case's body was accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("/initial_state/from: " + d +
                                         "/first/final_state.json holds no body 'n'"),
              std::string::npos)
        << e.what();
  }
  json partial = json::parse(std::ifstream(d + "/first/final_state.json"));
  partial["status"] = "partial";
  std::ofstream(d + "/partial.json") << partial.dump();
  next["initial_state"]["from"] = "partial.json";
  EXPECT_THROW(load_case_json(next, "<partial>", d), Error);
}

// A pendulum's end state meets its pin's velocity constraint only to generalized-α's
// discretization error (8e-5 m/s at h = 5 ms): it was refused as contradicting the pin. Its
// velocities are projected like its positions now, and the restarted run continues the swing:
// at t = 1 s it is where the uninterrupted run is, within the integrators' error at this h.
TEST(InitialState, APendulumRestartsFromItsOwnFinalState) {
  const std::string d = dir();
  auto pendulum = [](double t_end) {
    return json::parse(R"({"name": "pend", "gravity": [0, -9.81],
      "bodies": [{"name": "bob", "type": "rigid", "position": [1, 0], "mass": 1, "inertia": 0.01}],
      "joints": [{"name": "pin", "type": "revolute", "a": {"body": "bob", "at": [-1, 0]},
                  "b": {"ground": [0, 0]}}],
      "simulation": {"t_end": )" +
                       std::to_string(t_end) + R"(, "h": 0.005},
      "output": {"measures": [{"name": "p", "type": "position", "point": {"body": "bob"}}],
                 "responses": [{"name": "x_end", "measure": "p.x", "aggregate": "final"}]}})");
  };
  x_end(load_case_json(pendulum(0.5), "<pend>", d), d + "/pend_first");
  json next = pendulum(0.5);
  next["initial_state"] = {{"from", "pend_first/final_state.json"}};
  const double restarted = x_end(load_case_json(next, "<pend restarted>", d), d + "/pend_second");
  const double whole = x_end(load_case_json(pendulum(1.0), "<pend>", d), d + "/pend_whole");
  std::printf("pendulum x(1 s): restarted %.9f, uninterrupted %.9f\n", restarted, whole);
  EXPECT_NEAR(restarted, whole, 1e-4);
  // a state file that lists a body twice, or of another format version, is refused
  json twice = json::parse(std::ifstream(d + "/pend_first/final_state.json"));
  twice["bodies"].push_back(twice["bodies"][0]);
  std::ofstream(d + "/twice.json") << twice.dump();
  json v2 = json::parse(std::ifstream(d + "/pend_first/final_state.json"));
  v2["version"] = 2;
  std::ofstream(d + "/v2.json") << v2.dump();
  for (const auto& [file, message] : std::vector<std::pair<std::string, std::string>>{
           {"twice.json", "/bodies/1/name: body 'bob' is listed twice"},
           {"v2.json", "/version: expected 1"}}) {
    next["initial_state"]["from"] = file;
    try {
      load_case_json(next, "<bad state>", d);
      ADD_FAILURE() << file << " was accepted";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << e.what();
    }
  }
}

// a free square plate, 0.2 m × 0.2 m, 4 × 4 elements, no gravity
json free_plate() {
  return {
      {"name", "plate"},
      {"bodies",
       {{{"name", "p"},
         {"type", "flexible"},
         {"mesh",
          {{"type", "rectangle"}, {"origin", {0, 0}}, {"size", {0.2, 0.2}}, {"elements", {4, 4}}}},
         {"material", {{"E", 1e9}, {"nu", 0.3}, {"rho", 1000}}},
         {"thickness", 0.01}}}},
      {"simulation", {{"t_end", 0.01}, {"h", 1e-3}}},
      {"output",
       {{"measures",
         {{{"name", "c"},
           {"type", "position"},
           {"point", {{"body", "p"}, {"nearest", {0.2, 0.2}}}}}}},
        {"responses",
         {{{"name", "cx"}, {"measure", "c.x"}, {"aggregate", "final"}},
          {{"name", "cy"}, {"measure", "c.y"}, {"aggregate", "final"}}}}}}};
}

void write_nodes(const std::string& file, int n, const std::function<std::array<double, 4>(int)>& f,
                 bool numbered) {
  std::ofstream o(file);
  o << (numbered ? "node,ux,uy,vx,vy\n" : "ux,uy,vx,vy\n");
  o.precision(17);
  for (int i = 0; i < n; ++i) {
    const auto r = f(i);
    if (numbered) o << i << ",";
    o << r[0] << "," << r[1] << "," << r[2] << "," << r[3] << "\n";
  }
}

TEST(InitialState, NodalVelocitiesOfARigidMotionMoveThePlateAsTheRigidField) {
  const std::string d = dir();
  const Case plain = load_case_json(free_plate(), "<plate>", d);
  const FlexibleBody& fb = *plain.model->flexible_bodies()[0];
  const int n = fb.mesh.num_nodes();
  // a uniform velocity (1, -0.5) m/s: x(t) = X + v t at every node, to round-off
  write_nodes(
      d + "/translate.csv", n,
      [](int) {
        return std::array<double, 4>{0, 0, 1, -0.5};
      },
      false);
  json tr = free_plate();
  tr["initial_state"] = {{"nodes", {{{"body", "p"}, {"file", "translate.csv"}}}}};
  const Case ct = load_case_json(tr, "<translate>", d);
  RunOptions ro;
  const auto rt = run_simulation(ct, ro);
  ASSERT_TRUE(rt.integrator.ok) << rt.integrator.message;
  EXPECT_NEAR(rt.responses.at("cx"), 0.2 + 0.01, 1e-13);
  EXPECT_NEAR(rt.responses.at("cy"), 0.2 - 0.005, 1e-13);

  // a rigid rotation ω = 3 rad/s about the plate's corner (0, 0), node by node, with a node column
  write_nodes(
      d + "/rotate.csv", n,
      [&](int i) {
        const Vec2 x = fb.placed(i);
        return std::array<double, 4>{0, 0, -3 * x.y(), 3 * x.x()};
      },
      true);
  json rot = free_plate();
  rot["initial_state"] = {{"nodes", {{{"body", "p"}, {"file", "rotate.csv"}}}}};
  json field = free_plate();
  field["bodies"][0]["angular_velocity"] = 3.0;
  const auto a = run_simulation(load_case_json(rot, "<rotate csv>", d), ro);
  const auto b = run_simulation(load_case_json(field, "<rotate field>", d), ro);
  ASSERT_TRUE(a.integrator.ok && b.integrator.ok);
  EXPECT_NEAR(a.responses.at("cx"), b.responses.at("cx"), 1e-14);
  EXPECT_NEAR(a.responses.at("cy"), b.responses.at("cy"), 1e-14);
  EXPECT_GT(std::abs(a.responses.at("cx") - 0.2), 1e-4) << "the plate turned";

  // errors name the file and line
  std::ofstream(d + "/short.csv") << "ux,uy,vx,vy\n0,0,1,1\n";
  std::ofstream(d + "/bad.csv") << "ux,uy,vx,vy\n0,0,1x,1\n";
  for (const auto& [file, message] : std::vector<std::pair<std::string, std::string>>{
           {"short.csv", "short.csv: holds 1 rows, body 'p' has 25 nodes"},
           {"bad.csv", "bad.csv: line 2: expected a finite number for vx, got '1x'"}}) {
    json j = free_plate();
    j["initial_state"] = {{"nodes", {{{"body", "p"}, {"file", file}}}}};
    try {
      load_case_json(j, "<bad>", d);
      ADD_FAILURE() << file << " was accepted";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << e.what();
    }
  }
}

TEST(InitialState, TwoEntriesForABodyAndAFoldedStartAreInputErrors) {
  const std::string d = dir();
  const Case plain = load_case_json(free_plate(), "<plate>", d);
  const int n = plain.model->flexible_bodies()[0]->mesh.num_nodes();
  write_nodes(
      d + "/still.csv", n,
      [](int) {
        return std::array<double, 4>{0, 0, 0, 0};
      },
      false);
  // node 1 of the 4 × 4 mesh (x = 0.05 m) moved 0.15 m to the right, past its neighbours
  write_nodes(
      d + "/fold.csv", n,
      [](int i) {
        return std::array<double, 4>{i == 1 ? 0.15 : 0.0, 0, 0, 0};
      },
      false);
  json two = free_plate();
  two["initial_state"] = {
      {"nodes", {{{"body", "p"}, {"file", "still.csv"}}, {{"body", "p"}, {"file", "still.csv"}}}}};
  json fold = free_plate();
  fold["initial_state"] = {{"nodes", {{{"body", "p"}, {"file", "fold.csv"}}}}};
  for (const auto& [j, message] : std::vector<std::pair<json, std::string>>{
           {two, "/initial_state/nodes/1/body: body 'p' has two entries"},
           {fold, "/initial_state: the initial state folds or inverts an element"}}) {
    try {
      load_case_json(j, "<bad>", d);
      ADD_FAILURE() << message << ": accepted";
    } catch (const Error& e) {
      EXPECT_NE(std::string(e.what()).find(message), std::string::npos) << e.what();
    }
  }
}

// the plate clamped at x = 0, with a design hole; a bending velocity field vy = V (x / L)²
json clamped_plate_with_hole() {
  json j = free_plate();
  j["bodies"][0]["mesh"] = {
      {"type", "rectangle"}, {"origin", {0, 0}}, {"size", {1.0, 0.2}}, {"elements", {10, 2}}};
  j["joints"] = {{{"name", "c"}, {"type", "clamp"}, {"flexible", "p"}, {"node_set", "left"}}};
  j["simulation"] = {{"t_end", 0.004}, {"h", 5e-4}};
  j["output"]["measures"] = {
      {{"name", "tip"}, {"type", "position"}, {"point", {{"body", "p"}, {"nearest", {1.0, 0.1}}}}}};
  j["output"]["responses"] = {
      {{"name", "tip_end"}, {"measure", "tip.y"}, {"aggregate", "final"}},
      {{"name", "tip_mean"}, {"measure", "tip.y"}, {"aggregate", "average"}}};
  j["design"] = json::parse(R"({
    "variables": [{"name": "r", "initial": 0.05, "lower": 0.01, "upper": 0.08}],
    "geometry": [{"body": "p", "features": [
      {"name": "hole", "type": "circle", "cx": 0.5, "cy": 0.1, "r": "r"}]}]})");
  return j;
}

TEST(InitialState, SensitivitiesFromANodalVelocityFieldAgreeWithCentralDifferences) {
  const std::string d = dir();
  json j = clamped_plate_with_hole();
  const Case probe = load_case_json(j, "<probe>", d);
  const FlexibleBody& fb = *probe.model->flexible_bodies()[0];
  write_nodes(
      d + "/bend.csv", fb.mesh.num_nodes(),
      [&](int i) {
        const double x = fb.placed(i).x();
        return std::array<double, 4>{0, 0, 0, 2.0 * x * x};
      },
      false);
  j["initial_state"] = {{"nodes", {{{"body", "p"}, {"file", "bend.csv"}}}}};
  const Case cs = load_case_json(j, "<bend>", d);
  const Vec p = cs.design->initial();
  SensitivityOptions ref_o;
  ref_o.method = Method::kFdCentral;
  ref_o.delta = 1e-5;
  const auto ref = compute_sensitivities(cs, p, ref_o);
  ASSERT_TRUE(ref.ok) << ref.message;
  for (Method m : {Method::kDirectAnalytic, Method::kSemiAnalyticalCentral, Method::kAdjoint}) {
    SensitivityOptions o;
    o.method = m;
    const auto r = compute_sensitivities(cs, p, o);
    ASSERT_TRUE(r.ok) << SensitivityOptions::name(m) << ": " << r.message;
    const auto dd = compare_gradients(r.responses, ref.responses, GradientNorm::kPerResponse);
    std::printf("%-24s against fd-central: %.2e (%s)\n", SensitivityOptions::name(m), dd.worst,
                dd.where.c_str());
    EXPECT_LT(dd.worst, 1e-5) << SensitivityOptions::name(m) << " " << dd.where;
  }
  // the field moves the tip: the response is not the one of a start at rest
  RunOptions ro;
  const double at_rest = run_simulation(probe, ro).responses.at("tip_mean");
  EXPECT_GT(std::abs(run_simulation(cs, ro).responses.at("tip_mean") - at_rest), 1e-4);

  // a velocity at the clamped nodes contradicts the clamp: refused at the entry's path
  write_nodes(
      d + "/lift.csv", fb.mesh.num_nodes(),
      [](int) {
        return std::array<double, 4>{0, 0, 0, 1.0};
      },
      false);
  j["initial_state"] = {{"nodes", {{{"body", "p"}, {"file", "lift.csv"}}}}};
  try {
    load_case_json(j, "<lift>", d);
    ADD_FAILURE() << "velocities that contradict the clamp were accepted";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("<lift>: /initial_state/nodes/0: "), std::string::npos)
        << e.what();
  }
}

TEST(InitialState, AStartFromStaticEquilibriumStaysAtRestAndIsNamedInTheGradients) {
  const std::string d = dir();
  json j = clamped_plate_with_hole();
  j["gravity"] = {0, -9.81};
  j["simulation"] = {{"t_end", 0.01}, {"h", 5e-4}};
  const Case placed = load_case_json(j, "<placed>", d);
  StaticRunOptions so;
  so.out_dir = d + "/static";
  fs::remove_all(so.out_dir);
  const auto st = run_static(placed, so);
  ASSERT_TRUE(st.solver.ok) << st.solver.message;
  const double sag = st.responses.at("tip_end");  // the static tip height
  j["initial_state"] = {{"from", "static/final_state.json"}};
  const Case cs = load_case_json(j, "<from static>", d);
  RunOptions ro;
  const auto from_rest = run_simulation(cs, ro);
  const auto falling = run_simulation(placed, ro);
  ASSERT_TRUE(from_rest.integrator.ok && falling.integrator.ok);
  std::printf("tip: static %.9f m, from it after 10 ms %.9f m, placed start after 10 ms %.9f m\n",
              sag, from_rest.responses.at("tip_end"), falling.responses.at("tip_end"));
  EXPECT_LT(sag, 0.1 - 1e-5) << "gravity bends the plate";
  EXPECT_NEAR(from_rest.responses.at("tip_end"), sag, 1e-9 * std::abs(0.1 - sag) + 1e-12);
  EXPECT_GT(std::abs(falling.responses.at("tip_end") - sag), 1e-6);
  // the equilibrium belongs to one design: the gradients say they hold it fixed
  SensitivityOptions o;
  const auto r = compute_sensitivities(cs, cs.design->initial(), o);
  ASSERT_TRUE(r.ok) << r.message;
  EXPECT_TRUE(std::any_of(r.warnings.begin(), r.warnings.end(), [](const std::string& w) {
    return w.find("is the static equilibrium in") != std::string::npos;
  }));
}

}  // namespace
}  // namespace lsmbs
