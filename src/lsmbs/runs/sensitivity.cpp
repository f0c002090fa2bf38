#include "lsmbs/runs/sensitivity.hpp"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <thread>

#include "lsmbs/core/csv.hpp"
#include "lsmbs/core/interrupt.hpp"
#include "lsmbs/core/json_file.hpp"
#include "lsmbs/io/output.hpp"
#include "lsmbs/io/plot.hpp"
#include "lsmbs/records/json.hpp"
#include "lsmbs/runs/mpi.hpp"
#include "lsmbs/sensitivity/response_quadrature.hpp"

namespace lsmbs {
namespace {

std::vector<std::string> variable_names(const Design& d) {
  std::vector<std::string> v;
  for (const auto& x : d.variables) v.push_back(x.name);
  return v;
}

// methods.png: a bar per method for each response and variable, the derivative divided by the
// magnitude of the first method's, so that methods that agree draw bars of the same height; a
// per-step response at the step where the first method's derivative is largest.
bool plot_methods(const std::string& out, const std::vector<std::string>& names,
                  const std::vector<SensitivityResult>& runs,
                  const std::vector<std::string>& vars) {
  BarChartSpec bars;
  bars.png = out + "/methods.png";
  bars.title = "design derivatives by method";
  bars.ylabel = "derivative / |derivative by " + names[0] + "|";
  bars.series = names;
  bars.values.assign(names.size(), {});
  const auto& ref = runs[0].responses;
  for (size_t r = 0; r < ref.size(); ++r)
    for (size_t i = 0; i < vars.size(); ++i) {
      const Eigen::Index col = static_cast<Eigen::Index>(i);
      Eigen::Index step = 0;
      if (ref[r].gradient.rows() > 1) ref[r].gradient.col(col).cwiseAbs().maxCoeff(&step);
      const double scale = std::abs(ref[r].gradient(step, col));
      bars.groups.push_back(ref[r].name + " / " + vars[i] +
                            (ref[r].times.empty() ? "" : " (step " + std::to_string(step) + ")"));
      for (size_t k = 0; k < runs.size(); ++k) {
        const auto& rs = runs[k].responses;
        const bool has = runs[k].ok && r < rs.size() && rs[r].gradient.rows() > step;
        const double g = has ? rs[r].gradient(step, col) : NAN;
        bars.values[k].push_back(scale > 0 ? g / scale : g == 0 ? 0.0 : NAN);
      }
    }
  return !bars.groups.empty() && plot_bars(bars);
}

// Several methods: methods.csv (long form: every method's every derivative), methods.png and
// summary.json's "methods". Returns the files written.
std::vector<std::string> compare_methods(const std::string& out,
                                         const std::vector<SensitivityResult>& runs,
                                         const std::vector<std::string>& names,
                                         const std::vector<std::string>& vars,
                                         nlohmann::json& summary) {
  std::string csv = "method,response,variable,step,t,derivative\n";
  for (size_t k = 0; k < runs.size(); ++k) {
    const auto& run = runs[k];
    nlohmann::json grads = nlohmann::json::object();
    for (const auto& rs : run.responses) {
      nlohmann::json g = nlohmann::json::object();
      for (size_t i = 0; i < vars.size() && run.ok; ++i) {
        const Eigen::Index col = static_cast<Eigen::Index>(i);
        std::vector<double> v;
        for (Eigen::Index n = 0; n < rs.gradient.rows(); ++n) {
          v.push_back(rs.gradient(n, col));
          csv += csv_field(names[k]) + "," + csv_field(rs.name) + "," + csv_field(vars[i]) + "," +
                 std::to_string(n) + "," +
                 csv_number(rs.times.empty() ? NAN : rs.times[static_cast<size_t>(n)]) + "," +
                 csv_number(rs.gradient(n, col)) + "\n";
        }
        g[vars[i]] = rs.times.empty() ? nlohmann::json(v.empty() ? NAN : v[0]) : nlohmann::json(v);
      }
      grads[rs.name] = g;
    }
    summary[names[k]] = {{"status", run.ok ? "complete" : "failed"},
                         {"wall_seconds", run.counts.wall_seconds},
                         {"simulations", run.counts.simulations}};
    if (run.ok)
      summary[names[k]]["gradients"] = grads;
    else
      summary[names[k]]["failure"] = run.message;
  }
  std::vector<std::string> files;
  if (out.empty()) return files;
  write_file_atomic(out + "/methods.csv", csv);
  files.push_back("methods.csv");
  if (plot_methods(out, names, runs, vars)) files.push_back("methods.png");
  return files;
}

// summary.json's responses and gradients, and gradients.csv in long form, one row per response
// value and design variable: a plain CSV with a header that names every column (csv.DictReader
// and pandas.read_csv read it as is).
struct GradientTables {
  nlohmann::json responses = nlohmann::json::object(), gradients = nlohmann::json::object();
  std::string csv = "response,variable,step,t,value,derivative\n";
};
GradientTables gradient_tables(const SensitivityResult& res, const std::vector<std::string>& vars) {
  GradientTables t;
  const int n = static_cast<int>(vars.size());
  for (const auto& rs : res.responses) {
    const bool per_step = !rs.times.empty();
    nlohmann::json g = nlohmann::json::object();
    for (int i = 0; i < n; ++i) {
      if (per_step) {
        std::vector<double> col;
        for (Eigen::Index k = 0; k < rs.gradient.rows(); ++k) col.push_back(rs.gradient(k, i));
        g[vars[i]] = col;
      } else {
        g[vars[i]] = rs.gradient.rows() ? rs.gradient(0, i) : NAN;
      }
    }
    t.responses[rs.name] = per_step ? nlohmann::json(rs.values)
                                    : nlohmann::json(rs.values.empty() ? NAN : rs.values[0]);
    t.gradients[rs.name] = g;
    for (size_t k = 0; k < rs.values.size(); ++k)
      for (int i = 0; i < n; ++i)
        t.csv += csv_field(rs.name) + "," + csv_field(vars[i]) + "," + std::to_string(k) + "," +
                 csv_number(per_step ? rs.times[k] : NAN) + "," + csv_number(rs.values[k]) + "," +
                 csv_number(rs.gradient(static_cast<Eigen::Index>(k), i)) + "\n";
  }
  return t;
}

// The outcome part of summary.json: status, failure, the check, and the responses — a failed
// run's aggregates cover only the steps before the failure: not reported as the responses (null),
// but apart, under a name that says so.
void outcome_json(const SensitivityRun& run, const SensitivityRunOptions& o,
                  const GradientTables& t, nlohmann::json& S) {
  const SensitivityResult& res = run.result;
  S["status"] = run.stopped ? "interrupted" : res.ok ? "complete" : "partial";
  if (!res.ok) S["failure"] = res.message;
  if (run.stopped && res.ok)
    S["failure"] = std::string("interrupted by signal ") + std::to_string(interrupted()) +
                   (run.checked && run.checked->interrupted ? " during the gradient check"
                                                            : " after the first method");
  if (run.checked)
    S["gradient_check"] = gradient_check_json(*run.checked, *o.check);
  else if (o.check && run.stopped)  // asked for, and the interrupt came before it could run
    S["gradient_check"] = {{"completed", false},
                           {"verdict", "interrupted"},
                           {"message", "interrupted before the check's simulations began"}};
  if (res.ok) {
    S["responses"] = t.responses;
    S["gradients"] = t.gradients;
  } else {
    nlohmann::json nulls = nlohmann::json::object();
    for (const auto& [name, v] : t.responses.items()) nulls[name] = nullptr;
    S["responses"] = nulls;
    S["gradients"] = nulls;
    S["partial_responses_until_failure"] = t.responses;
  }
}

}  // namespace

int SensitivityRun::exit_code(const std::optional<GradientCheckOptions>& check) const {
  if (stopped) return 130;
  return failure(check).empty() ? 0 : 1;
}

std::string SensitivityRun::failure(const std::optional<GradientCheckOptions>& check) const {
  if (stopped) return {};
  if (!result.ok) return "numerical failure: " + result.message;
  if (!others_ok) return "numerical failure of a compared method (summary.json methods)";
  if (checked && check && checked->verdict(*check) == "fail") {
    if (!checked->ok) return "gradient check failed: " + checked->message;
    char worst[32];
    std::snprintf(worst, sizeof worst, "%g", checked->worst);
    return "gradient check failed: response '" + checked->worst_response +
           "' disagrees with central differences by " + worst;
  }
  return {};
}

SensitivityRun run_sensitivity(const Case& cs, const Vec& p, const SensitivityRunOptions& o) {
  const Conditions c = conditions_of(cs);
  const ConditionExecutor executor =
      o.executor ? o.executor
                 : mpi::conditions_executor(mpi::conditions_at_once(o.options.threads));
  if (!cs.design)
    throw SetupError("design", "sensitivities need a design section (design variables)");
  if (cs.responses.empty())
    throw SetupError("responses", "sensitivities need at least one response");
  SensitivityRun run;
  SensitivityOptions so = o.options;
  so.idas.h_out = cs.simulation.h;  // what IDAS runs with (recorded in summary.json)
  so.idas.t_end = cs.simulation.t_end;
  run.result = compute_sensitivities(c, p, so, executor);
  const SensitivityResult& res = run.result;
  run.compared = {res};
  std::vector<std::string> names = {SensitivityOptions::name(so.method)};
  for (size_t k = 0; k < o.compare.size() && res.ok; ++k) {
    SensitivityOptions sk = so;
    sk.method = o.compare[k];
    run.compared.push_back(compute_sensitivities(c, p, sk, executor));
    names.push_back(SensitivityOptions::name(sk.method));
  }
  if (o.check && res.ok && !interrupted())
    run.checked = check_gradients(c, p, res.responses, *o.check, executor);
  run.stopped = res.interrupted || interrupted() != 0;
  const auto vars = variable_names(*cs.design);
  const GradientTables t = gradient_tables(res, vars);
  nlohmann::json& S = run.summary = case_provenance(o.command, cs);
  S["overrides"] = cs.overrides;
  S["case_name"] = cs.name;
  outcome_json(run, o, t, S);
  S["design"] = design_json(cs, p);
  S["options"] = {{"sensitivity", nlohmann::json(so)},
                  {"generalized_alpha", nlohmann::json(cs.simulation)},
                  {"ranks", mpi::world().size}};
  S["counts"] = nlohmann::json(res.counts);
  S["primal"] = nlohmann::json(res.primal);
  S["warnings"] = res.warnings;
  S["wall_seconds"] = res.counts.wall_seconds;
  if (!res.quadratures.empty() && res.ok)
    S["quadratures"] = quadratures_json(res.quadratures, vars);
  if (so.is_idas()) S["idas"] = nlohmann::json(res.idas);
  S["units"] = units_json(c);
  if (c.several() || !c.combinations.empty()) S["conditions"] = conditions_json(cs, c);
  std::vector<std::string> files = {"summary.json"};
  // under MPI every rank runs this job (runs/mpi.hpp); rank 0 writes its files
  const std::string out = mpi::world().rank == 0 ? o.out_dir : std::string();
  if (!out.empty()) std::filesystem::create_directories(out);
  if (res.ok && !out.empty()) {  // a failed run has no gradients
    write_file_atomic(out + "/gradients.csv", t.csv);
    files.push_back("gradients.csv");
  }
  if (run.compared.size() > 1) {
    nlohmann::json methods = nlohmann::json::object();
    for (const auto& f : compare_methods(out, run.compared, names, vars, methods))
      files.push_back(f);
    S["methods"] = methods;
    for (const auto& r : run.compared) run.others_ok = run.others_ok && r.ok;
  }
  S["files"] = file_list(std::move(files));
  if (!out.empty()) write_json_atomic(out + "/summary.json", S);
  return run;
}

}  // namespace lsmbs
