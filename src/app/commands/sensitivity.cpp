// lsmbs sensitivity: responses and their design gradients by one method (§4.3), gradients.csv
// and summary.json, with an optional gradient check along a random direction.
#include "lsmbs/sensitivity/sensitivity.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <optional>

#include "app/commands/commands.hpp"
#include "app/commands/common.hpp"
#include "app/progress_line.hpp"
#include "lsmbs/core/error.hpp"
#include "lsmbs/core/interrupt.hpp"
#include "lsmbs/core/json_file.hpp"
#include "lsmbs/core/text.hpp"
#include "lsmbs/io/case.hpp"
#include "lsmbs/io/output.hpp"
#include "lsmbs/io/plot.hpp"
#include "lsmbs/records/json.hpp"
#include "lsmbs/sensitivity/response_quadrature.hpp"

namespace lsmbs::app {
namespace {

struct MethodComparison {
  nlohmann::json summary = nlohmann::json::object();  // summary.json["methods"]
  std::vector<std::string> files;
  bool all_ok = true;
};

// Several methods run (--method a,b,…): methods.csv (long form: every method's every derivative),
// methods.png (a bar per method for each response and variable: the derivative divided by the
// magnitude of the first method's, so that methods that agree draw bars of the same height; a
// per-step response at the step where the first method's derivative is largest) and the summary.
MethodComparison compare_methods(const std::string& out, const std::vector<std::string>& names,
                                 const std::vector<lsmbs::SensitivityResult>& runs,
                                 const std::vector<std::string>& vars) {
  MethodComparison mc;
  std::string csv = "method,response,variable,step,t,derivative\n";
  lsmbs::BarChartSpec bars;
  bars.png = out + "/methods.png";
  bars.title = "design derivatives by method";
  bars.ylabel = "derivative / |derivative by " + names[0] + "|";
  bars.series = names;
  bars.values.assign(names.size(), {});
  const auto& ref = runs[0].responses;
  for (size_t r = 0; r < ref.size(); ++r)
    for (size_t i = 0; i < vars.size(); ++i) {
      const Eigen::Index col = static_cast<Eigen::Index>(i);
      Eigen::Index step = 0;  // a per-step response: the first method's largest derivative
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
          csv += lsmbs::csv_field(names[k]) + "," + lsmbs::csv_field(rs.name) + "," +
                 lsmbs::csv_field(vars[i]) + "," + std::to_string(n) + "," +
                 lsmbs::csv_number(rs.times.empty() ? NAN : rs.times[static_cast<size_t>(n)]) +
                 "," + lsmbs::csv_number(rs.gradient(n, col)) + "\n";
        }
        g[vars[i]] = rs.times.empty() ? nlohmann::json(v.empty() ? NAN : v[0]) : nlohmann::json(v);
      }
      grads[rs.name] = g;
    }
    mc.all_ok = mc.all_ok && run.ok;
    mc.summary[names[k]] = {{"status", run.ok ? "complete" : "failed"},
                            {"wall_seconds", run.counts.wall_seconds},
                            {"simulations", run.counts.simulations}};
    if (run.ok)
      mc.summary[names[k]]["gradients"] = grads;
    else
      mc.summary[names[k]]["failure"] = run.message;
  }
  lsmbs::write_file_atomic(out + "/methods.csv", csv);
  mc.files.push_back("methods.csv");
  if (!bars.groups.empty() && lsmbs::plot_bars(bars)) mc.files.push_back("methods.png");
  return mc;
}

}  // namespace

int sensitivity_command(const CommonArgs& c, const SensitivityArgs& a) {
  const std::string& case_file = c.case_file;
  const std::string& out = c.out;
  // --method a,b,…: every method is run; the first one's results are the gradients, the others
  // are compared with it (methods.csv, methods.png)
  std::vector<std::string> methods;
  for (size_t b = 0, e; b <= a.method.size(); b = e + 1) {
    e = std::min(a.method.find(',', b), a.method.size());
    methods.push_back(a.method.substr(b, e - b));
  }
  const std::string& method = methods.front();
  const std::string& cmdline = c.command_line;
  const bool quiet = c.quiet;
  const lsmbs::GradientCheckOptions* check = a.check ? &a.check_options : nullptr;
  lsmbs::SensitivityOptions so;
  so.threads = a.threads;
  so.adjoint_memory_mb = a.adjoint_memory_mb;
  std::vector<lsmbs::SensitivityOptions::Method> parsed;
  for (const auto& m : methods) {
    if (!lsmbs::SensitivityOptions::parse(m, so.method)) {
      std::string all;
      for (const auto& n : lsmbs::SensitivityOptions::names()) all += (all.empty() ? "" : ", ") + n;
      throw lsmbs::Error("--method " + a.method + ": '" + m +
                         "' is not a method; expected one of " + all +
                         " (or several, separated by commas)");
    }
    if (std::count(methods.begin(), methods.end(), m) > 1)
      throw lsmbs::Error("--method " + a.method + ": '" + m + "' is given twice");
    parsed.push_back(so.method);
  }
  so.method = parsed.front();
  if (!(a.delta > 0) || !std::isfinite(a.delta))
    throw lsmbs::Error("--delta: expected a positive step");
  check_idas_tolerances(a.rtol, a.atol);
  if (!lsmbs::SensitivityOptions::parse_matrix(a.matrix, so.matrix))
    throw lsmbs::Error("--matrix " + a.matrix + ": expected last, converged or refined");
  so.delta = a.delta;
  so.relative = !a.absolute;
  so.idas.rtol = a.rtol;
  so.idas.atol = a.atol > 0 ? a.atol : a.rtol;
  so.full_residual = a.full_residual;
  if (auto msg = so.validate(); !msg.empty())  // named as the command line spells the option
    throw lsmbs::Error(lsmbs::rename_fields(
        msg,
        {{"delta", "--delta"}, {"threads", "--threads"}, {"adjoint_memory", "--adjoint-memory"}}));
  if (check) check_gradient_check_options(*check);
  lsmbs::Case cs = load_case_with_sets(case_file, c.sets);
  if (!cs.design)
    throw lsmbs::Error(case_file, "/design",
                       "sensitivities need a design section (design variables)");
  if (cs.responses.empty())
    throw lsmbs::Error(case_file, "/output/responses", "sensitivities need at least one response");
  const lsmbs::Vec p = design_point(cs, c.sets);
  claim_output(c, *cs.model);
  so.idas.h_out = cs.simulation.h;  // what IDAS runs with (recorded in summary.json)
  so.idas.t_end = cs.simulation.t_end;
  ProgressLine line(!quiet && ::isatty(STDERR_FILENO));
  so.progress = line.callback();
  lsmbs::install_interrupt_handlers();  // an interrupt stops the generalized-α runs at the next
                                        // step
  // the adjoint's memory bound is this command's option, not a value of the case file
  auto compute = [&](const lsmbs::SensitivityOptions& o) {
    try {
      return lsmbs::compute_sensitivities(cs, p, o);
    } catch (const lsmbs::SetupError& e) {
      if (e.subject() != "optimization.sensitivity.adjoint_memory_mb") throw;
      char v[32];
      std::snprintf(v, sizeof v, "%g", a.adjoint_memory_mb);
      throw lsmbs::Error(std::string("--adjoint-memory ") + v + ": " + e.reason());
    }
  };
  const auto res = compute(so);
  std::vector<lsmbs::SensitivityResult> compared = {res};  // every method, the first one first
  for (size_t k = 1; k < parsed.size() && res.ok; ++k) {
    lsmbs::SensitivityOptions sk = so;
    sk.method = parsed[k];
    compared.push_back(compute(sk));
  }
  std::optional<lsmbs::GradientCheckResult> checked;
  if (check && res.ok && !lsmbs::interrupted())
    checked = lsmbs::check_gradients(cs, p, res.responses, *check);
  line.clear();
  // an interrupt in any part (the method, a compared method, the check): what finished is written
  // and the run is flagged interrupted, never failed or complete
  const bool stopped = res.interrupted || lsmbs::interrupted() != 0;
  const auto& d = *cs.design;
  // summary.json and gradients.csv
  nlohmann::json responses = nlohmann::json::object(), grads = nlohmann::json::object();
  // gradients.csv in long form, one row per response value and design variable: a plain CSV with
  // a header that names every column (csv.DictReader and pandas.read_csv read it as is)
  std::string csv = "response,variable,step,t,value,derivative\n";
  for (size_t r = 0; r < res.responses.size(); ++r) {
    const auto& rs = res.responses[r];
    const bool per_step = !rs.times.empty();
    nlohmann::json g = nlohmann::json::object();
    for (int i = 0; i < d.size(); ++i) {
      if (per_step) {
        std::vector<double> col;
        for (Eigen::Index k = 0; k < rs.gradient.rows(); ++k) col.push_back(rs.gradient(k, i));
        g[d.variables[i].name] = col;
      } else {
        g[d.variables[i].name] = rs.gradient.rows() ? rs.gradient(0, i) : NAN;
      }
    }
    responses[rs.name] = per_step ? nlohmann::json(rs.values)
                                  : nlohmann::json(rs.values.empty() ? NAN : rs.values[0]);
    grads[rs.name] = g;
    for (size_t k = 0; k < rs.values.size(); ++k)
      for (int i = 0; i < d.size(); ++i)
        csv += lsmbs::csv_field(rs.name) + "," + lsmbs::csv_field(d.variables[i].name) + "," +
               std::to_string(k) + "," + lsmbs::csv_number(per_step ? rs.times[k] : NAN) + "," +
               lsmbs::csv_number(rs.values[k]) + "," +
               lsmbs::csv_number(rs.gradient(static_cast<Eigen::Index>(k), i)) + "\n";
  }
  nlohmann::json S = lsmbs::case_provenance(cmdline, cs);
  S["overrides"] = cs.overrides;
  S["case_name"] = cs.name;
  S["status"] = stopped ? "interrupted" : res.ok ? "complete" : "partial";
  if (!res.ok) S["failure"] = res.message;
  if (stopped && res.ok)
    S["failure"] = std::string("interrupted by signal ") + std::to_string(lsmbs::interrupted()) +
                   (checked && checked->interrupted ? " during the gradient check"
                                                    : " after the first method");
  S["design"] = lsmbs::design_json(cs, p);
  S["options"] = {{"sensitivity", nlohmann::json(so)},
                  {"generalized_alpha", nlohmann::json(cs.simulation)}};
  S["counts"] = nlohmann::json(res.counts);
  S["primal"] = nlohmann::json(res.primal);
  S["warnings"] = res.warnings;
  if (checked)
    S["gradient_check"] = lsmbs::gradient_check_json(*checked, *check);
  else if (check && stopped)  // asked for, and the interrupt came before it could run
    S["gradient_check"] = {{"completed", false},
                           {"verdict", "interrupted"},
                           {"message", "interrupted before the check's simulations began"}};
  for (const auto& w : res.warnings)
    std::fprintf(stderr, "lsmbs sensitivity: warning: %s\n", w.c_str());
  S["wall_seconds"] = res.counts.wall_seconds;
  if (res.ok) {
    S["responses"] = responses;
    S["gradients"] = grads;
  } else {
    // a failed run's aggregates cover only the steps before the failure: not reported as the
    // responses (null), but apart, under a name that says so
    nlohmann::json nulls = nlohmann::json::object();
    for (const auto& [name, v] : responses.items()) nulls[name] = nullptr;
    S["responses"] = nulls;
    S["gradients"] = nulls;
    S["partial_responses_until_failure"] = responses;
  }
  if (!res.quadratures.empty() && res.ok) {
    std::vector<std::string> names;
    for (const auto& v : d.variables) names.push_back(v.name);
    S["quadratures"] = lsmbs::quadratures_json(res.quadratures, names);
  }
  if (so.is_idas()) S["idas"] = nlohmann::json(res.idas);
  std::filesystem::create_directories(out);
  if (res.ok)
    lsmbs::write_file_atomic(out + "/gradients.csv", csv);  // a failed run has no gradients
  S["units"] = lsmbs::units_json(cs);
  std::vector<std::string> files = {"summary.json"};
  if (res.ok) files.push_back("gradients.csv");
  bool others_ok = true;
  if (compared.size() > 1) {
    std::vector<std::string> vars;
    for (const auto& v : d.variables) vars.push_back(v.name);
    const MethodComparison mc = compare_methods(out, methods, compared, vars);
    S["methods"] = mc.summary;
    for (const auto& f : mc.files) files.push_back(f);
    others_ok = mc.all_ok;
  }
  S["files"] = lsmbs::file_list(std::move(files));
  lsmbs::write_json_atomic(out + "/summary.json", S);
  if (!quiet) {
    std::printf(
        "lsmbs sensitivity (%s): %s — %ld simulations, %ld steps, %ld factorizations, %ld "
        "back-solves (%ld rhs), %.3f s\n",
        method.c_str(),
        stopped  ? "INTERRUPTED"
        : res.ok ? "complete"
                 : "FAILED",
        res.counts.simulations, res.counts.steps, res.counts.factorizations, res.counts.back_solves,
        res.counts.back_solve_rhs, res.counts.wall_seconds);
    for (const auto& rs : res.responses) {
      if (!res.ok) break;  // aggregates of a failed run are not responses
      if (!rs.times.empty()) {
        std::printf("  %-24s per-step, %zu values\n", rs.name.c_str(), rs.values.size());
        continue;
      }
      std::printf("  %-24s %.10g\n", rs.name.c_str(), rs.values.empty() ? NAN : rs.values[0]);
      for (int i = 0; i < d.size() && rs.gradient.rows(); ++i)
        std::printf("      d/d%-12s %+.10e\n", d.variables[i].name.c_str(), rs.gradient(0, i));
    }
    for (const auto& q : res.quadratures) {
      if (!res.ok) break;
      std::printf("  %-24s %.10g (IDAS quadrature on [%g, %g])\n", q.name.c_str(), q.value, q.t0,
                  q.t1);
      for (int i = 0; i < d.size() && i < q.gradient.size(); ++i)
        std::printf("      d/d%-12s %+.10e\n", d.variables[i].name.c_str(), q.gradient[i]);
    }
    if (checked) print_gradient_check(*checked, *check);
    std::printf("  results in %s\n", out.c_str());
  }
  if (stopped) {
    std::fprintf(stderr, "lsmbs sensitivity: %s; partial results in %s (status interrupted)\n",
                 S["failure"].get<std::string>().c_str(), out.c_str());
    return 130;
  }
  if (!res.ok) {
    std::fprintf(stderr, "lsmbs: numerical failure: %s\n", res.message.c_str());
    return 1;
  }
  if (!others_ok) {
    std::fprintf(stderr, "lsmbs: numerical failure of a compared method (summary.json methods)\n");
    return 1;
  }
  if (checked && checked->verdict(*check) == "fail") {
    std::fprintf(stderr, "lsmbs: gradient check failed: %s\n",
                 checked->ok
                     ? ("response '" + checked->worst_response +
                        "' disagrees with central differences by " + std::to_string(checked->worst))
                           .c_str()
                     : checked->message.c_str());
    return 1;
  }
  return 0;
}

}  // namespace lsmbs::app
