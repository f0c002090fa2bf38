#include "lsmbs/runs/optimize.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "lsmbs/core/interrupt.hpp"
#include "lsmbs/core/json_file.hpp"
#include "lsmbs/io/output.hpp"
#include "lsmbs/io/plot.hpp"
#include "lsmbs/io/sha256.hpp"
#include "lsmbs/optimization/problem.hpp"
#include "lsmbs/records/json.hpp"
#include "lsmbs/runs/geometry.hpp"
#include "lsmbs/runs/mpi.hpp"

namespace lsmbs {
namespace {

// Convergence picture: the objective and (with constraints) the largest relative constraint
// violation per evaluation, in panels over the evaluation number (history.csv has the numbers).
bool plot_history(const std::string& out, const OptimizeResult& res, bool constrained) {
  std::vector<std::vector<double>> rows;
  for (size_t k = 0; k < res.history.size(); ++k)
    rows.push_back({double(k + 1), res.history[k].objective, res.history[k].max_violation});
  PanelPlotSpec ps;
  ps.png = out + "/convergence.png";
  ps.title = "convergence";
  ps.xlabel = "evaluation";
  ps.points = true;
  ps.panel_height = 180;
  ps.panels.push_back({"objective", {{2, "objective"}}});
  if (constrained)
    ps.panels.push_back({"max. relative violation", {{3, "max constraint violation"}}});
  return plot_panels(ps, rows);
}

nlohmann::json design_json(const Design& d, const Vec& p) {
  nlohmann::json j = nlohmann::json::object();
  for (int i = 0; i < d.size(); ++i) j[d.variables[static_cast<size_t>(i)].name] = p[i];
  return j;
}

double largest(const std::vector<double>& v) {
  return v.empty() ? NAN : *std::max_element(v.begin(), v.end());
}

// What every summary.json of the job holds before its outcome.
nlohmann::json provenance(const Case& cs, const OptimizationSpec& spec,
                          const OptimizeRunOptions& o) {
  nlohmann::json S = case_provenance(o.command, cs);
  S["overrides"] = cs.overrides;
  S["case_name"] = cs.name;
  S["options"] = {{"optimization", spec.to_json()},
                  {"generalized_alpha", nlohmann::json(cs.simulation)},
                  {"resume", o.resume},
                  {"ranks", o.alone ? 1 : mpi::world().size}};  // not in the resume hash
  return S;
}

// The gradient check at the initial design. False when the run must not go on (refused or
// interrupted), with run.summary saying why.
bool initial_check(DesignProblem& prob, const Case& cs, const OptimizationSpec& spec,
                   const OptimizeRunOptions& o, OptimizeRun& run) {
  const GradientCheckOptions& co = *o.check;
  run.checked = check_problem_gradients(prob, run.initial, co);
  if (interrupted()) {
    run.stage = OptimizeRun::Stage::kInterruptedInCheck;
    run.checked.reset();
    run.summary = provenance(cs, spec, o);
    run.summary["status"] = "interrupted";
    run.summary["failure"] = "interrupted by signal " + std::to_string(interrupted()) +
                             " during the gradient check at the initial design: nothing was "
                             "optimized";
    run.summary["interrupted_phase"] = kInitialCheckPhase;
    run.summary["resumable"] = true;
    return false;
  }
  if (!run.checked) return true;  // nothing to check (no variable moves a response)
  const GradientCheckResult& c = *run.checked;
  run.check_verdict = c.verdict(co);
  char worst[32];
  std::snprintf(worst, sizeof worst, "%.3g", c.worst);
  run.check_message = c.ok ? "response '" + c.worst_response +
                                 "': the gradient disagrees with central differences by " + worst +
                                 " (relative)"
                           : c.message;
  if (run.check_verdict != "fail") return true;
  run.stage = OptimizeRun::Stage::kCheckFailed;
  run.summary = provenance(cs, spec, o);
  run.summary["status"] = "refused";
  run.summary["failure"] = "gradient check at the initial design failed: " + run.check_message;
  run.summary["gradient_check"] = gradient_check_json(c, co);
  run.summary["units"] = units_json(prob.conditions());
  return false;
}

// What the user should know, the optimizer's first, then the design's.
std::vector<std::string> warnings_of(const Case& cs, const OptimizeRun& run) {
  const Design& d = *cs.design;
  const OptimizeResult& res = run.result;
  std::vector<std::string> w = res.warnings;
  if (run.check_verdict == "warn")
    w.push_back("gradient check at the initial design: " + run.check_message);
  if (auto x = d.coincident_features(run.initial); !x.empty()) w.push_back("initial design: " + x);
  if (auto x = d.features_outside(run.initial); !x.empty()) w.push_back("initial design: " + x);
  if (auto x = d.idle_variables(); !x.empty()) w.push_back(x);
  if (!cs.initial_state_note.empty()) w.push_back(cs.initial_state_note);
  if (auto x = d.coincident_features(res.p); !x.empty()) w.push_back("final design: " + x);
  if (run.judgement)
    for (const auto& f : run.judgement->flags()) w.push_back("final design: " + f);
  return w;
}

// summary.json of an optimization that ran: its status (a numerical failure, or a final
// evaluation that failed, leaves a partial result), the initial and final designs, the verdicts.
nlohmann::json outcome_summary(const Case& cs, const OptimizationSpec& spec,
                               const OptimizeRunOptions& o, const OptimizeRun& run,
                               const DesignProblem& prob) {
  const Design& d = *cs.design;
  const OptimizeResult& res = run.result;
  nlohmann::json S = provenance(cs, spec, o);
  S["status"] = !res.failure.empty() ? "partial"
                : res.interrupted    ? "interrupted"
                : res.final.ok       ? "complete"
                                     : "partial";
  S["report"] = res.report();
  if (!res.failure.empty()) S["failure"] = res.failure;
  // an interrupt during the first evaluation leaves no evaluation at all
  const Evaluation first = res.history.empty() ? Evaluation{} : res.history.front();
  S["initial"] = {{"design", design_json(d, run.initial)},
                  {"objective", res.history.empty() ? NAN : first.objective},
                  {"max_violation", res.history.empty() ? NAN : first.max_violation},
                  {"constraints_max", largest(first.constraints)}};
  S["final"] = {{"design", design_json(d, res.p)},
                {"objective", res.final.objective},
                {"max_violation", res.final.max_violation},
                {"constraints_max", largest(res.final.constraints)}};
  S["responses"] = {{spec.objective, res.final.objective}};
  S["nlopt"] = {{"code", res.nlopt_code}, {"status", res.nlopt_status}};
  S["stop_reason"] = res.stop_reason;
  S["converged"] = res.converged;
  S["warnings"] = run.warnings;
  // no KKT report of a failed evaluation: its gradients were never computed
  S["kkt"] = res.kkt ? res.kkt->to_json() : nlohmann::json(nullptr);
  S["gradient_check"] =
      run.checked ? gradient_check_json(*run.checked, *o.check) : nlohmann::json(nullptr);
  S["counts"] = {{"evaluations", res.evaluations},
                 {"simulations_this_run", res.simulations},
                 {"cache_hits", prob.cache_hits()}};
  S["wall_seconds"] = res.wall_seconds;
  S["units"] = units_json(prob.conditions());
  if (prob.conditions().several() || !prob.conditions().combinations.empty())
    S["conditions"] = conditions_json(cs, prob.conditions());
  S["judgement"] = run.judgement ? run.judgement->to_json() : nlohmann::json(nullptr);
  S["length_scale"] = prob.length_scale_json(res.p);
  return S;
}

void write_summary(const std::string& out, nlohmann::json& S, std::vector<std::string> files) {
  if (out.empty()) return;
  S["files"] = file_list(std::move(files));
  write_json_atomic(out + "/summary.json", S);
}

}  // namespace

int OptimizeRun::exit_code() const {
  if (stage == Stage::kInterruptedInCheck) return 130;
  if (stage == Stage::kCheckFailed || !result.failure.empty()) return 1;
  if (result.interrupted) return 130;
  return result.final.ok ? 0 : 1;
}

bool interrupted_in_initial_check(const std::string& out_dir) {
  std::error_code ec;
  if (out_dir.empty() || std::filesystem::exists(out_dir + "/checkpoint.json", ec)) return false;
  try {
    const auto S = nlohmann::json::parse(std::ifstream(out_dir + "/summary.json"));
    return S.value("interrupted_phase", "") == kInitialCheckPhase;
  } catch (const std::exception&) {
    return false;
  }
}

OptimizeRun run_optimize(const Case& cs, const OptimizationSpec& spec,
                         const OptimizeRunOptions& o) {
  const Design& d = *cs.design;
  OptimizeRun run;
  if (o.initial.size() && o.initial.size() != d.size())
    throw Error("run_optimize: the initial design has " + std::to_string(o.initial.size()) +
                " values, the case " + std::to_string(d.size()) + " design variables");
  run.initial = o.initial.size() ? o.initial : d.initial();
  const ConditionExecutor executor =
      o.executor ? o.executor
      : o.alone  ? thread_executor(1)  // a campaign uses the cores
                 : mpi::conditions_executor(mpi::conditions_at_once(spec.sensitivity.threads));
  DesignProblem prob(conditions_of(cs), spec, executor);
  // under MPI every rank runs this job (runs/mpi.hpp) and rank 0 writes its files, unless the
  // job is this process's alone
  const bool writes = !o.out_dir.empty() && (o.alone || mpi::world().rank == 0);
  if (writes) std::filesystem::create_directories(o.out_dir);
  if (o.on_start) o.on_start(prob.num_constraints());
  // a run interrupted during its gradient check has no checkpoint: resuming starts it anew
  OptimizeRunOptions opt = o;
  opt.resume = o.resume && !interrupted_in_initial_check(o.out_dir);
  if (opt.check && !opt.resume && !initial_check(prob, cs, spec, opt, run)) {
    if (writes) write_summary(o.out_dir, run.summary, {"summary.json"});
    return run;
  }
  OptimizeOptions oo;
  oo.out_dir = o.out_dir;
  oo.write_files = writes;
  oo.resume = opt.resume;
  oo.stop_after = o.stop_after;
  oo.on_evaluation = o.on_evaluation;
  oo.initial = run.initial;
  // a resumed run must see the same problem, and the same start when one was given
  oo.input_sha256 = resume_hash(cs);
  if (o.initial.size()) {
    std::string start = oo.input_sha256 + " start";
    char b[32];
    for (Eigen::Index i = 0; i < o.initial.size(); ++i)
      start += (std::snprintf(b, sizeof b, " %.17g", o.initial[i]), b);
    oo.input_sha256 = sha256_hex(start);
  }
  // an interrupt stops the evaluation in progress at its next step; that evaluation is dropped,
  // and the checkpoint keeps every one before it (--resume evaluates it again)
  run.result = optimize(prob, oo);
  const OptimizeResult& res = run.result;
  // the final design judged: a structure the mesh resolves, no load path through void
  if (spec.judge.enabled && !(d.bodies.empty() && d.solid_bodies.empty()) && res.final.ok &&
      !res.interrupted && res.failure.empty()) {
    try {
      run.judgement = judge_design(prob.conditions(), spec, res.p, executor);
    } catch (const Interrupted&) {  // the optimization's result stands; unjudged
    }
  }

  run.warnings = warnings_of(cs, run);
  run.summary = outcome_summary(cs, spec, opt, run, prob);
  nlohmann::json& S = run.summary;
  if (!writes) return run;

  // final design pictures and the convergence plot
  GeometryRunOptions go;
  go.out_dir = o.out_dir + "/final_design";
  const auto geo = run_geometry(cs, res.p, go);
  S["final_design_mass"] = geo["bodies"];
  std::vector<std::string> files = {"history.csv", "summary.json"};
  std::error_code ec;
  // none when the first evaluation was interrupted (resumed runs: the earlier run's, rewritten)
  if (std::filesystem::exists(o.out_dir + "/checkpoint.json", ec))
    files.push_back("checkpoint.json");
  if (plot_history(o.out_dir, res, prob.num_constraints() > 0)) files.push_back("convergence.png");
  for (const auto& f : geo["files"]) files.push_back("final_design/" + f.get<std::string>());
  write_summary(o.out_dir, S, std::move(files));
  return run;
}

}  // namespace lsmbs
