#include "lsmbs/runs/multistart.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <random>
#include <sstream>
#include <thread>

#include "lsmbs/core/error.hpp"
#include "lsmbs/core/interrupt.hpp"
#include "lsmbs/core/json_file.hpp"
#include "lsmbs/io/output.hpp"
#include "lsmbs/io/output_folder.hpp"
#include "lsmbs/optimization/problem.hpp"
#include "lsmbs/runs/mpi.hpp"
#include "lsmbs/runs/optimize.hpp"

namespace lsmbs {
namespace {

std::string g17(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.17g", v);
  return b;
}

void say(const MultistartOptions& o, const std::string& line) {
  if (o.on_message) o.on_message(line);
}

// The starts of a resumed multi-start: OUT/multistart.json, refused for another seed or number.
std::vector<Vec> stored_starts(const std::string& plan_file, const MultistartOptions& o, int n,
                               int& candidates) {
  std::error_code ec;
  if (!std::filesystem::exists(plan_file, ec))
    throw Error(plan_file + ": cannot resume a multi-start: no multistart.json here");
  nlohmann::json plan;
  try {
    plan = nlohmann::json::parse(std::ifstream(plan_file));
  } catch (const nlohmann::json::exception& e) {
    throw Error(plan_file + ": unreadable (" + e.what() + ")");
  }
  if (plan.value("seed", 0UL) != o.seed || plan.value("starts", 0) != o.starts)
    throw Error("--resume: " + plan_file + " holds --starts " +
                std::to_string(plan.value("starts", 0)) + " --seed " +
                std::to_string(plan.value("seed", 0UL)) + "; give the same options");
  std::vector<Vec> starts;
  for (const auto& row : plan.at("initial_designs")) {
    if (row.size() != static_cast<size_t>(n))
      throw Error(plan_file + ": a start has " + std::to_string(row.size()) +
                  " variables, the case " + std::to_string(n));
    Vec p(n);
    for (int i = 0; i < n; ++i) p[i] = row[i].get<double>();
    starts.push_back(p);
  }
  candidates = plan.value("candidates_evaluated", 0);
  return starts;
}

// Draws random designs within the bounds until `o.starts` are feasible (at most 20 per start):
// their responses meet the constraints. With length-scale constraints each random design is first
// moved to the nearest one that keeps them (DesignProblem::admissible_start, no simulation): a
// random layout of holes rarely keeps them (none of 80 on the robot arm), and an optimizer started
// far outside them stopped infeasible.
// False when interrupted.
bool screen(const Case& cs, const OptimizationSpec& spec, const MultistartOptions& o,
            std::vector<Vec>& starts, int& candidates) {
  const Design& d = *cs.design;
  const int n = d.size();
  std::mt19937_64 gen(o.seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  DesignProblem prob(conditions_of(cs), spec);
  const int max_candidates = 20 * o.starts;
  while (static_cast<int>(starts.size()) < o.starts && candidates < max_candidates) {
    Vec p(n);
    for (int i = 0; i < n; ++i)
      p[i] = d.variables[i].lower + u(gen) * (d.variables[i].upper - d.variables[i].lower);
    ++candidates;
    double geometric = 0;
    p = prob.admissible_start(p, &geometric);
    if (geometric > 1e-3) {  // SLSQP ends within its tolerance: the optimizer takes the rest
      char line[160];
      std::snprintf(line, sizeof line,
                    "multi-start: candidate %d skipped: no design near it keeps the length-scale "
                    "constraints (violation %.3e)",
                    candidates, geometric);
      say(o, line);
      continue;
    }
    const Evaluation& e = prob.evaluate(p);
    if (e.interrupted || interrupted()) return false;  // not infeasible: not judged at all
    const double violation = prob.response_violation(e);
    const bool kept = e.ok && violation <= 0;
    if (kept) starts.push_back(p);
    char line[160];
    std::snprintf(line, sizeof line, "multi-start: candidate %d %s (max violation %.3e)",
                  candidates, kept ? "feasible, kept" : "infeasible, skipped", violation);
    say(o, line);
  }
  if (static_cast<int>(starts.size()) < o.starts)
    throw NumericalFailure("multi-start: only " + std::to_string(starts.size()) + " of " +
                           std::to_string(max_candidates) + " random designs are feasible; " +
                           std::to_string(o.starts) + " were asked for (--starts)");
  return true;
}

// One start, as `lsmbs optimize` alone would run it in its folder: the folder claimed (an
// earlier run replaced only with overwrite, a user's file never), resumed from its checkpoint
// when the multi-start resumes and one exists, afresh otherwise.
MultistartRow run_start(const Case& cs, const OptimizationSpec& spec, const MultistartOptions& o,
                        int k, const Vec& p0) {
  MultistartRow r;
  r.start = k + 1;
  r.initial = p0;
  r.final_design = Vec::Constant(p0.size(), NAN);
  const std::string dir = o.out_dir + "/start_" + std::to_string(k + 1);
  std::error_code ec;
  const bool resume = o.resume && std::filesystem::exists(dir + "/checkpoint.json", ec);
  ReplacedRun replaced;
  try {
    check_output_folder(dir);
    // a start that never began, or was interrupted in its first evaluation, starts afresh
    replaced =
        claim_output_folder(dir, o.overwrite || o.resume, resume, planned_outputs(*cs.model));
    std::filesystem::create_directories(dir);
    OptimizeRunOptions ro;
    ro.out_dir = dir;
    ro.command =
        o.command + " [start " + std::to_string(k + 1) + " of " + std::to_string(o.starts) + "]";
    ro.resume = resume;
    ro.check = o.check;
    ro.initial = p0;
    ro.alone = true;  // a start is one task: on this rank (or thread) only
    const OptimizeRun run = run_optimize(cs, spec, ro);
    r.exit_code = run.exit_code();
    r.status = run.summary.value("status", "unknown");
    if (run.stage != OptimizeRun::Stage::kOptimized) {
      r.message = run.summary.value("failure", "");
      return r;
    }
    const OptimizeResult& res = run.result;
    r.objective = res.final.objective;
    r.violation = res.final.max_violation;
    r.evaluations = res.evaluations;
    r.wall = res.wall_seconds;
    r.feasible = r.status == "complete" && r.violation <= spec.tol_constraint;
    r.converged = res.converged;
    r.stop_reason = res.stop_reason;
    r.kkt_verdict = res.kkt ? res.kkt->to_json().value("verdict", "") : "";
    r.final_design = res.p;
    if (run.judgement)
      r.verdict = DesignJudgement::verdict_name(run.judgement->verdict()),
      r.flags = run.judgement->flags();
  } catch (const Error& e) {  // this start's input (its folder, its checkpoint): it did not run
    replaced.restore();
    r.exit_code = 2;
    r.status = "not run";
    r.message = e.what();
  } catch (const NumericalFailure& e) {
    r.exit_code = 1;
    r.status = "partial";
    r.message = e.what();
  }
  return r;
}

void write_starts_csv(const std::string& file, const Design& d, const MultistartRun& run) {
  std::vector<std::string> header = {"start",         "exit_code", "status",      "objective",
                                     "max_violation", "feasible",  "evaluations", "wall_seconds",
                                     "stop_reason",   "kkt",       "converged",   "judgement",
                                     "rank"};
  for (const auto& v : d.variables) header.push_back("initial." + v.name);
  for (const auto& v : d.variables) header.push_back("final." + v.name);
  std::ostringstream f;  // written whole (write_file_atomic: a full disk is an error, not a cut)
  for (size_t i = 0; i < header.size(); ++i) f << (i ? "," : "") << header[i];
  f << "\n";
  for (const auto& r : run.rows) {
    char wall[32];
    std::snprintf(wall, sizeof wall, "%.6g", r.wall);
    const auto rank = std::find(run.order.begin(), run.order.end(), r.start);
    f << r.start << "," << r.exit_code << "," << r.status << "," << g17(r.objective) << ","
      << g17(r.violation) << "," << (r.feasible ? 1 : 0) << "," << r.evaluations << "," << wall
      << "," << r.stop_reason << "," << r.kkt_verdict << "," << (r.converged ? 1 : 0) << ","
      << r.verdict << ","
      << (rank == run.order.end() ? std::string() : std::to_string(rank - run.order.begin() + 1));
    for (Eigen::Index i = 0; i < r.initial.size(); ++i) f << "," << g17(r.initial[i]);
    for (Eigen::Index i = 0; i < r.final_design.size(); ++i) f << "," << g17(r.final_design[i]);
    f << "\n";
  }
  write_file_atomic(file, f.str());
}

// The ranking: feasible, completed starts; by the judgement's verdict (runs/judge.hpp): sound
// designs, then unresolved ones, then those that are no structure (a lighter design that hangs on
// void is not a better result);
// converged ones first, then those that stopped on their tolerance without meeting the KKT
// conditions, then those cut off (the evaluation limit); by objective within each tier: a lower
// objective of a start that did not finish is not a result.
void rank(MultistartRun& run) {
  for (const auto& r : run.rows)
    if (r.feasible) run.order.push_back(r.start);
  const auto& rows = run.rows;
  std::stable_sort(run.order.begin(), run.order.end(), [&](int a, int b) {
    const MultistartRow &ra = rows[a - 1], &rb = rows[b - 1];
    if (ra.verdict_rank() != rb.verdict_rank()) return ra.verdict_rank() < rb.verdict_rank();
    return ra.tier() != rb.tier() ? ra.tier() < rb.tier() : ra.objective < rb.objective;
  });
  run.best = run.lowest = run.order.empty() ? -1 : run.order.front();
  for (int k : run.order)  // the lowest objective, when it is not the best one's (cut off)
    if (rows[k - 1].objective < rows[run.lowest - 1].objective) run.lowest = k;
  run.all_ran = std::all_of(rows.begin(), rows.end(),
                            [](const MultistartRow& r) { return r.exit_code == 0; });
}

nlohmann::json ranking_json(const MultistartRun& run) {
  std::vector<double> objs;
  for (int k : run.order) objs.push_back(run.rows[k - 1].objective);
  std::sort(objs.begin(), objs.end());
  if (objs.empty()) return nullptr;
  const MultistartRow& b = run.rows[run.best - 1];
  const size_t m = objs.size();
  return {{"rule",
           "feasible starts; by the judgement of the final design: sound, then unresolved (parts "
           "narrower than the mesh resolves), then not a structure (pieces, load paths through "
           "void); then converged ones first (stopped on their tolerance at a KKT "
           "point), then those that stopped on their tolerance without meeting the KKT "
           "conditions, then those cut off (max_evaluations); by objective within each"},
          {"order", run.order},
          {"feasible_results", m},
          {"best", b.objective},
          {"best_start", run.best},
          {"best_stop_reason", b.stop_reason},
          {"best_converged", b.converged},
          {"lowest_objective", objs.front()},
          {"lowest_objective_start", run.lowest},
          {"median", m % 2 ? objs[m / 2] : 0.5 * (objs[m / 2 - 1] + objs[m / 2])},
          {"worst", objs.back()}};
}

nlohmann::json summary_json(const Case& cs, const OptimizationSpec& spec,
                            const MultistartOptions& o, const MultistartRun& run) {
  nlohmann::json S = case_provenance(o.command, cs);
  S["overrides"] = cs.overrides;
  S["case_name"] = cs.name;
  S["status"] = interrupted()                 ? "interrupted"
                : run.all_ran && run.best > 0 ? "complete"
                                              : "partial";
  S["options"] = {
      {"optimization", spec.to_json()},
      {"multistart",
       {{"starts", o.starts},
        {"seed", o.seed},
        {"jobs", o.jobs},
        {"ranks", mpi::world().size},
        {"sampling",
         "uniform within the bounds (std::mt19937_64), moved to the nearest design that keeps the "
         "length-scale constraints if any, kept when the responses meet the constraints"},
        {"candidates_evaluated", run.candidates}}}};
  nlohmann::json list = nlohmann::json::array();
  for (const auto& r : run.rows) {
    list.push_back({{"start", r.start},
                    {"folder", "start_" + std::to_string(r.start)},
                    {"exit_code", r.exit_code},
                    {"status", r.status},
                    {"objective", r.objective},
                    {"max_violation", r.violation},
                    {"feasible", r.feasible},
                    {"evaluations", r.evaluations},
                    {"stop_reason", r.stop_reason},
                    {"kkt", r.kkt_verdict},
                    {"converged", r.converged},
                    {"judgement", r.verdict},
                    {"flags", r.flags}});
    if (!r.message.empty()) list.back()["message"] = r.message;
  }
  S["starts"] = list;
  if (auto ranking = ranking_json(run); !ranking.is_null()) S["ranking"] = ranking;
  std::vector<std::string> files = {"starts.csv", "summary.json", "multistart.json"};
  for (const auto& r : run.rows) files.push_back("start_" + std::to_string(r.start) + "/");
  S["files"] = file_list(std::move(files));
  return S;
}

}  // namespace

std::string MultistartOptions::validate() const {
  if (starts < 1) return "starts: expected at least 1";
  if (jobs < 1) return "jobs: expected at least 1";
  if (out_dir.empty()) return "out_dir: a multi-start writes a folder per start; give one";
  return {};
}

int MultistartRow::tier() const {
  return converged                                                                      ? 0
         : (stop_reason == "ftol" || stop_reason == "xtol" || stop_reason == "success") ? 1
                                                                                        : 2;
}

int MultistartRun::exit_code() const {
  if (ranks_exit >= 0) return ranks_exit;
  if (interrupted_in_screening || interrupted()) return 130;
  return all_ran && best > 0 ? 0 : 1;
}

namespace {

// A start's row as bytes (a task of the farm hands it to rank 0): exact doubles (NaN as null).
nlohmann::json number(double v) {
  return std::isnan(v) ? nlohmann::json(nullptr) : nlohmann::json(v);
}
double number(const nlohmann::json& j) { return j.is_null() ? NAN : j.get<double>(); }
nlohmann::json vector(const Vec& v) {
  nlohmann::json a = nlohmann::json::array();
  for (Eigen::Index i = 0; i < v.size(); ++i) a.push_back(number(v[i]));
  return a;
}
Vec vector(const nlohmann::json& a) {
  Vec v(static_cast<Eigen::Index>(a.size()));
  for (size_t i = 0; i < a.size(); ++i) v[static_cast<Eigen::Index>(i)] = number(a[i]);
  return v;
}
std::string row_bytes(const MultistartRow& r) {
  return nlohmann::json{{"start", r.start},
                        {"exit_code", r.exit_code},
                        {"status", r.status},
                        {"message", r.message},
                        {"objective", number(r.objective)},
                        {"violation", number(r.violation)},
                        {"wall", number(r.wall)},
                        {"evaluations", r.evaluations},
                        {"feasible", r.feasible},
                        {"converged", r.converged},
                        {"stop_reason", r.stop_reason},
                        {"kkt", r.kkt_verdict},
                        {"judgement", r.verdict},
                        {"flags", r.flags},
                        {"initial", vector(r.initial)},
                        {"final", vector(r.final_design)}}
      .dump();
}
MultistartRow row_from(const std::string& bytes) {
  const auto j = nlohmann::json::parse(bytes);
  MultistartRow r;
  r.start = j["start"], r.exit_code = j["exit_code"], r.status = j["status"];
  r.message = j["message"], r.objective = number(j["objective"]);
  r.violation = number(j["violation"]), r.wall = number(j["wall"]);
  r.evaluations = j["evaluations"], r.feasible = j["feasible"], r.converged = j["converged"];
  r.stop_reason = j["stop_reason"], r.kkt_verdict = j["kkt"];
  r.verdict = j["judgement"], r.flags = j["flags"].get<std::vector<std::string>>();
  r.initial = vector(j["initial"]), r.final_design = vector(j["final"]);
  return r;
}

// The starts: drawn (or, resuming, read) by rank 0 and handed to every rank. Empty: interrupted
// while screening.
std::vector<Vec> plan_starts(const Case& cs, const OptimizationSpec& spec,
                             const MultistartOptions& o, MultistartRun& run) {
  const Design& d = *cs.design;
  nlohmann::json plan = nullptr;
  if (mpi::world().rank == 0) {
    const std::string plan_file = o.out_dir + "/multistart.json";
    std::vector<Vec> starts;
    if (o.resume) starts = stored_starts(plan_file, o, d.size(), run.candidates);
    if (screen(cs, spec, o, starts, run.candidates)) {
      plan = {{"seed", o.seed}, {"starts", o.starts}, {"candidates_evaluated", run.candidates}};
      nlohmann::json rows = nlohmann::json::array();
      for (const auto& p : starts)
        rows.push_back(std::vector<double>(p.data(), p.data() + p.size()));
      plan["initial_designs"] = rows;
      if (!o.resume) write_json_atomic(plan_file, plan);
    }
  }
  plan = nlohmann::json::parse(mpi::broadcast(plan.dump()));
  std::vector<Vec> starts;
  if (plan.is_null()) return starts;
  run.candidates = plan["candidates_evaluated"];
  for (const auto& row : plan["initial_designs"]) {
    Vec p(static_cast<Eigen::Index>(row.size()));
    for (size_t i = 0; i < row.size(); ++i) p[static_cast<Eigen::Index>(i)] = row[i];
    starts.push_back(p);
  }
  return starts;
}

}  // namespace

MultistartRun run_multistart(const Case& cs, const OptimizationSpec& spec,
                             const MultistartOptions& o) {
  if (auto msg = o.validate(); !msg.empty()) throw Error("multi-start option " + msg);
  const Design& d = *cs.design;
  MultistartRun run;
  const std::vector<Vec> starts = plan_starts(cs, spec, o, run);
  if (starts.empty()) {
    run.interrupted_in_screening = true;
    return run;
  }
  // one sensitivity thread per start when several run at once, unless the case chose its own
  OptimizationSpec start_spec = spec;
  const bool own_threads = cs.optimization.contains("sensitivity") &&
                           cs.optimization["sensitivity"].is_object() &&
                           cs.optimization["sensitivity"].contains("threads");
  if ((o.jobs > 1 || mpi::world().size > 1) && !own_threads) start_spec.sensitivity.threads = 1;
  start_spec.sensitivity.progress = nullptr;  // the starts report by their end only
  run.rows.resize(starts.size());
  for (size_t k = 0; k < starts.size(); ++k) {
    run.rows[k].start = static_cast<int>(k) + 1;
    run.rows[k].initial = starts[k];
    run.rows[k].final_design = Vec::Constant(d.size(), NAN);
  }
  // the starts over the ranks as they finish one (or `jobs` threads of this process): each is a
  // whole optimize run in its folder, written by the rank that runs it
  mpi::task_farm(
      static_cast<int>(starts.size()), o.jobs,
      [&](int k) { return row_bytes(run_start(cs, start_spec, o, k, starts[k])); },
      [&](int k, const std::string& bytes) {
        run.rows[static_cast<size_t>(k)] = row_from(bytes);
        say(o, "multi-start: start " + std::to_string(k + 1) + " ended (exit " +
                   std::to_string(run.rows[static_cast<size_t>(k)].exit_code) + ")");
      },
      [&](int k, const std::string& why) {
        run.rows[static_cast<size_t>(k)].exit_code = 1;
        run.rows[static_cast<size_t>(k)].status = "failed";
        run.rows[static_cast<size_t>(k)].message = why;
      });
  if (mpi::world().rank == 0) {
    rank(run);
    write_starts_csv(o.out_dir + "/starts.csv", d, run);
    run.summary = summary_json(cs, spec, o, run);
    write_json_atomic(o.out_dir + "/summary.json", run.summary);
  }
  if (mpi::world().size > 1)  // every rank ends with rank 0's outcome
    run.ranks_exit = std::stoi(mpi::broadcast(std::to_string(run.exit_code())));
  return run;
}

}  // namespace lsmbs
