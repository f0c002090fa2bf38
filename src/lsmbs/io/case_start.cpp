// The case side of the start checks (Study::prepare, located in the case file), the provenance
// and the resume hash of a case.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <optional>

#include "lsmbs/integrators/initial_state.hpp"
#include "lsmbs/io/case.hpp"
#include "lsmbs/io/output.hpp"
#include "lsmbs/io/sha256.hpp"
#include "lsmbs/records/json.hpp"

namespace lsmbs {

void prepare_case(Case& cs, const Vec* design) {
  try {
    cs.prepare(design);
  } catch (const SetupError& e) {
    throw locate(cs, e);
  }
}

void prepare_conditions(Case& cs, const Vec* design) {
  prepare_case(cs, design);
  if (cs.conditions.empty()) return;
  const auto& names = cs.model->parameter_names();
  for (auto& k : cs.conditions) {
    auto sets = [&](const std::string& path) {  // the condition sets it, or a value holding it
      for (const auto& p : k.set)
        if (path == p || path.rfind(p + "/", 0) == 0) return true;
      return false;
    };
    GeneralizedAlphaOptions& o = k.cs->simulation;
    const GeneralizedAlphaOptions& b = cs.simulation;
    auto copy = [&](const char* field, auto& to, const auto& from) {
      if (!sets(std::string("/simulation/") + field)) to = from;
    };
    copy("h", o.h, b.h), copy("t_end", o.t_end, b.t_end), copy("rho_inf", o.rho_inf, b.rho_inf);
    copy("tol_r", o.tol_r, b.tol_r), copy("tol_phi", o.tol_phi, b.tol_phi);
    copy("tol_q", o.tol_q, b.tol_q), copy("force_floor", o.force_floor, b.force_floor);
    copy("max_iter", o.max_iter, b.max_iter), copy("min_iter", o.min_iter, b.min_iter);
    copy("max_halvings", o.max_halvings, b.max_halvings);
    copy("consistent_start", o.consistent_start, b.consistent_start);
    copy("project_initial", o.project_initial, b.project_initial);
    copy("newton", o.newton, b.newton), copy("ordering", o.ordering, b.ordering);
    copy("linear_solver", o.linear_solver, b.linear_solver);
    copy("k", o.k, b.k), copy("zeta", o.zeta, b.zeta);
    if (k.cs->model->parameter_names() == names)
      for (size_t i = 0; i < names.size(); ++i) {
        const std::string path = parameter_json_path(cs, static_cast<int>(i));
        if (!path.empty() && !sets(path))
          k.cs->model->params().scalars[i] = cs.model->params().scalars[i];
      }
    prepare_case(*k.cs, design);
  }
}

nlohmann::json case_provenance(const std::string& command, const Case& cs) {
  nlohmann::json S = provenance(command, cs.file, cs.sha256);
  if (!cs.input_files.empty()) S["input_files_sha256"] = cs.input_files;
  return S;
}

std::string resume_hash(const Case& cs) {
  std::string state = cs.sha256 + cs.overrides.dump() + nlohmann::json(cs.simulation).dump();
  const auto& scalars = cs.model->params().scalars;
  char b[32];
  for (size_t i = 0; i < scalars.size(); ++i) {  // those the design sets excepted
    bool bound = false;
    if (cs.design)
      for (const auto& pb : cs.design->bindings) bound |= pb.parameter == static_cast<int>(i);
    std::snprintf(b, sizeof b, "%.17g,", scalars[i]);
    state += bound ? std::string("design,") : std::string(b);
  }
  return sha256_hex(state);
}

std::string parameter_json_path(const Case& cs, int i) {
  const auto& names = cs.model->parameter_names();
  if (i < 0 || static_cast<size_t>(i) >= names.size()) return {};
  const std::string& name = names[static_cast<size_t>(i)];
  const auto dot = name.rfind('.');
  if (dot == std::string::npos) return {};
  const std::string entity = name.substr(0, dot), property = name.substr(dot + 1);
  const auto at = cs.paths.find(entity);
  if (at == cs.paths.end()) return {};
  // a flexible body's material constants sit in its "material" object (docs/case-format.md)
  const bool material =
      cs.model->find_flexible(entity) && (property == "E" || property == "nu" || property == "rho");
  return at->second + (material ? "/material/" : "/") + property;
}

}  // namespace lsmbs
