#include "lsmbs/runs/static.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "lsmbs/core/error.hpp"
#include "lsmbs/core/json_file.hpp"
#include "lsmbs/io/initial_state_file.hpp"
#include "lsmbs/io/output.hpp"
#include "lsmbs/responses/aggregation.hpp"
#include "lsmbs/sensitivity/sensitivity.hpp"

namespace lsmbs {

std::string StaticRunOptions::validate() const {
  if (!std::isfinite(t)) return "t: expected a finite time";
  if (max_iter < 1) return "max_iter: expected at least 1";
  return {};
}

std::string StaticRunResult::report() const {
  std::string r = solver.report();
  char b[160];
  for (const auto& [name, v] : responses) {
    std::snprintf(b, sizeof b, "\n  %-28s %.10g", name.c_str(), v);
    r += b;
  }
  return r;
}

namespace {

// history.csv (the one state), the bodies as VTU, final_state.json and summary.json.
void write_outputs(const Case& cs, const ModelParams& params, const StaticRunOptions& o,
                   StaticRunResult& res) {
  const Model& m = *cs.model;
  nlohmann::json& S = res.summary;
  std::filesystem::create_directories(o.out_dir);
  std::vector<std::string> header = {"t"};
  header.insert(header.end(), res.columns.begin(), res.columns.end());
  std::vector<double> row = {o.t};
  row.insert(row.end(), res.measures.begin(), res.measures.end());
  std::vector<std::string> files = {"summary.json"};
  if (res.solver.ok) {
    write_csv(o.out_dir + "/history.csv", header, {row});
    files.push_back("history.csv");
    const ModelVtkFiles f = write_model_vtk(o.out_dir, "", "", m, params, res.state.q);
    for (const auto& b : f.bodies) files.push_back(b.second);
    files.push_back(f.multiblock);
    // the equilibrium, for a run to start from ("initial_state": {"from": ...})
    write_json_atomic(o.out_dir + "/final_state.json",
                      final_state_json(m, res.state, cs.name, "complete", "static"));
    files.push_back("final_state.json");
  }
  S["files"] = file_list(std::move(files));
  write_json_atomic(o.out_dir + "/summary.json", S);
}

}  // namespace

StaticRunResult run_static(const Case& cs, const StaticRunOptions& o) {
  if (auto msg = o.validate(); !msg.empty()) throw SetupError("static", msg);
  const auto t0 = std::chrono::steady_clock::now();
  const Model& m = *cs.model;
  // the case's parameters with the design point written in (the case is not changed)
  const ModelParams params =
      cs.design && o.design_point.size() ? parameters_at(cs, o.design_point) : m.params();
  StaticRunResult res;
  res.state = cs.initial;
  res.state.t = o.t;
  res.state.v.setZero();
  res.state.a.setZero();
  StaticOptions so;
  so.t = o.t;
  so.max_iter = o.max_iter;
  so.tol_phi = cs.simulation.tol_phi;
  so.k = cs.simulation.k;
  so.linear_solver = cs.simulation.linear_solver;
  so.ordering = cs.simulation.ordering;
  res.solver = solve_static(m, params, res.state, so);
  res.columns = cs.measure_columns();
  res.measures.assign(res.columns.size(), NAN);
  if (res.solver.ok) {
    size_t c = 0;
    for (const auto& meas : cs.measures) {
      meas->evaluate(m, res.state, params, res.measures.data() + c);
      c += meas->components().size();
    }
  }
  // responses over the one state: a window that does not contain t has no value
  nlohmann::json responses = nlohmann::json::object();
  for (const auto& r : cs.responses) {
    const Aggregate a = aggregate(r, {o.t}, {res.measures[static_cast<size_t>(r.column)]});
    const double v = res.solver.ok && a.count > 0 ? a.scalar() : NAN;
    res.responses[r.name] = v;
    responses[r.name] = std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr);
  }
  nlohmann::json& S = res.summary;
  S = case_provenance(o.command_line.empty() ? "static" : o.command_line, cs);
  S["overrides"] = cs.overrides;
  S["case_name"] = cs.name;
  S["units"] = units_json(cs);  // of every measure column and response, as simulate's
  S["status"] = res.solver.ok ? "complete" : "partial";
  if (!res.solver.ok) S["failure"] = res.solver.message;
  S["options"] = {{"analysis", "static"},   {"t", o.t},
                  {"max_iter", o.max_iter}, {"tol_r", so.tol_r},
                  {"tol_phi", so.tol_phi},  {"k", so.k}};
  if (cs.design) S["design"] = design_json(cs, o.design_point);
  S["model"] = {{"dofs", m.nq()}, {"constraints", m.nc()}};
  S["counts"] = {{"newton_iterations", res.solver.iterations},
                 {"residual_norm", res.solver.residual_norm},
                 {"linear_solver", res.solver.linear_solver}};
  nlohmann::json measures = nlohmann::json::object();
  for (size_t i = 0; i < res.columns.size(); ++i)
    measures[res.columns[i]] =
        std::isfinite(res.measures[i]) ? nlohmann::json(res.measures[i]) : nlohmann::json(nullptr);
  S["measures"] = measures;
  S["responses"] = responses;
  S["wall_seconds"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  if (!o.out_dir.empty()) write_outputs(cs, params, o, res);
  return res;
}

}  // namespace lsmbs
