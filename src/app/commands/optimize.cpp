// lsmbs optimize: the fully coupled optimization of the case's design (NLopt MMA, CCSAQ, SLSQP,
// or the classic MMA), with a gradient check at the initial design, checkpoints and --resume.
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <optional>

#include "app/commands/commands.hpp"
#include "app/commands/common.hpp"
#include "app/progress_line.hpp"
#include "lsmbs/core/error.hpp"
#include "lsmbs/core/interrupt.hpp"
#include "lsmbs/core/json_file.hpp"
#include "lsmbs/io/case.hpp"
#include "lsmbs/io/geometry_run.hpp"
#include "lsmbs/io/optimization_spec.hpp"
#include "lsmbs/io/output.hpp"
#include "lsmbs/io/plot.hpp"
#include "lsmbs/io/sha256.hpp"
#include "lsmbs/optimization/kkt.hpp"
#include "lsmbs/optimization/optimizer.hpp"
#include "lsmbs/records/json.hpp"

namespace lsmbs::app {

namespace {

// Convergence plot (objective and maximum constraint violation per evaluation) with gnuplot,
// when it is installed; returns false otherwise.
bool plot_history(const std::string& out) {
  const std::string script = out + "/convergence.gp";
  {
    std::ofstream g(script);
    g << "set terminal pngcairo size 900,500 noenhanced\nset output "
      << lsmbs::gnuplot_quote(out + "/convergence.png") << "\n"
      << "set datafile separator ','\nset key autotitle columnhead\nset xlabel 'evaluation'\n"
      << "set ylabel 'objective'\nset y2label 'max. relative constraint violation'\nset "
         "y2tics\nset grid\n"
      << "plot " << lsmbs::gnuplot_quote(out + "/history.csv")
      << " using 1:2 with linespoints title 'objective', "
      << "'' using 1:3 axes x1y2 with linespoints title 'max constraint violation'\n";
  }
  const bool ok = lsmbs::run_gnuplot(script);
  std::filesystem::remove(script);
  std::error_code ec;
  if (!ok) std::filesystem::remove(out + "/convergence.png", ec);  // no 0-byte picture
  return ok;
}

}  // namespace

// On a terminal: a table row per evaluation and a progress line of the running simulation; not on
// a terminal: the final summary only (history.csv has every evaluation), unless --verbose.
int optimize_command(const CommonArgs& c, const OptimizeArgs& a) {
  const std::string& case_file = c.case_file;
  const std::string& out = c.out;
  const std::string& cmdline = c.command_line;
  const bool quiet = c.quiet, verbose = c.verbose, resume = a.resume;
  const std::string& optimizer = a.optimizer;
  const lsmbs::GradientCheckOptions* check = a.check ? &a.check_options : nullptr;
  lsmbs::Case cs = load_case_with_sets(case_file, c.sets, /*design_as_initial=*/true);
  lsmbs::OptimizationSpec spec =
      lsmbs::parse_optimization(cs);  // validated before anything is written
  // Testing hook (docs/verification.md): LSMBS_STOP_AFTER_EVALUATIONS=N ends the run after N
  // evaluations simulated in this run exactly as an interruption (SIGINT) would: checkpoint and
  // history written, status "interrupted", exit code 130, resumable with --resume.
  long stop_after = -1;
  if (const char* env = std::getenv("LSMBS_STOP_AFTER_EVALUATIONS")) {
    char* end = nullptr;
    errno = 0;
    const long n = std::strtol(env, &end, 10);
    if (*env == '\0' || *end != '\0' || errno != 0 || n < 1)
      throw lsmbs::Error(
          "environment variable LSMBS_STOP_AFTER_EVALUATIONS=" + std::string(env) +
          ": expected a positive integer (a testing hook: stop after that many evaluations)");
    stop_after = n;
  }
  if (!optimizer.empty()) {
    if (optimizer != "mma-svanberg" && cs.optimization.contains("move_limit"))
      throw lsmbs::Error("--optimizer " + optimizer +
                         ": the case sets a move_limit, which only mma-svanberg has");
    spec.optimizer = optimizer;
  }
  const bool interactive = !quiet && ::isatty(STDOUT_FILENO) && ::isatty(STDERR_FILENO);
  const bool table = interactive || (verbose && !quiet);
  ProgressLine line(interactive);
  spec.sensitivity.progress = line.callback();
  std::filesystem::create_directories(out);
  lsmbs::DesignProblem prob(cs, spec);
  const auto& d = *cs.design;
  lsmbs::OptimizeOptions o;
  // a resumed run must see the same case: the file's hash, and the overrides' when there are any
  o.input_sha256 =
      cs.overrides.empty() ? cs.sha256 : lsmbs::sha256_hex(cs.sha256 + cs.overrides.dump());
  o.out_dir = out;
  o.resume = resume;
  o.stop_after = stop_after;
  if (table) {
    std::printf("lsmbs optimize: %d variables, %d constraints, optimizer %s, sensitivities %s\n",
                d.size(), prob.num_constraints(), spec.optimizer.c_str(),
                lsmbs::SensitivityOptions::name(spec.sensitivity.method));
    std::printf("%6s %16s %14s %10s\n", "eval", "objective", "max violation", "time [s]");
  }
  o.on_evaluation = [&](int k, const lsmbs::Evaluation& e) {
    line.clear();
    if (table)
      std::printf("%6d %16.9g %14.4e %10.2f\n", k, e.objective, e.max_violation, e.wall_seconds);
    std::fflush(stdout);
  };
  // Gradient check at the initial design (not on resume: the first run did it)
  std::optional<lsmbs::GradientCheckResult> checked;
  if (check && !resume) {
    checked = lsmbs::check_problem_gradients(prob, d.initial(), *check);
    if (checked) {
      line.clear();
      const std::string verdict = checked->verdict(*check);
      if (verdict != "pass") {
        const std::string what =
            checked->ok ? "response '" + checked->worst_response +
                              "': the gradient disagrees with central differences by " +
                              std::to_string(checked->worst) + " (relative)"
                        : checked->message;
        if (verdict == "fail") {
          nlohmann::json S = lsmbs::provenance(cmdline, cs.file, cs.sha256);
          S["overrides"] = cs.overrides;
          S["case_name"] = cs.name;
          S["status"] = "refused";
          S["failure"] = "gradient check at the initial design failed: " + what;
          S["options"] = {{"optimization", spec.to_json()},
                          {"generalized_alpha", nlohmann::json(cs.simulation)}};
          S["gradient_check"] = lsmbs::gradient_check_json(*checked, *check);
          S["units"] = lsmbs::units_json(cs);
          S["files"] = lsmbs::file_list({"summary.json"});
          lsmbs::write_json_atomic(out + "/summary.json", S);
          std::fprintf(
              stderr,
              "lsmbs optimize: refused: gradient check at the initial design failed: %s (above %g; "
              "--no-check skips the check)\n",
              what.c_str(), check->fail);
          return 1;
        }
        if (!quiet)
          std::fprintf(stderr,
                       "lsmbs optimize: warning: gradient check at the initial design: %s\n",
                       what.c_str());
      }
    }
  }
  // an interrupt stops the evaluation in progress at its next step; that evaluation is dropped, and
  // the checkpoint keeps every one before it (--resume evaluates it again)
  lsmbs::install_interrupt_handlers();
  const auto res = lsmbs::optimize(prob, o);
  line.clear();
  // final design pictures and summary
  lsmbs::GeometryRunOptions go;
  go.out_dir = out + "/final_design";
  const auto geo = lsmbs::run_geometry(cs, res.p, go);
  const bool plotted = plot_history(out);
  nlohmann::json S = lsmbs::provenance(cmdline, cs.file, cs.sha256);
  S["overrides"] = cs.overrides;
  S["case_name"] = cs.name;
  S["status"] = !res.failure.empty() ? "partial"
                : res.interrupted    ? "interrupted"
                : res.final.ok       ? "complete"
                                     : "partial";
  if (!res.failure.empty()) S["failure"] = res.failure;
  S["options"] = {{"optimization", spec.to_json()},
                  {"generalized_alpha", nlohmann::json(cs.simulation)}};
  nlohmann::json p0 = nlohmann::json::object(), pf = nlohmann::json::object();
  const lsmbs::Vec init = d.initial();
  for (int i = 0; i < d.size(); ++i)
    p0[d.variables[i].name] = init[i], pf[d.variables[i].name] = res.p[i];
  // an interrupt during the first evaluation leaves no evaluation at all
  const lsmbs::Evaluation first = res.history.empty() ? lsmbs::Evaluation{} : res.history.front();
  const double first_objective = res.history.empty() ? NAN : first.objective;
  S["initial"] = {{"design", p0},
                  {"objective", first_objective},
                  {"max_violation", res.history.empty() ? NAN : first.max_violation},
                  {"constraints_max",
                   first.constraints.empty()
                       ? NAN
                       : *std::max_element(first.constraints.begin(), first.constraints.end())}};
  S["final"] = {{"design", pf},
                {"objective", res.final.objective},
                {"max_violation", res.final.max_violation},
                {"constraints_max", res.final.constraints.empty()
                                        ? NAN
                                        : *std::max_element(res.final.constraints.begin(),
                                                            res.final.constraints.end())}};
  S["responses"] = {{spec.objective, res.final.objective}};
  S["nlopt"] = {{"code", res.nlopt_code}, {"status", res.nlopt_status}};
  S["converged"] = res.converged;
  // the KKT report of a failed evaluation would read gradients that were never computed
  const auto kkt = res.final.ok ? lsmbs::kkt_report(prob, res.final) : lsmbs::KktReport{};
  S["kkt"] = res.final.ok ? kkt.to_json() : nlohmann::json(nullptr);
  S["gradient_check"] =
      checked ? lsmbs::gradient_check_json(*checked, *check) : nlohmann::json(nullptr);
  S["counts"] = {{"evaluations", res.evaluations},
                 {"simulations_this_run", res.simulations},
                 {"cache_hits", prob.cache_hits()}};
  S["wall_seconds"] = res.wall_seconds;
  S["final_design_mass"] = geo["bodies"];
  S["units"] = lsmbs::units_json(cs);
  std::vector<std::string> files = {"history.csv", "summary.json"};
  std::error_code ec;
  // none when the first evaluation was interrupted (resumed runs: the earlier run's, rewritten)
  if (std::filesystem::exists(out + "/checkpoint.json", ec)) files.push_back("checkpoint.json");
  if (plotted) files.push_back("convergence.png");
  for (const auto& f : geo["files"]) files.push_back("final_design/" + f.get<std::string>());
  S["files"] = lsmbs::file_list(std::move(files));
  lsmbs::write_json_atomic(out + "/summary.json", S);
  if (!quiet) {
    std::printf("lsmbs optimize: %s after %ld evaluations (%ld simulations in this run), %.1f s\n",
                res.nlopt_status.c_str(), res.evaluations, res.simulations, res.wall_seconds);
    std::printf("  objective %.9g -> %.9g, max constraint violation %.3e\n", first_objective,
                res.final.objective, res.final.max_violation);
    if (res.final.ok)
      std::printf(
          "  KKT: %d active constraints, %d free variables, %d at lower / %d at upper bounds; "
          "stationarity %.2e, "
          "bound-sign violation %.2e\n",
          kkt.active_constraints, kkt.free_variables, kkt.at_lower, kkt.at_upper, kkt.stationarity,
          kkt.bound_sign_violation);
    for (int i = 0; i < d.size(); ++i)
      std::printf("  %-10s %.6g -> %.6g\n", d.variables[i].name.c_str(), init[i], res.p[i]);
    std::printf("  results in %s\n", out.c_str());
  }
  if (!res.failure.empty()) {
    std::fprintf(stderr,
                 "lsmbs optimize: numerical failure: %s (results up to it kept; status partial)\n",
                 res.failure.c_str());
    return 1;
  }
  if (res.interrupted && res.evaluations == 0) {
    std::fprintf(stderr,
                 "lsmbs optimize: interrupted during the first evaluation (nothing to resume)\n");
    return 130;
  }
  if (res.interrupted && (lsmbs::interrupted() || stop_after > 0)) {
    std::fprintf(stderr,
                 "lsmbs optimize: interrupted after %ld evaluations; --resume continues from the "
                 "checkpoint\n",
                 res.evaluations);
    return 130;
  }
  return res.final.ok ? 0 : 1;
}

}  // namespace lsmbs::app
