// lsmbs optimize: the fully coupled optimization of the case's design (NLopt MMA, CCSAQ, SLSQP,
// or the classic MMA), with a gradient check at the initial design, checkpoints and --resume.
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <optional>
#include <random>
#include <sstream>
#include <thread>

#include "app/commands/commands.hpp"
#include "app/commands/common.hpp"
#include "app/progress_line.hpp"
#include "lsmbs/core/error.hpp"
#include "lsmbs/core/interrupt.hpp"
#include "lsmbs/core/json_file.hpp"
#include "lsmbs/io/case.hpp"
#include "lsmbs/io/geometry_run.hpp"
#include "lsmbs/io/optimization_spec.hpp"
#include "lsmbs/io/optimize_run.hpp"
#include "lsmbs/io/output.hpp"
#include "lsmbs/io/plot.hpp"
#include "lsmbs/io/sha256.hpp"
#include "lsmbs/optimization/kkt.hpp"
#include "lsmbs/optimization/optimizer.hpp"
#include "lsmbs/records/json.hpp"

namespace lsmbs::app {

namespace {

// Multi-start (--starts N): N feasible initial designs drawn uniformly within the bounds
// (std::mt19937_64 seeded with --seed; a candidate is kept when its evaluation is feasible:
// max_violation <= 0), each optimized by a child `lsmbs optimize` in OUT/start_k with the same
// options, two at a time on the two cores (each child with one sensitivity thread). The children
// are whole runs: each has its summary.json, checkpoint and --resume. OUT/starts.csv and
// OUT/summary.json rank the feasible results.
int multistart(const CommonArgs& c, const OptimizeArgs& a, lsmbs::Case& cs,
               lsmbs::DesignProblem& prob) {
  const auto& d = *cs.design;
  const int n = d.size();
  lsmbs::install_interrupt_handlers();
  std::mt19937_64 gen(a.seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<lsmbs::Vec> starts;
  const int max_candidates = 20 * a.starts;
  int candidates = 0;
  // OUT/multistart.json: the starts of this folder, written before any child runs; --resume
  // reuses them and refuses another seed or number of starts
  const std::string plan_file = c.out + "/multistart.json";
  if (a.resume) {
    std::error_code ec;
    if (!std::filesystem::exists(plan_file, ec))
      throw lsmbs::Error(plan_file + ": cannot resume a multi-start: no multistart.json here");
    nlohmann::json plan;
    try {
      plan = nlohmann::json::parse(std::ifstream(plan_file));
    } catch (const nlohmann::json::exception& e) {
      throw lsmbs::Error(plan_file + ": unreadable (" + e.what() + ")");
    }
    if (plan.value("seed", 0UL) != a.seed || plan.value("starts", 0) != a.starts)
      throw lsmbs::Error("--resume: " + plan_file + " holds --starts " +
                         std::to_string(plan.value("starts", 0)) + " --seed " +
                         std::to_string(plan.value("seed", 0UL)) + "; give the same options");
    for (const auto& row : plan.at("initial_designs")) {
      if (row.size() != static_cast<size_t>(n))
        throw lsmbs::Error(plan_file + ": a start has " + std::to_string(row.size()) +
                           " variables, the case " + std::to_string(n));
      lsmbs::Vec p(n);
      for (int i = 0; i < n; ++i) p[i] = row[i].get<double>();
      starts.push_back(p);
    }
    candidates = plan.value("candidates_evaluated", 0);
  }
  while (static_cast<int>(starts.size()) < a.starts && candidates < max_candidates) {
    lsmbs::Vec p(n);
    for (int i = 0; i < n; ++i)
      p[i] = d.variables[i].lower + u(gen) * (d.variables[i].upper - d.variables[i].lower);
    ++candidates;
    const lsmbs::Evaluation& e = prob.evaluate(p);
    if (e.interrupted || lsmbs::interrupted()) {  // not an infeasible candidate: not judged at all
      std::fprintf(stderr,
                   "lsmbs optimize: interrupted while screening candidate %d of the multi-start "
                   "(no start had begun; nothing was written: run the command again)\n",
                   candidates);
      return 130;
    }
    if (e.ok && e.max_violation <= 0) starts.push_back(p);
    if (!c.quiet)
      std::printf("multi-start: candidate %d %s (max violation %.3e)\n", candidates,
                  e.ok && e.max_violation <= 0 ? "feasible, kept" : "infeasible, skipped",
                  e.max_violation);
  }
  if (static_cast<int>(starts.size()) == a.starts && !a.resume) {
    nlohmann::json rows = nlohmann::json::array();
    for (const auto& p : starts) rows.push_back(std::vector<double>(p.data(), p.data() + n));
    lsmbs::write_json_atomic(plan_file, {{"seed", a.seed},
                                         {"starts", a.starts},
                                         {"candidates_evaluated", candidates},
                                         {"initial_designs", rows}});
  }
  if (static_cast<int>(starts.size()) < a.starts)
    throw lsmbs::NumericalFailure("multi-start: only " + std::to_string(starts.size()) + " of " +
                                  std::to_string(max_candidates) +
                                  " random designs are feasible; " + std::to_string(a.starts) +
                                  " were asked for (--starts)");
  const std::string exe = std::filesystem::read_symlink("/proc/self/exe").string();
  auto child_args = [&](int k) {
    std::vector<std::string> v = {
        exe, "optimize", c.case_file, "-o", c.out + "/start_" + std::to_string(k + 1), "-q"};
    for (const auto& set : c.sets) v.insert(v.end(), {"--set", set});
    char buf[64];
    for (int i = 0; i < n; ++i) {
      std::snprintf(buf, sizeof buf, "%.17g", starts[k][i]);
      v.insert(v.end(), {"--set", d.variables[i].name + "=" + buf});
    }
    // one sensitivity thread per child when two run at once, unless the user's own --set
    // chose the sensitivity options (a value may be set once)
    const std::string threads = cs.optimization.contains("sensitivity")
                                    ? "/optimization/sensitivity/threads=1"
                                    : "/optimization/sensitivity={\"threads\": 1}";
    if (a.jobs > 1 && std::none_of(c.sets.begin(), c.sets.end(), [&](const std::string& s) {
          return pointers_overlap(set_target(s, cs.raw), set_target(threads, cs.raw));
        }))
      v.insert(v.end(), {"--set", threads});
    if (!a.optimizer.empty()) v.insert(v.end(), {"--optimizer", a.optimizer});
    if (!a.check) {
      v.push_back("--no-check");  // and no thresholds: they would have no check to judge
    } else {
      std::snprintf(buf, sizeof buf, "%.17g", a.check_options.warn);
      v.insert(v.end(), {"--check-warn", buf});
      std::snprintf(buf, sizeof buf, "%.17g", a.check_options.fail);
      v.insert(v.end(), {"--check-fail", buf});
    }
    std::error_code ec;
    if (a.resume &&
        std::filesystem::exists(c.out + "/start_" + std::to_string(k + 1) + "/checkpoint.json", ec))
      v.push_back("--resume");
    else if (a.resume)  // never begun, or interrupted in its first evaluation: start it afresh
      v.push_back("--overwrite");
    if (a.overwrite) v.push_back("--overwrite");
    return v;
  };
  std::vector<int> rc(starts.size(), -1);
  std::atomic<int> next{0};
  auto worker = [&] {
    for (int k; (k = next++) < static_cast<int>(starts.size());) {
      if (lsmbs::interrupted()) return;
      auto args = child_args(k);
      std::vector<char*> argv;
      for (auto& s : args) argv.push_back(s.data());
      argv.push_back(nullptr);
      pid_t pid = 0;
      if (posix_spawn(&pid, exe.c_str(), nullptr, nullptr, argv.data(), environ) != 0) continue;
      int status = 0;
      bool forwarded = false;
      for (;;) {  // an interrupt of this process is passed on to the child (it checkpoints)
        const pid_t w = waitpid(pid, &status, WNOHANG);
        if (w == pid || (w < 0 && errno != EINTR)) break;
        if (lsmbs::interrupted() && !forwarded) {
          ::kill(pid, SIGINT);
          forwarded = true;
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(50));
      }
      rc[k] = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
      if (!c.quiet) std::printf("multi-start: start %d ended (exit %d)\n", k + 1, rc[k]);
      std::fflush(stdout);
    }
  };
  {
    std::vector<std::thread> pool;
    for (int j = 0; j < std::max(1, a.jobs); ++j) pool.emplace_back(worker);
    for (auto& t : pool) t.join();
  }
  // the ranking: feasible, completed starts; converged ones first, then those that stopped on their
  // tolerance without meeting the KKT conditions, then those cut off (the evaluation limit); by
  // objective within each tier: a lower objective of a start that did not finish is not a result
  struct Row {
    int start;
    int rc;
    std::string status;
    double objective = NAN, violation = NAN;
    long evaluations = 0;
    double wall = NAN;
    bool feasible = false;
    bool converged = false;
    std::string stop_reason = "", kkt_verdict = "";
    std::vector<double> final_design = {};
    int tier() const {
      return converged                                                                      ? 0
             : (stop_reason == "ftol" || stop_reason == "xtol" || stop_reason == "success") ? 1
                                                                                            : 2;
    }
  };
  std::vector<Row> rows;
  const double tol = prob.spec().tol_constraint;
  for (size_t k = 0; k < starts.size(); ++k) {
    Row r{static_cast<int>(k) + 1, rc[k], "not run"};
    r.final_design.assign(static_cast<size_t>(n), NAN);  // a start with no summary.json has none
    const std::string f = c.out + "/start_" + std::to_string(k + 1) + "/summary.json";
    std::error_code ec;
    if (std::filesystem::exists(f, ec)) {
      nlohmann::json S;
      try {
        S = nlohmann::json::parse(std::ifstream(f));
      } catch (const nlohmann::json::exception&) {
        S = {{"status", "unreadable summary.json"}};
      }
      r.status = S.contains("status") && S["status"].is_string() ? S["status"].get<std::string>()
                                                                 : "unknown";
      auto number = [](const nlohmann::json& j, const char* key) {
        return j.is_object() && j.contains(key) && j[key].is_number() ? j[key].get<double>()
                                                                      : double(NAN);
      };
      if (S.contains("final")) {
        r.objective = number(S["final"], "objective");
        r.violation = number(S["final"], "max_violation");
      }
      if (S.contains("counts") && S["counts"].is_object()) {
        const double e = number(S["counts"], "evaluations");
        r.evaluations = std::isfinite(e) ? static_cast<long>(e) : 0;
      }
      r.wall = number(S, "wall_seconds");
      r.feasible = r.status == "complete" && r.violation <= tol;
      r.converged = S.contains("converged") && S["converged"].is_boolean() && S["converged"];
      if (S.contains("stop_reason") && S["stop_reason"].is_string())
        r.stop_reason = S["stop_reason"].get<std::string>();
      if (S.contains("kkt") && S["kkt"].is_object() && S["kkt"].contains("verdict") &&
          S["kkt"]["verdict"].is_string())
        r.kkt_verdict = S["kkt"]["verdict"].get<std::string>();
      if (S.contains("final") && S["final"].is_object() && S["final"].contains("design"))
        for (int i = 0; i < n; ++i)
          r.final_design[static_cast<size_t>(i)] =
              number(S["final"]["design"], d.variables[i].name.c_str());
    }
    rows.push_back(r);
  }
  std::vector<double> objs;
  std::vector<int> order;  // feasible starts, best first
  for (const auto& r : rows)
    if (r.feasible) objs.push_back(r.objective), order.push_back(r.start);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
    const Row &ra = rows[a - 1], &rb = rows[b - 1];
    return ra.tier() != rb.tier() ? ra.tier() < rb.tier() : ra.objective < rb.objective;
  });
  const int best = order.empty() ? -1 : order.front();
  // the lowest objective of all feasible starts, when it is not the best one's (a start cut off)
  int lowest = best;
  for (int k : order)
    if (rows[k - 1].objective < rows[lowest - 1].objective) lowest = k;
  std::sort(objs.begin(), objs.end());
  {
    std::vector<std::string> header = {"start",         "exit_code", "status",      "objective",
                                       "max_violation", "feasible",  "evaluations", "wall_seconds",
                                       "stop_reason",   "kkt",       "converged",   "rank"};
    for (const auto& v : d.variables) header.push_back("initial." + v.name);
    for (const auto& v : d.variables) header.push_back("final." + v.name);
    std::ostringstream f;  // written whole (write_file_atomic: a full disk is an error, not a cut)
    for (size_t i = 0; i < header.size(); ++i) f << (i ? "," : "") << header[i];
    f << "\n";
    char buf[64];
    for (size_t k = 0; k < rows.size(); ++k) {
      const auto& r = rows[k];
      f << r.start << "," << r.rc << "," << r.status;
      for (double x : {r.objective, r.violation}) {
        std::snprintf(buf, sizeof buf, "%.17g", x);
        f << "," << buf;
      }
      f << "," << (r.feasible ? 1 : 0) << "," << r.evaluations;
      std::snprintf(buf, sizeof buf, "%.6g", r.wall);
      f << "," << buf;
      const auto rank = std::find(order.begin(), order.end(), r.start);
      f << "," << r.stop_reason << "," << r.kkt_verdict << "," << (r.converged ? 1 : 0) << ","
        << (rank == order.end() ? std::string() : std::to_string(rank - order.begin() + 1));
      for (int i = 0; i < n; ++i) {
        std::snprintf(buf, sizeof buf, "%.17g", starts[k][i]);
        f << "," << buf;
      }
      for (int i = 0; i < n; ++i) {
        std::snprintf(buf, sizeof buf, "%.17g", r.final_design[static_cast<size_t>(i)]);
        f << "," << buf;
      }
      f << "\n";
    }
    lsmbs::write_file_atomic(c.out + "/starts.csv", f.str());
  }
  nlohmann::json S = lsmbs::case_provenance(c.command_line, cs);
  S["overrides"] = cs.overrides;
  S["case_name"] = cs.name;
  // every child ended well (exit 0); a start that failed or was refused makes the run partial
  const bool all_ran =
      std::all_of(rows.begin(), rows.end(), [](const Row& r) { return r.rc == 0; });
  S["status"] = lsmbs::interrupted() ? "interrupted" : all_ran && best > 0 ? "complete" : "partial";
  S["options"] = {{"optimization", prob.spec().to_json()},
                  {"multistart",
                   {{"starts", a.starts},
                    {"seed", a.seed},
                    {"jobs", a.jobs},
                    {"sampling", "uniform within the bounds (std::mt19937_64), feasible ones kept"},
                    {"candidates_evaluated", candidates}}}};
  nlohmann::json list = nlohmann::json::array();
  for (const auto& r : rows)
    list.push_back({{"start", r.start},
                    {"folder", "start_" + std::to_string(r.start)},
                    {"exit_code", r.rc},
                    {"status", r.status},
                    {"objective", r.objective},
                    {"max_violation", r.violation},
                    {"feasible", r.feasible},
                    {"evaluations", r.evaluations},
                    {"stop_reason", r.stop_reason},
                    {"kkt", r.kkt_verdict},
                    {"converged", r.converged}});
  S["starts"] = list;
  static constexpr const char* kRankingRule =
      "feasible starts; converged ones first (stopped on their tolerance at a KKT point), then "
      "those that stopped on their tolerance without meeting the KKT conditions, then those cut "
      "off (max_evaluations); by objective within each";
  if (!objs.empty())
    S["ranking"] = {
        {"rule", kRankingRule},
        {"order", order},
        {"feasible_results", objs.size()},
        {"best", rows[best - 1].objective},
        {"best_start", best},
        {"best_stop_reason", rows[best - 1].stop_reason},
        {"best_converged", rows[best - 1].converged},
        {"lowest_objective", objs.front()},
        {"lowest_objective_start", lowest},
        {"median", objs.size() % 2 ? objs[objs.size() / 2]
                                   : 0.5 * (objs[objs.size() / 2 - 1] + objs[objs.size() / 2])},
        {"worst", objs.back()}};
  std::vector<std::string> files = {"starts.csv", "summary.json", "multistart.json"};
  for (const auto& r : rows) files.push_back("start_" + std::to_string(r.start) + "/");
  S["files"] = lsmbs::file_list(std::move(files));
  lsmbs::write_json_atomic(c.out + "/summary.json", S);
  if (!all_ran && !c.quiet)
    std::fprintf(stderr, "multi-start: %d of %zu starts did not end well (starts.csv: exit_code)\n",
                 static_cast<int>(std::count_if(rows.begin(), rows.end(),
                                                [](const Row& r) { return r.rc != 0; })),
                 rows.size());
  if (!c.quiet && !objs.empty()) {
    const Row& b = rows[best - 1];
    std::printf(
        "multi-start: %zu of %zu starts feasible; best %.9g (start %d, %s, stopped on '%s'), "
        "median %.9g, worst %.9g\n",
        objs.size(), rows.size(), b.objective, best, b.converged ? "converged" : "not converged",
        b.stop_reason.c_str(), S["ranking"]["median"].get<double>(), objs.back());
    if (lowest != best)
      std::printf(
          "  start %d reached a lower objective, %.9g, but is ranked after it: it %s (%s)\n",
          lowest, rows[lowest - 1].objective,
          rows[lowest - 1].tier() == 2 ? "was cut off" : "is not a KKT point",
          rows[lowest - 1].stop_reason.c_str());
    std::printf("  results in %s\n", c.out.c_str());
  }
  if (lsmbs::interrupted()) return 130;
  return all_ran && best > 0 ? 0 : 1;
}

}  // namespace

namespace {

// The folder holds a run interrupted before its first evaluation (during the initial gradient
// check): no checkpoint to resume from.
}  // namespace

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
        "stationarity %.2e, bound-sign violation %.2e: %s (kkt_tolerance %.2g)\n",
        kkt->active_constraints, kkt->free_variables, kkt->at_lower, kkt->at_upper,
        kkt->stationarity, kkt->bound_sign_violation,
        kkt->satisfied() ? "satisfied" : "not satisfied", kkt->tolerance);
  std::printf("  stopped on '%s': %s\n", res.stop_reason.c_str(),
              res.converged ? "converged" : "not converged");
  for (int i = 0; i < d.size(); ++i)
    std::printf("  %-10s %.6g -> %.6g\n", d.variables[static_cast<size_t>(i)].name.c_str(),
                run.initial[i], res.p[i]);
  std::printf("  results in %s\n", out.c_str());
}

int optimize_command(const CommonArgs& c, const OptimizeArgs& a) {
  const std::string& case_file = c.case_file;
  const std::string& out = c.out;
  const std::string& cmdline = c.command_line;
  const bool quiet = c.quiet, verbose = c.verbose;
  // a run interrupted during its initial gradient check has no checkpoint: --resume starts it anew
  const bool resume = a.resume && !lsmbs::interrupted_in_initial_check(out);
  const std::string& optimizer = a.optimizer;
  const lsmbs::GradientCheckOptions* check = a.check ? &a.check_options : nullptr;
  if (check) check_gradient_check_options(*check);
  lsmbs::Case cs = load_case_with_sets(case_file, c.sets, /*design_as_initial=*/true);
  lsmbs::OptimizationSpec spec =
      lsmbs::parse_optimization(cs);  // validated before anything is written
  if (a.starts >= 1) {
    // every start's initial design is drawn at random: an initial value given with --set would
    // be replaced in every start
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
  lsmbs::set_optimizer(spec, cs, optimizer, "--optimizer " + optimizer);
  const bool interactive = !quiet && ::isatty(STDOUT_FILENO) && ::isatty(STDERR_FILENO);
  const bool table = interactive || (verbose && !quiet);
  ProgressLine line(interactive);
  spec.sensitivity.progress = line.callback();
  claim_output(c, *cs.model);
  std::filesystem::create_directories(out);
  if (a.starts >= 1) {
    lsmbs::DesignProblem prob(cs, spec);
    return multistart(c, a, cs, prob);
  }
  const auto& d = *cs.design;
  lsmbs::OptimizeRunOptions o;
  o.out_dir = out;
  o.command = cmdline;
  o.resume = resume;
  o.stop_after = stop_after;
  if (check) o.check = *check;
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
  using Stage = lsmbs::OptimizeRun::Stage;
  if (run.stage == Stage::kInterruptedInCheck) {
    std::fprintf(stderr, "lsmbs optimize: %s; --resume starts it again\n",
                 run.summary["failure"].get<std::string>().c_str());
    return 130;
  }
  if (run.stage == Stage::kCheckFailed) {
    std::fprintf(stderr,
                 "lsmbs optimize: refused: gradient check at the initial design failed: %s (above "
                 "%g; --no-check skips the check)\n",
                 run.check_message.c_str(), check->fail);
    return 1;
  }
  const lsmbs::OptimizeResult& res = run.result;
  if (!quiet) print_outcome(run, d, out);
  for (const auto& w : run.warnings)
    std::fprintf(stderr, "lsmbs optimize: warning: %s\n", w.c_str());
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
