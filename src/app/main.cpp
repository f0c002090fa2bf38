// lsmbs — command line of the level-set flexible-multibody testbed.
//
//   lsmbs simulate CASE.json -o OUT      generalized-α simulation (Algorithm 1 of the paper)
//   lsmbs geometry CASE.json -o OUT      level-set design mapped on the mesh (μ_e VTU + PNG, mass)
//   lsmbs sensitivity CASE.json --method NAME -o OUT   responses and design gradients (§4.3)
//   lsmbs optimize CASE.json -o OUT [--resume]         fully coupled optimization (NLopt MMA)
//   lsmbs verify CASE.json -o OUT                      verification report (methods, Δp, h, mesh)
//   lsmbs bench CASE.json -o OUT                       step cost against the floor, sensitivity overheads
//   lsmbs --version
//
// Exit codes: 0 success; 1 numerical failure (message says when and why); 2 invalid input or
// usage (file, JSON path, what was expected). Nothing is written when the input is invalid.
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <optional>
#include <set>

#include "lsmbs/core/error.hpp"
#include "lsmbs/core/interrupt.hpp"
#include "lsmbs/core/version.hpp"
#include "lsmbs/io/case.hpp"
#include "lsmbs/io/geometry_run.hpp"
#include "lsmbs/io/output.hpp"
#include "lsmbs/io/plot.hpp"
#include "lsmbs/sensitivity/response_quadrature.hpp"
#include "lsmbs/sensitivity/gradient_check.hpp"
#include "lsmbs/sensitivity/sensitivity.hpp"
#include "lsmbs/io/optimization_spec.hpp"
#include "lsmbs/io/verify_run.hpp"
#include "lsmbs/io/bench_run.hpp"
#include "lsmbs/optimization/kkt.hpp"
#include "lsmbs/optimization/optimizer.hpp"
#include "lsmbs/io/simulation_run.hpp"

namespace {

std::string joined_args(int argc, char** argv) {
  std::string s;
  for (int i = 0; i < argc; ++i) {
    if (i) s += ' ';
    s += argv[i];
  }
  return s;
}

lsmbs::Vec design_point(const lsmbs::Case& cs, const std::vector<std::string>& sets);
void check_idas_tolerances(double rtol, double atol);

int simulate(const std::string& case_file, const std::string& out, const std::vector<std::string>& sets, bool quiet,
             bool verbose, const std::string& integrator, double rtol, double atol, int max_order,
             const std::string& error_test, const std::string& cmdline) {
  check_idas_tolerances(rtol, atol);
  lsmbs::Case cs = lsmbs::load_case(case_file);  // validates everything before writing
  lsmbs::RunOptions ro;
  if (!sets.empty()) {
    if (!cs.design) throw lsmbs::Error(case_file, "/design", "--set needs a design section (design variables)");
    ro.design_point = design_point(cs, sets);
    cs.design->apply(ro.design_point, cs.model->params());
  }
  ro.out_dir = out;
  ro.progress = !quiet && ::isatty(STDERR_FILENO);
  ro.command_line = cmdline;
  ro.idas = integrator == "idas";
  ro.idas_options.rtol = rtol;
  ro.idas_options.atol = atol > 0 ? atol : rtol;
  ro.idas_options.max_order = max_order;
  using ET = lsmbs::IdasOptions::ErrorTest;
  ro.idas_options.error_test = error_test == "positions"    ? ET::kPositions
                               : error_test == "positions+velocities" ? ET::kPositionsAndVelocities
                                                                       : ET::kAuto;
  if (verbose)
    std::fprintf(stderr, "lsmbs: case '%s': %d DOFs, %d constraint equations, %d nonzeros\n", cs.name.c_str(),
                 cs.model->nq(), cs.model->nc(), cs.model->pattern().nnz());
  lsmbs::install_interrupt_handlers();
  const auto res = lsmbs::run_simulation(cs, ro);
  const auto& s = res.integrator;
  if (res.interrupted) {
    std::fprintf(stderr, "lsmbs simulate: %s; what was computed is in %s (status partial)\n", s.message.c_str(),
                 out.c_str());
    return 130;
  }
  if (!quiet) {
    std::printf("lsmbs simulate: %s — %ld steps, %ld Newton iterations, %ld factorizations, %.3f s\n",
                s.ok ? "complete" : "FAILED", s.steps, s.newton_iterations, s.factorizations, s.wall_seconds);
    if (s.halvings) std::printf("  step halvings: %ld (first at t = %g s)\n", s.halvings, s.halving_times.front());
    if (s.ok)
      for (const auto& [name, v] : res.responses) std::printf("  %-28s %.10g\n", name.c_str(), v);
    std::printf("  results in %s\n", out.c_str());
  }
  if (!s.ok) {
    std::fprintf(stderr, "lsmbs: numerical failure: %s\n  (partial results in %s, flagged in summary.json)\n",
                 s.message.c_str(), out.c_str());
    return 1;
  }
  return 0;
}

// "name=value" overrides of design variables.
std::pair<std::string, double> parse_set(const std::string& s) {
  const auto eq = s.find('=');
  if (eq == std::string::npos) throw lsmbs::Error("--set " + s + ": expected name=value");
  try {
    size_t used = 0;
    const double v = std::stod(s.substr(eq + 1), &used);
    if (used != s.size() - eq - 1) throw std::invalid_argument("trailing characters");
    return {s.substr(0, eq), v};
  } catch (const std::exception&) {
    throw lsmbs::Error("--set " + s + ": expected a number after '='");
  }
}

// The output folder (-o) must be a folder that exists or can be created, and be writable: checked
// before anything runs, without creating it (nothing is written for invalid input).
void check_output_folder(const std::string& out) {
  namespace fs = std::filesystem;
  if (out.empty()) throw lsmbs::Error("-o \"\": expected an output folder name");
  std::error_code ec;
  fs::path p = fs::absolute(out, ec);
  if (ec) throw lsmbs::Error("-o " + out + ": not a usable path (" + ec.message() + ")");
  if (fs::exists(p, ec) && !fs::is_directory(p, ec))
    throw lsmbs::Error("-o " + out + ": exists and is not a folder");
  // the nearest existing ancestor must be a writable folder
  fs::path q = p;
  while (!fs::exists(q, ec) && q.has_parent_path() && q.parent_path() != q) q = q.parent_path();
  if (!fs::is_directory(q, ec)) throw lsmbs::Error("-o " + out + ": " + q.string() + " is not a folder");
  if (::access(q.c_str(), W_OK) != 0 || q.string().rfind("/proc", 0) == 0 || q.string().rfind("/sys", 0) == 0)
    throw lsmbs::Error("-o " + out + ": cannot create or write in " + q.string());
}

// An output folder that holds an earlier lsmbs run is refused (its files would be mixed with this
// run's) unless --overwrite, which removes the earlier run's files first (and only those);
// optimize --resume continues the run the folder holds.
void claim_output_folder(const std::string& out, bool overwrite, bool resume) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (resume || !fs::is_directory(out, ec)) return;
  static const std::set<std::string> kFiles = {"summary.json", "history.csv", "gradients.csv", "checkpoint.json",
                                               "report.md",    "bench.json",  "convergence.png"};
  static const std::set<std::string> kFolders = {"vtu", "final_design"};
  static const std::set<std::string> kExtensions = {".pvd", ".png", ".csv", ".gp"};
  std::vector<fs::path> ours;
  for (const auto& e : fs::directory_iterator(out, ec)) {
    const std::string name = e.path().filename().string();
    if (kFiles.count(name) || (e.is_directory() && kFolders.count(name)) ||
        (e.is_regular_file() && kExtensions.count(e.path().extension().string())))
      ours.push_back(e.path());
  }
  if (ours.empty()) return;
  if (!overwrite)
    throw lsmbs::Error("-o " + out + ": the folder holds an earlier run (" + ours.front().filename().string() +
                       (ours.size() > 1 ? ", … " + std::to_string(ours.size()) + " entries" : std::string()) +
                       "); give another folder, or --overwrite to replace that run");
  for (const auto& p : ours) fs::remove_all(p);
}

// A run that ends with an exception once it has started (a numerical failure raised deep inside,
// memory exhausted, an internal error) leaves a summary.json with status partial and the reason,
// replacing any earlier summary: exit 1 always comes with results flagged as partial.
void flag_failed_run(const std::string& out, const std::string& cmdline, const std::string& case_file,
                     const std::string& what) {
  try {
    std::filesystem::create_directories(out);
    nlohmann::json S = lsmbs::provenance(cmdline, case_file, "");
    S["status"] = "partial";
    S["failure"] = what;
    lsmbs::write_json_atomic(out + "/summary.json", S);
  } catch (const std::exception&) {  // the folder cannot be written: the message on stderr remains
  }
}

// IDAS tolerances from the command line: checked before anything runs
void check_idas_tolerances(double rtol, double atol) {
  if (!(rtol > 0) || !std::isfinite(rtol) || rtol >= 1)
    throw lsmbs::Error("--rtol " + std::to_string(rtol) + ": expected a relative tolerance in (0, 1)");
  if (!(atol >= 0) || !std::isfinite(atol))
    throw lsmbs::Error("--atol " + std::to_string(atol) + ": expected a non-negative absolute tolerance (0: rtol)");
}

lsmbs::Vec design_point(const lsmbs::Case& cs, const std::vector<std::string>& sets) {
  lsmbs::Vec p = cs.design->initial();
  for (const auto& s : sets) {
    const auto [name, value] = parse_set(s);
    const int k = cs.design->variable_index(name);
    if (k < 0) throw lsmbs::Error("--set " + s + ": unknown design variable '" + name + "'");
    const auto& v = cs.design->variables[k];
    if (!(value >= v.lower && value <= v.upper))
      throw lsmbs::Error("--set " + s + ": outside the bounds [" + std::to_string(v.lower) + ", " +
                         std::to_string(v.upper) + "] of design variable '" + name +
                         "' (the case validates its features over these bounds; widen them in the case to go further)");
    p[k] = value;
  }
  return p;
}

int geometry(const std::string& case_file, const std::string& out, const std::vector<std::string>& sets, int width,
             bool quiet, const std::string& cmdline) {
  lsmbs::Case cs = lsmbs::load_case(case_file);
  if (!cs.design) throw lsmbs::Error(case_file, "/design", "the case has no design section (nothing to map)");
  const lsmbs::Vec p = design_point(cs, sets);
  lsmbs::GeometryRunOptions o;
  o.out_dir = out;
  o.image_width = width;
  o.command_line = cmdline;
  const auto S = lsmbs::run_geometry(cs, p, o);
  if (!quiet) {
    for (const auto& b : S["bodies"])
      std::printf("lsmbs geometry: body '%s': mass %.6f kg, void area %.6e m², %d cut elements of %d\n",
                  b["body"].get<std::string>().c_str(), b["mass"].get<double>(), b["void_area"].get<double>(),
                  b["cut_elements"].get<int>(), b["elements"].get<int>());
    std::printf("  results in %s\n", out.c_str());
  }
  return 0;
}

void print_gradient_check(const lsmbs::GradientCheckResult& c, const lsmbs::GradientCheckOptions& o) {
  std::printf("  gradient check (central differences along a random direction, 2 simulations): %s\n",
              c.verdict(o).c_str());
  if (!c.ok) {
    std::printf("    %s\n", c.message.c_str());
    return;
  }
  for (const auto& e : c.entries)
    std::printf("    %-24s fd %+.6e  method %+.6e  relative disagreement %.2e\n", e.response.c_str(),
                e.finite_difference, e.method, e.relative_error);
}

int sensitivity(const std::string& case_file, const std::string& out, const std::vector<std::string>& sets,
                const std::string& method, double delta, bool absolute, const std::string& matrix, bool full_residual,
                double rtol, double atol, int threads, bool quiet, const std::string& cmdline,
                const lsmbs::GradientCheckOptions* check) {
  lsmbs::SensitivityOptions so;
  so.threads = threads;
  if (!lsmbs::SensitivityOptions::parse(method, so.method)) {
    std::string all;
    for (const auto& n : lsmbs::SensitivityOptions::names()) all += (all.empty() ? "" : ", ") + n;
    throw lsmbs::Error("--method " + method + ": expected one of " + all);
  }
  if (!(delta > 0) || !std::isfinite(delta)) throw lsmbs::Error("--delta: expected a positive step");
  check_idas_tolerances(rtol, atol);
  if (!lsmbs::SensitivityOptions::parse_matrix(matrix, so.matrix))
    throw lsmbs::Error("--matrix " + matrix + ": expected last, converged or refined");
  so.delta = delta;
  so.relative = !absolute;
  so.idas.rtol = rtol;
  so.idas.atol = atol > 0 ? atol : rtol;
  so.full_residual = full_residual;
  lsmbs::Case cs = lsmbs::load_case(case_file);
  if (!cs.design) throw lsmbs::Error(case_file, "/design", "sensitivities need a design section (design variables)");
  if (cs.responses.empty()) throw lsmbs::Error(case_file, "/output/responses", "sensitivities need at least one response");
  const lsmbs::Vec p = design_point(cs, sets);
  so.idas.h_out = cs.simulation.h;  // what IDAS runs with (recorded in summary.json)
  so.idas.t_end = cs.simulation.t_end;
  lsmbs::ProgressLine line(!quiet && ::isatty(STDERR_FILENO));
  so.progress = &line;
  lsmbs::install_interrupt_handlers();  // an interrupt stops the generalized-α runs at the next step
  const auto res = lsmbs::compute_sensitivities(cs, p, so);
  std::optional<lsmbs::GradientCheckResult> checked;
  if (check && res.ok) checked = lsmbs::check_gradients(cs, p, res.responses, *check);
  line.clear();
  const auto& d = *cs.design;
  // summary.json and gradients.csv
  nlohmann::json responses = nlohmann::json::object(), grads = nlohmann::json::object();
  std::vector<std::string> header = {"response", "index", "t", "value"};
  for (const auto& v : d.variables) header.push_back("d/d" + v.name);
  std::vector<std::vector<double>> rows;
  std::vector<std::string> row_names;
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
    responses[rs.name] = per_step ? nlohmann::json(rs.values) : nlohmann::json(rs.values.empty() ? NAN : rs.values[0]);
    grads[rs.name] = g;
    for (size_t k = 0; k < rs.values.size(); ++k) {
      std::vector<double> row = {static_cast<double>(r), static_cast<double>(k), per_step ? rs.times[k] : NAN, rs.values[k]};
      for (int i = 0; i < d.size(); ++i) row.push_back(rs.gradient(static_cast<Eigen::Index>(k), i));
      rows.push_back(row);
    }
  }
  nlohmann::json S = lsmbs::provenance(cmdline, cs.file, cs.sha256);
  S["case_name"] = cs.name;
  S["status"] = res.ok ? "complete" : res.interrupted ? "interrupted" : "partial";
  if (!res.ok) S["failure"] = res.message;
  nlohmann::json vars = nlohmann::json::object();
  for (int i = 0; i < d.size(); ++i) vars[d.variables[i].name] = p[i];
  S["design"] = vars;
  S["options"] = {{"sensitivity", so.to_json()}, {"generalized_alpha", cs.simulation.to_json()}};
  S["counts"] = res.counts.to_json();
  S["primal"] = res.primal.to_json();
  S["warnings"] = res.warnings;
  if (checked) S["gradient_check"] = checked->to_json(*check);
  for (const auto& w : res.warnings) std::fprintf(stderr, "lsmbs sensitivity: warning: %s\n", w.c_str());
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
    S["quadratures"] = lsmbs::ResponseQuadrature::to_json(res.quadratures, names);
  }
  if (so.is_idas()) S["idas"] = res.idas.to_json();
  std::filesystem::create_directories(out);
  {
    // the CSV names responses by index (numbers only); the mapping is in the header comment
    std::string csv = "# responses:";
    for (size_t r = 0; r < res.responses.size(); ++r) csv += " " + std::to_string(r) + "=" + res.responses[r].name;
    csv += "\n";
    for (size_t i = 0; i < header.size(); ++i) csv += (i ? "," : "") + header[i];
    csv += "\n";
    char buf[64];
    for (const auto& row : rows) {
      for (size_t i = 0; i < row.size(); ++i) {
        std::snprintf(buf, sizeof buf, "%.17g", row[i]);
        csv += (i ? "," : "") + std::string(buf);
      }
      csv += "\n";
    }
    if (res.ok) lsmbs::write_file_atomic(out + "/gradients.csv", csv);  // a failed run has no gradients
  }
  lsmbs::write_json_atomic(out + "/summary.json", S);
  if (!quiet) {
    std::printf("lsmbs sensitivity (%s): %s — %ld simulations, %ld steps, %ld factorizations, %ld back-solves (%ld rhs), %.3f s\n",
                method.c_str(), res.ok ? "complete" : "FAILED", res.counts.simulations, res.counts.steps,
                res.counts.factorizations, res.counts.back_solves, res.counts.back_solve_rhs, res.counts.wall_seconds);
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
      std::printf("  %-24s %.10g (IDAS quadrature on [%g, %g])\n", q.name.c_str(), q.value, q.t0, q.t1);
      for (int i = 0; i < d.size() && i < q.gradient.size(); ++i)
        std::printf("      d/d%-12s %+.10e\n", d.variables[i].name.c_str(), q.gradient[i]);
    }
    if (checked) print_gradient_check(*checked, *check);
    std::printf("  results in %s\n", out.c_str());
  }
  if (res.interrupted) {
    std::fprintf(stderr, "lsmbs sensitivity: %s; partial results in %s\n", res.message.c_str(), out.c_str());
    return 130;
  }
  if (!res.ok) {
    std::fprintf(stderr, "lsmbs: numerical failure: %s\n", res.message.c_str());
    return 1;
  }
  if (checked && checked->verdict(*check) == "fail") {
    std::fprintf(stderr, "lsmbs: gradient check failed: %s\n",
                 checked->ok ? ("response '" + checked->worst_response + "' disagrees with central differences by " +
                                std::to_string(checked->worst)).c_str()
                             : checked->message.c_str());
    return 1;
  }
  return 0;
}

// Convergence plot (objective and maximum constraint violation per evaluation) with gnuplot,
// when it is installed; returns false otherwise.
bool plot_history(const std::string& out) {
  const std::string script = out + "/convergence.gp";
  {
    std::ofstream g(script);
    g << "set terminal pngcairo size 900,500 noenhanced\nset output " << lsmbs::gnuplot_quote(out + "/convergence.png") << "\n"
      << "set datafile separator ','\nset key autotitle columnhead\nset xlabel 'evaluation'\n"
      << "set ylabel 'objective'\nset y2label 'max. relative constraint violation'\nset y2tics\nset grid\n"
      << "plot " << lsmbs::gnuplot_quote(out + "/history.csv") << " using 1:2 with linespoints title 'objective', "
      << "'' using 1:3 axes x1y2 with linespoints title 'max constraint violation'\n";
  }
  const bool ok = lsmbs::run_gnuplot(script);
  std::filesystem::remove(script);
  std::error_code ec;
  if (!ok) std::filesystem::remove(out + "/convergence.png", ec);  // no 0-byte picture
  return ok;
}

// On a terminal: a table row per evaluation and a progress line of the running simulation; not on
// a terminal: the final summary only (history.csv has every evaluation), unless --verbose.
int optimize(const std::string& case_file, const std::string& out, bool resume, const std::string& optimizer,
             bool quiet, bool verbose, const std::string& cmdline, const lsmbs::GradientCheckOptions* check) {
  lsmbs::Case cs = lsmbs::load_case(case_file);
  lsmbs::OptimizationSpec spec = lsmbs::parse_optimization(cs);  // validated before anything is written
  // Testing hook (docs/verification.md): LSMBS_STOP_AFTER_EVALUATIONS=N ends the run after N
  // evaluations simulated in this run exactly as an interruption (SIGINT) would: checkpoint and
  // history written, status "interrupted", exit code 130, resumable with --resume.
  long stop_after = -1;
  if (const char* env = std::getenv("LSMBS_STOP_AFTER_EVALUATIONS")) {
    char* end = nullptr;
    errno = 0;
    const long n = std::strtol(env, &end, 10);
    if (*env == '\0' || *end != '\0' || errno != 0 || n < 1)
      throw lsmbs::Error("environment variable LSMBS_STOP_AFTER_EVALUATIONS=" + std::string(env) +
                         ": expected a positive integer (a testing hook: stop after that many evaluations)");
    stop_after = n;
  }
  if (!optimizer.empty()) {
    if (optimizer != "mma-svanberg" && cs.optimization.contains("move_limit"))
      throw lsmbs::Error("--optimizer " + optimizer + ": the case sets a move_limit, which only mma-svanberg has");
    spec.optimizer = optimizer;
  }
  const bool interactive = !quiet && ::isatty(STDOUT_FILENO) && ::isatty(STDERR_FILENO);
  const bool table = interactive || (verbose && !quiet);
  lsmbs::ProgressLine line(interactive);
  spec.sensitivity.progress = &line;
  std::filesystem::create_directories(out);
  lsmbs::DesignProblem prob(cs, spec);
  const auto& d = *cs.design;
  lsmbs::OptimizeOptions o;
  o.input_sha256 = cs.sha256;
  o.out_dir = out;
  o.resume = resume;
  o.stop_after = stop_after;
  if (table) {
    std::printf("lsmbs optimize: %d variables, %d constraints, optimizer %s, sensitivities %s\n", d.size(),
                prob.num_constraints(), spec.optimizer.c_str(), lsmbs::SensitivityOptions::name(spec.sensitivity.method));
    std::printf("%6s %16s %14s %10s\n", "eval", "objective", "max violation", "time [s]");
  }
  o.on_evaluation = [&](int k, const lsmbs::Evaluation& e) {
    line.clear();
    if (table) std::printf("%6d %16.9g %14.4e %10.2f\n", k, e.objective, e.max_violation, e.wall_seconds);
    std::fflush(stdout);
  };
  // Gradient check at the initial design (not on resume: the first run did it)
  std::optional<lsmbs::GradientCheckResult> checked;
  if (check && !resume) {
    const lsmbs::Vec p0 = d.initial();
    const auto sres = lsmbs::compute_sensitivities(cs, p0, spec.sensitivity);
    if (sres.ok) {
      std::vector<lsmbs::ResponseSensitivity> used;
      for (const auto& r : sres.responses) {
        bool use = r.name == spec.objective;
        for (const auto& c : spec.constraints) use |= r.name == c.response;
        if (use) used.push_back(r);
      }
      checked = lsmbs::check_gradients(cs, p0, used, *check);
      line.clear();
      const std::string verdict = checked->verdict(*check);
      if (verdict != "pass") {
        const std::string what = checked->ok ? "response '" + checked->worst_response +
                                                   "': the gradient disagrees with central differences by " +
                                                   std::to_string(checked->worst) + " (relative)"
                                             : checked->message;
        if (verdict == "fail") {
          nlohmann::json S = lsmbs::provenance(cmdline, cs.file, cs.sha256);
          S["case_name"] = cs.name;
          S["status"] = "refused";
          S["failure"] = "gradient check at the initial design failed: " + what;
          S["options"] = {{"optimization", spec.to_json()}, {"generalized_alpha", cs.simulation.to_json()}};
          S["gradient_check"] = checked->to_json(*check);
          lsmbs::write_json_atomic(out + "/summary.json", S);
          std::fprintf(stderr,
                       "lsmbs optimize: refused: gradient check at the initial design failed: %s (above %g; "
                       "--no-check skips the check)\n", what.c_str(), check->fail);
          return 1;
        }
        if (!quiet) std::fprintf(stderr, "lsmbs optimize: warning: gradient check at the initial design: %s\n", what.c_str());
      }
    }
  }
  // an interrupt stops the evaluation in progress at its next step; that evaluation is dropped, and the
  // checkpoint keeps every one before it (--resume evaluates it again)
  lsmbs::install_interrupt_handlers();
  const auto res = lsmbs::optimize(prob, o);
  line.clear();
  // final design pictures and summary
  lsmbs::GeometryRunOptions go;
  go.out_dir = out + "/final_design";
  const auto geo = lsmbs::run_geometry(cs, res.p, go);
  const bool plotted = plot_history(out);
  nlohmann::json S = lsmbs::provenance(cmdline, cs.file, cs.sha256);
  S["case_name"] = cs.name;
  S["status"] = !res.failure.empty() ? "partial" : res.interrupted ? "interrupted" : res.final.ok ? "complete" : "partial";
  if (!res.failure.empty()) S["failure"] = res.failure;
  S["options"] = {{"optimization", spec.to_json()}, {"generalized_alpha", cs.simulation.to_json()}};
  nlohmann::json p0 = nlohmann::json::object(), pf = nlohmann::json::object();
  const lsmbs::Vec init = d.initial();
  for (int i = 0; i < d.size(); ++i) p0[d.variables[i].name] = init[i], pf[d.variables[i].name] = res.p[i];
  // an interrupt during the first evaluation leaves no evaluation at all
  const lsmbs::Evaluation first = res.history.empty() ? lsmbs::Evaluation{} : res.history.front();
  const double first_objective = res.history.empty() ? NAN : first.objective;
  S["initial"] = {{"design", p0}, {"objective", first_objective},
                  {"max_violation", res.history.empty() ? NAN : first.max_violation},
                  {"constraints_max", first.constraints.empty() ? NAN
                                      : *std::max_element(first.constraints.begin(), first.constraints.end())}};
  S["final"] = {{"design", pf}, {"objective", res.final.objective}, {"max_violation", res.final.max_violation},
                {"constraints_max", res.final.constraints.empty() ? NAN
                                    : *std::max_element(res.final.constraints.begin(), res.final.constraints.end())}};
  S["responses"] = {{spec.objective, res.final.objective}};
  S["nlopt"] = {{"code", res.nlopt_code}, {"status", res.nlopt_status}};
  S["converged"] = res.converged;
  // the KKT report of a failed evaluation would read gradients that were never computed
  const auto kkt = res.final.ok ? lsmbs::kkt_report(prob, res.final) : lsmbs::KktReport{};
  S["kkt"] = res.final.ok ? kkt.to_json() : nlohmann::json(nullptr);
  S["gradient_check"] = checked ? checked->to_json(*check) : nlohmann::json(nullptr);
  S["counts"] = {{"evaluations", res.evaluations}, {"simulations_this_run", res.simulations},
                 {"cache_hits", prob.cache_hits()}};
  S["wall_seconds"] = res.wall_seconds;
  S["final_design_mass"] = geo["bodies"];
  S["files"] = {{"history", "history.csv"}, {"checkpoint", "checkpoint.json"}, {"final_design", "final_design/"},
                {"convergence_plot", plotted ? nlohmann::json("convergence.png") : nlohmann::json(nullptr)}};
  lsmbs::write_json_atomic(out + "/summary.json", S);
  if (!quiet) {
    std::printf("lsmbs optimize: %s after %ld evaluations (%ld simulations in this run), %.1f s\n",
                res.nlopt_status.c_str(), res.evaluations, res.simulations, res.wall_seconds);
    std::printf("  objective %.9g -> %.9g, max constraint violation %.3e\n", first_objective, res.final.objective,
                res.final.max_violation);
    if (res.final.ok)
      std::printf("  KKT: %d active constraints, %d free variables, %d at lower / %d at upper bounds; stationarity %.2e, "
                  "bound-sign violation %.2e\n", kkt.active_constraints, kkt.free_variables, kkt.at_lower, kkt.at_upper,
                  kkt.stationarity, kkt.bound_sign_violation);
    for (int i = 0; i < d.size(); ++i) std::printf("  %-10s %.6g -> %.6g\n", d.variables[i].name.c_str(), init[i], res.p[i]);
    std::printf("  results in %s\n", out.c_str());
  }
  if (!res.failure.empty()) {
    std::fprintf(stderr, "lsmbs optimize: numerical failure: %s (results up to it kept; status partial)\n",
                 res.failure.c_str());
    return 1;
  }
  if (res.interrupted && res.evaluations == 0) {
    std::fprintf(stderr, "lsmbs optimize: interrupted during the first evaluation (nothing to resume)\n");
    return 130;
  }
  if (res.interrupted && (lsmbs::interrupted() || stop_after > 0)) {
    std::fprintf(stderr, "lsmbs optimize: interrupted after %ld evaluations; --resume continues from the checkpoint\n",
                 res.evaluations);
    return 130;
  }
  return res.final.ok ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"lsmbs — level-set structural optimization of flexible multibody system components"};
  app.require_subcommand(0, 1);
  bool version = false;
  app.add_flag("--version", version, "print version and git commit");

  std::string case_file, out = "out";
  bool quiet = false, verbose = false, overwrite = false;
  auto* sim = app.add_subcommand("simulate", "simulate a case with the generalized-alpha scheme");
  sim->add_option("case", case_file, "case file (JSON)")->required()->check(CLI::ExistingFile);
  sim->add_option("-o,--output", out, "output folder (summary.json, history.csv, VTU)")->capture_default_str();
  sim->add_flag("--overwrite", overwrite, "reuse an output folder that holds an earlier run (its lsmbs files are removed first)");
  sim->add_flag("-q,--quiet", quiet, "print nothing but errors");
  sim->add_flag("-v,--verbose", verbose, "print model statistics");
  std::string integrator = "generalized-alpha";
  double rtol = 1e-9;
  sim->add_option("--integrator", integrator, "generalized-alpha (the paper's) or idas (SUNDIALS IDAS, GGL index 2)")
      ->check(CLI::IsMember({"generalized-alpha", "idas"}))->capture_default_str();
  sim->add_option("--rtol", rtol, "IDAS relative tolerance")->capture_default_str();
  double atol = 0;
  sim->add_option("--atol", atol, "IDAS absolute tolerance on positions, in units of the model's length scale "
                                  "(default: rtol)");
  int max_order = 0;
  sim->add_option("--max-order", max_order, "IDAS maximum BDF order 1-5; 0 = auto (2, A-stable, for models with a "
                                            "flexible body; 5 otherwise)")
      ->check(CLI::Range(0, 5))->capture_default_str();
  std::string error_test = "auto";
  sim->add_option("--error-test", error_test, "IDAS error test: positions, positions+velocities, or auto (positions "
                                              "for models with a flexible body)")
      ->check(CLI::IsMember({"auto", "positions", "positions+velocities"}))->capture_default_str();

  std::vector<std::string> sets;
  sim->add_option("--set", sets, "design variable override name=value (repeatable)");
  int width = 1600;
  auto* geo = app.add_subcommand("geometry", "map the level-set design onto the mesh: μ_e (VTU, PNG), mass and its gradient");
  geo->add_option("case", case_file, "case file (JSON) with a design section")->required()->check(CLI::ExistingFile);
  geo->add_option("-o,--output", out, "output folder")->capture_default_str();
  geo->add_flag("--overwrite", overwrite, "reuse an output folder that holds an earlier run (its lsmbs files are removed first)");
  geo->add_option("--set", sets, "design variable override name=value (repeatable)");
  geo->add_option("--width", width, "PNG width in pixels")->capture_default_str()->check(CLI::Range(16, 20000));
  geo->add_flag("-q,--quiet", quiet, "print nothing but errors");

  std::string method = "direct-analytic";
  double delta = 1e-6;
  bool absolute = false;
  auto* sen = app.add_subcommand("sensitivity", "responses and their design gradients (semi-analytical, direct, finite differences)");
  sen->add_option("case", case_file, "case file (JSON) with design variables and responses")->required()->check(CLI::ExistingFile);
  sen->add_option("-o,--output", out, "output folder")->capture_default_str();
  sen->add_flag("--overwrite", overwrite, "reuse an output folder that holds an earlier run (its lsmbs files are removed first)");
  sen->add_option("--method", method,
                  "semi-analytical | semi-analytical-central | direct-analytic | fd-forward | fd-central | idas | "
                  "idas-adjoint (time-integral responses only)")
      ->capture_default_str();
  sen->add_option("--delta", delta, "perturbation Δp (semi-analytical) or finite-difference step")->capture_default_str();
  sen->add_flag("--absolute", absolute, "Δp absolute instead of relative to max(|p_i|, 1e-2 (upper - lower))");
  std::string matrix = lsmbs::SensitivityOptions::matrix_name(lsmbs::SensitivityOptions{}.matrix);
  bool full_residual = false;
  sen->add_flag("--full-residual", full_residual,
                "semi-analytical pseudo-loads from whole-residual evaluations (Algorithm 2 literally) instead of element-local ones");
  sen->add_option("--matrix", matrix,
                  "matrix of the back-solves: converged (default: S_t refactorized at the converged state, exact), "
                  "refined (S_t at the converged state by iterative refinement, exact), last (the last Newton "
                  "iteration's, Algorithm 2 literally; not exact where a step converged in one iteration)")->capture_default_str();
  sen->add_option("--set", sets, "design variable override name=value (repeatable)");
  sen->add_option("--rtol", rtol, "--method idas, idas-adjoint: IDAS relative tolerance")->capture_default_str();
  sen->add_option("--atol", atol, "--method idas, idas-adjoint: IDAS absolute tolerance in units of the length scale (default: rtol)");
  int threads = 2;
  sen->add_option("--threads", threads,
                  "2: the sensitivity update of each step runs on a second thread while the next step is computed; "
                  "1: one thread (same results to round-off)")->capture_default_str()->check(CLI::Range(1, 2));
  sen->add_flag("-q,--quiet", quiet, "print nothing but errors");
  bool check = false;
  lsmbs::GradientCheckOptions check_opt;
  sen->add_flag("--check", check,
                "gradient check: central differences of 2 more simulations along a random direction against the "
                "gradient; per-response disagreement in summary.json (exit 1 above --check-fail)");
  sen->add_option("--check-delta", check_opt.delta, "--check: relative step along the direction")->capture_default_str();
  sen->add_option("--check-seed", check_opt.seed, "--check: seed of the random direction")->capture_default_str();
  sen->add_option("--check-warn", check_opt.warn, "--check: warn above this relative disagreement")->capture_default_str();
  sen->add_option("--check-fail", check_opt.fail, "--check: fail above this relative disagreement")->capture_default_str();

  bool resume = false;
  auto* opt = app.add_subcommand("optimize", "fully coupled optimization of the case's design (NLopt MMA/CCSAQ/SLSQP)");
  opt->add_option("case", case_file, "case file (JSON) with design, responses and an optimization section")
      ->required()->check(CLI::ExistingFile);
  opt->add_option("-o,--output", out, "output folder (history.csv, checkpoint.json, final_design/, summary.json)")
      ->capture_default_str();
  opt->add_flag("--overwrite", overwrite, "reuse an output folder that holds an earlier run (its lsmbs files are removed first)");
  opt->add_flag("--resume", resume, "continue an interrupted run from OUT/checkpoint.json");
  std::string optimizer;
  opt->add_option("--optimizer", optimizer, "override the case's optimizer")
      ->check(CLI::IsMember({"mma", "ccsaq", "slsqp", "mma-svanberg"}));
  opt->add_flag("-q,--quiet", quiet, "print nothing but errors");
  bool no_check = false;
  lsmbs::GradientCheckOptions opt_check;
  opt->add_flag("--no-check", no_check,
                "skip the gradient check at the initial design (default: central differences along a random "
                "direction, 2 simulations; warns above --check-warn, refuses above --check-fail)");
  opt->add_option("--check-warn", opt_check.warn, "gradient check: warn above this relative disagreement")
      ->capture_default_str();
  opt->add_option("--check-fail", opt_check.fail, "gradient check: refuse above this relative disagreement")
      ->capture_default_str();
  opt->add_flag("-v,--verbose", verbose, "a row per evaluation also when not on a terminal (default there: final summary only)");

  lsmbs::VerifyOptions vo;
  bool no_idas = false, no_mesh = false;
  auto* ver = app.add_subcommand("verify", "verification report: every sensitivity method, costs, delta-p study, "
                                           "time-step study against IDAS, mesh study, pass/fail");
  ver->add_option("case", case_file, "case file (JSON) with design variables and responses")->required()->check(CLI::ExistingFile);
  ver->add_option("-o,--output", out, "output folder (report.md, CSV, PNG)")->capture_default_str();
  ver->add_flag("--overwrite", overwrite, "reuse an output folder that holds an earlier run (its lsmbs files are removed first)");
  ver->add_flag("--no-idas", no_idas, "skip IDAS (too slow for long runs of stiff flexible models)");
  ver->add_flag("--no-mesh-study", no_mesh, "skip the mesh study");
  ver->add_option("--fd-delta", vo.fd_delta, "fd-central step")->capture_default_str();
  ver->add_flag("--fd-absolute", vo.fd_absolute, "fd-central step absolute instead of relative");
  ver->add_option("--tol-fd", vo.tol_fd, "threshold direct-analytic vs fd-central")->capture_default_str();
  ver->add_option("--tol-semi", vo.tol_semi, "threshold semi-analytical-central vs direct-analytic")->capture_default_str();
  ver->add_option("--set", sets, "design variable override name=value (repeatable)");

  lsmbs::BenchOptions bo;
  std::vector<std::string> bench_methods;
  auto* ben = app.add_subcommand("bench", "whole-run benchmark: step cost against the KLU/assembly floor, "
                                          "sensitivity overheads, peak memory");
  ben->add_option("case", case_file, "case file (JSON)")->required()->check(CLI::ExistingFile);
  ben->add_option("-o,--output", out, "output folder (bench.json, summary.json)")->capture_default_str();
  ben->add_flag("--overwrite", overwrite, "reuse an output folder that holds an earlier run (its lsmbs files are removed first)");
  ben->add_option("--methods", bench_methods, "sensitivity methods to time (default: direct-analytic "
                                              "semi-analytical-central; 'none' for none)");
  ben->add_option("--matrices", bo.matrices, "back-solve matrices timed besides the default for the direct methods "
                                             "(last, converged, refined; 'none' for none)")->capture_default_str();
  ben->add_option("--repetitions", bo.repetitions, "repetitions of the floor measurements")->capture_default_str()
      ->check(CLI::Range(1, 100000));
  ben->add_option("--threads", bo.threads, "threads of the sensitivity runs (see sensitivity --threads)")
      ->capture_default_str()->check(CLI::Range(1, 2));

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int rc = app.exit(e);
    return rc == 0 ? 0 : 2;
  }
  if (version) {
    std::printf("lsmbs %s (commit %s)\n", lsmbs::kVersion, lsmbs::git_commit());
    return 0;
  }
  bool started = false;  // the output folder is ours: a failure from here on is flagged in it
  try {
    if (*sim || *geo || *opt || *ben || *ver || *sen) {
      check_output_folder(out);
      claim_output_folder(out, overwrite, *opt && resume);
      started = true;
    }
    if (*sim) return simulate(case_file, out, sets, quiet, verbose, integrator, rtol, atol, max_order, error_test,
                                joined_args(argc, argv));
    if (*geo) return geometry(case_file, out, sets, width, quiet, joined_args(argc, argv));
    if (*opt)
      return optimize(case_file, out, resume, optimizer, quiet, verbose, joined_args(argc, argv),
                      no_check ? nullptr : &opt_check);
    if (*ben) {
      bo.out_dir = out;
      bo.command_line = joined_args(argc, argv);
      if (!bench_methods.empty()) bo.methods = bench_methods;
      if (bo.methods.size() == 1 && bo.methods[0] == "none") bo.methods.clear();
      if (bo.matrices.size() == 1 && bo.matrices[0] == "none") bo.matrices.clear();
      for (const auto& m : bo.methods) {
        lsmbs::SensitivityOptions::Method mm;
        if (!lsmbs::SensitivityOptions::parse(m, mm)) throw lsmbs::Error("--methods " + m + ": unknown sensitivity method");
      }
      for (const auto& m : bo.matrices) {
        lsmbs::SensitivityOptions::Matrix mm;
        if (!lsmbs::SensitivityOptions::parse_matrix(m, mm))
          throw lsmbs::Error("--matrices " + m + ": expected last, converged or refined");
      }
      const auto J = lsmbs::run_bench(case_file, bo);
      std::printf("lsmbs bench: step %.3f ms, floor %.3f ms (residual %.3f + matrix %.3f + KLU %.3f): ratio %.2f\n",
                  1e3 * J["primal"]["seconds_per_step"].get<double>(), 1e3 * J["floor_seconds"]["total"].get<double>(),
                  1e3 * J["floor_seconds"]["residual"].get<double>(), 1e3 * J["floor_seconds"]["iteration_matrix"].get<double>(),
                  1e3 * J["floor_seconds"]["klu_refactor_and_solve"].get<double>(), J["primal"]["step_over_floor"].get<double>());
      for (auto it = J["sensitivities"].begin(); it != J["sensitivities"].end(); ++it)
        std::printf("  %-26s %.2f x primal\n", it.key().c_str(), it.value()["over_primal"].get<double>());
      std::printf("  peak memory %.1f MB; results in %s\n", J["peak_rss_kb"].get<double>() / 1024, out.c_str());
      return 0;
    }
    if (*ver) {
      vo.out_dir = out;
      vo.idas = !no_idas;
      vo.mesh_study = !no_mesh;
      vo.command_line = joined_args(argc, argv);
      for (const auto& st : sets) vo.design_overrides.push_back(parse_set(st));
      const auto r = lsmbs::run_verify(case_file, vo);
      for (const auto& v : r.summary["verdicts"]) std::printf("  %s\n", v.get<std::string>().c_str());
      std::printf("lsmbs verify: %s — report in %s/report.md\n", r.pass ? "all checks pass" : "SOME CHECKS FAIL", out.c_str());
      return r.pass ? 0 : 1;
    }
    if (*sen)
      return sensitivity(case_file, out, sets, method, delta, absolute, matrix, full_residual, rtol, atol, threads, quiet,
                         joined_args(argc, argv), check ? &check_opt : nullptr);
    std::cout << app.help();
    return 2;
  } catch (const lsmbs::SetupError& e) {  // the library names the subject; the case file has the path
    std::fprintf(stderr, "lsmbs: error: %s\n", lsmbs::locate(case_file, e).what());
    return 2;
  } catch (const lsmbs::Error& e) {
    std::fprintf(stderr, "lsmbs: error: %s\n", e.what());
    return 2;
  } catch (const lsmbs::NumericalFailure& e) {
    std::fprintf(stderr, "lsmbs: numerical failure: %s\n", e.what());
    if (started) flag_failed_run(out, joined_args(argc, argv), case_file, std::string("numerical failure: ") + e.what());
    return 1;
  } catch (const std::filesystem::filesystem_error& e) {
    std::fprintf(stderr, "lsmbs: error: cannot write the output (-o %s): %s\n", out.c_str(), e.code().message().c_str());
    return 2;
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "lsmbs: out of memory (the model or a table or mesh of the case is too large for this machine)\n");
    if (started) flag_failed_run(out, joined_args(argc, argv), case_file, "out of memory");
    return 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "lsmbs: internal error: %s\n", e.what());
    if (started) flag_failed_run(out, joined_args(argc, argv), case_file, std::string("internal error: ") + e.what());
    return 1;
  }
}
