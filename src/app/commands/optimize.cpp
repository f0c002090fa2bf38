// lsmbs optimize: the fully coupled optimization of the case's design (NLopt MMA, CCSAQ, SLSQP,
// or the classic MMA), with a gradient check at the initial design, checkpoints and --resume.
#include "lsmbs/runs/optimize.hpp"

#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>

#include "app/commands/commands.hpp"
#include "app/commands/common.hpp"
#include "app/progress_line.hpp"
#include "lsmbs/core/error.hpp"
#include "lsmbs/io/case.hpp"
#include "lsmbs/io/optimization_spec.hpp"
#include "lsmbs/runs/mpi.hpp"
#include "lsmbs/runs/multistart.hpp"

namespace lsmbs::app {

namespace {

// Multi-start (--starts N): the library's run_multistart (runs/multistart.hpp) with the command
// line's options; prints its progress and the ranking.
int multistart(const CommonArgs& c, const OptimizeArgs& a, const lsmbs::Case& cs,
               const lsmbs::OptimizationSpec& spec) {
  lsmbs::MultistartOptions o;
  o.starts = a.starts;
  o.seed = a.seed;
  o.jobs = a.jobs;
  o.resume = a.resume;
  o.overwrite = a.overwrite;
  o.out_dir = c.out;
  o.command = c.command_line;
  if (a.check) o.check = a.check_options;
  if (!c.quiet)
    o.on_message = [](const std::string& line) {
      std::printf("%s\n", line.c_str());
      std::fflush(stdout);
    };
  const lsmbs::MultistartRun run = lsmbs::run_multistart(cs, spec, o);
  if (lsmbs::mpi::world().rank > 0) return run.exit_code();  // rank 0 says it
  if (run.interrupted_in_screening) {
    std::fprintf(stderr,
                 "lsmbs optimize: interrupted while screening candidate %d of the multi-start "
                 "(no start had begun; nothing was written: run the command again)\n",
                 run.candidates);
    return 130;
  }
  const auto& rows = run.rows;
  if (!run.all_ran && !c.quiet)
    std::fprintf(stderr, "multi-start: %d of %zu starts did not end well (starts.csv: exit_code)\n",
                 static_cast<int>(std::count_if(rows.begin(), rows.end(),
                                                [](const auto& r) { return r.exit_code != 0; })),
                 rows.size());
  if (!c.quiet && run.best > 0) {
    const auto& b = rows[run.best - 1];
    const auto& R = run.summary["ranking"];
    std::printf(
        "multi-start: %zu of %zu starts feasible; best %.9g (start %d, %s, stopped on '%s'), "
        "median %.9g, worst %.9g\n",
        run.order.size(), rows.size(), b.objective, run.best,
        b.converged ? "converged" : "not converged", b.stop_reason.c_str(),
        R["median"].get<double>(), R["worst"].get<double>());
    if (run.lowest != run.best) {
      const auto& l = rows[run.lowest - 1];
      if (l.verdict_rank() > b.verdict_rank())
        std::printf(
            "  start %d reached a lower objective, %.9g, but is ranked after it: its "
            "design is judged '%s' (%s)\n",
            run.lowest, l.objective, l.verdict.c_str(), l.flags.front().c_str());
      else
        std::printf(
            "  start %d reached a lower objective, %.9g, but is ranked after it: it %s (%s)\n",
            run.lowest, l.objective, l.tier() == 2 ? "was cut off" : "is not a KKT point",
            l.stop_reason.c_str());
    }
    std::map<std::string, int> verdicts;
    for (int k : run.order)
      ++verdicts[rows[k - 1].verdict.empty() ? "not judged" : rows[k - 1].verdict];
    std::string v;
    for (const auto& [name, n] : verdicts)
      v += (v.empty() ? "" : ", ") + std::to_string(n) + " " + name;
    std::printf("  judgement of the feasible designs: %s (summary.json: starts[].flags)\n",
                v.c_str());
    std::printf("  results in %s\n", c.out.c_str());
  }
  return run.exit_code();
}

// On a terminal: a table row per evaluation and a progress line of the running simulation; not on
// a terminal: the final summary only (history.csv has every evaluation), unless --verbose.
// The outcome on the terminal: objective, violation, KKT verdict, stop reason, the design.
void print_outcome(const lsmbs::OptimizeRun& run, const lsmbs::Design& d, const std::string& out) {
  const lsmbs::OptimizeResult& res = run.result;
  const double first_objective = res.history.empty() ? NAN : res.history.front().objective;
  std::printf("lsmbs optimize: %s after %ld evaluations (%ld simulations in this run), %.1f s\n",
              res.nlopt_status.c_str(), res.evaluations, res.simulations, res.wall_seconds);
  std::printf("  objective %.9g -> %.9g, max constraint violation %.3e\n", first_objective,
              res.final.objective, res.final.max_violation);
  if (const auto& kkt = res.kkt)
    std::printf(
        "  KKT: %d active constraints, %d free variables, %d at lower / %d at upper bounds; "
        "stationarity %.2e, complementarity %.2e, bound-sign violation %.2e: %s "
        "(kkt_tolerance %.2g)\n",
        kkt->active_constraints, kkt->free_variables, kkt->at_lower, kkt->at_upper,
        kkt->stationarity, kkt->complementarity, kkt->bound_sign_violation,
        kkt->satisfied() ? "satisfied" : "not satisfied", kkt->tolerance);
  std::printf("  stopped on '%s': %s\n", res.stop_reason.c_str(),
              res.converged ? "converged" : "not converged");
  for (int i = 0; i < d.size(); ++i)
    std::printf("  %-10s %.6g -> %.6g\n", d.variables[static_cast<size_t>(i)].name.c_str(),
                run.initial[i], res.p[i]);
  std::printf("  results in %s\n", out.c_str());
}

// --starts draws every start's initial design at random: an initial value given with --set would
// be replaced in every start.
void refuse_initial_sets(const CommonArgs& c, const lsmbs::Case& cs) {
  for (const auto& set : c.sets)
    for (int i = 0; i < cs.design->size(); ++i)
      if (pointers_overlap(set_target(set, cs.raw),
                           "/design/variables/" + std::to_string(i) + "/initial"))
        throw lsmbs::Error("--set " + set +
                           ": --starts draws the initial value of design variable '" +
                           cs.design->variables[static_cast<size_t>(i)].name +
                           "' at random in every start; drop this --set, or set the variable's "
                           "bounds (/design/variables/" +
                           std::to_string(i) + "/lower, /upper)");
}

// Testing hook (docs/verification.md): LSMBS_STOP_AFTER_EVALUATIONS=N ends the run after N
// evaluations simulated in this run exactly as an interruption (SIGINT) would: checkpoint and
// history written, status "interrupted", exit code 130, resumable with --resume. -1: not set.
long stop_after_hook() {
  const char* env = std::getenv("LSMBS_STOP_AFTER_EVALUATIONS");
  if (!env) return -1;
  char* end = nullptr;
  errno = 0;
  const long n = std::strtol(env, &end, 10);
  if (*env == '\0' || *end != '\0' || errno != 0 || n < 1)
    throw lsmbs::Error(
        "environment variable LSMBS_STOP_AFTER_EVALUATIONS=" + std::string(env) +
        ": expected a positive integer (a testing hook: stop after that many evaluations)");
  return n;
}

// What the terminal shows of a finished run (stdout unless quiet; failures on stderr).
int report_run(const lsmbs::OptimizeRun& run, const lsmbs::Design& d, const CommonArgs& c,
               const OptimizeArgs& a) {
  using Stage = lsmbs::OptimizeRun::Stage;
  if (lsmbs::mpi::world().rank > 0) return run.exit_code();  // rank 0 says it
  if (run.stage == Stage::kInterruptedInCheck) {
    std::fprintf(stderr, "lsmbs optimize: %s; --resume starts it again\n",
                 run.summary["failure"].get<std::string>().c_str());
  } else if (run.stage == Stage::kCheckFailed) {
    std::fprintf(stderr,
                 "lsmbs optimize: refused: gradient check at the initial design failed: %s (above "
                 "%g; --no-check skips the check)\n",
                 run.check_message.c_str(), a.check_options.fail);
  } else {
    const lsmbs::OptimizeResult& res = run.result;
    if (!c.quiet) print_outcome(run, d, c.out);
    for (const auto& w : run.warnings)
      std::fprintf(stderr, "lsmbs optimize: warning: %s\n", w.c_str());
    if (!res.failure.empty())
      std::fprintf(stderr,
                   "lsmbs optimize: numerical failure: %s (results up to it kept; status "
                   "partial)\n",
                   res.failure.c_str());
    else if (res.interrupted && res.evaluations == 0)
      std::fprintf(stderr,
                   "lsmbs optimize: interrupted during the first evaluation (nothing to "
                   "resume)\n");
    else if (res.interrupted)
      std::fprintf(stderr,
                   "lsmbs optimize: interrupted after %ld evaluations; --resume continues from "
                   "the checkpoint\n",
                   res.evaluations);
  }
  return run.exit_code();
}

}  // namespace

int optimize_command(const CommonArgs& c, const OptimizeArgs& a) {
  if (a.check) check_gradient_check_options(a.check_options);
  lsmbs::Case cs = load_case_with_sets(c.case_file, c.sets, /*design_as_initial=*/true);
  lsmbs::OptimizationSpec spec = lsmbs::parse_optimization(cs);  // before anything is written
  if (a.starts >= 1) refuse_initial_sets(c, cs);
  const long stop_after = stop_after_hook();
  lsmbs::set_optimizer(spec, cs, a.optimizer, "--optimizer " + a.optimizer);
  const bool interactive = !c.quiet && ::isatty(STDOUT_FILENO) && ::isatty(STDERR_FILENO);
  const bool table = interactive || (c.verbose && !c.quiet);
  ProgressLine line(interactive);
  spec.sensitivity.progress = line.callback();
  claim_output(c, *cs.model);
  std::filesystem::create_directories(c.out);
  if (a.starts >= 1) return multistart(c, a, cs, spec);
  const auto& d = *cs.design;
  lsmbs::OptimizeRunOptions o;
  o.out_dir = c.out;
  o.command = c.command_line;
  o.resume = a.resume;  // a run interrupted in its initial check starts anew (run_optimize)
  o.stop_after = stop_after;
  if (a.check) o.check = a.check_options;
  if (table)
    o.on_start = [&](int constraints) {
      std::printf("lsmbs optimize: %d variables, %d constraints, optimizer %s, sensitivities %s\n",
                  d.size(), constraints, spec.optimizer.c_str(),
                  lsmbs::SensitivityOptions::name(spec.sensitivity.method));
      std::printf("%6s %16s %14s %10s\n", "eval", "objective", "max violation", "time [s]");
    };
  o.on_evaluation = [&](int k, const lsmbs::Evaluation& e) {
    line.clear();
    if (table)
      std::printf("%6d %16.9g %14.4e %10.2f\n", k, e.objective, e.max_violation, e.wall_seconds);
    std::fflush(stdout);
  };
  const lsmbs::OptimizeRun run = lsmbs::run_optimize(cs, spec, o);
  line.clear();
  return report_run(run, d, c, a);
}

}  // namespace lsmbs::app
