// lsmbs sensitivity: the command line of run_sensitivity (runs/sensitivity.hpp): responses and
// their design gradients by one method (§4.3), other methods compared with it, an optional
// gradient check; gradients.csv and summary.json.
#include "lsmbs/runs/sensitivity.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "app/commands/commands.hpp"
#include "app/commands/common.hpp"
#include "app/progress_line.hpp"
#include "lsmbs/core/error.hpp"
#include "lsmbs/core/interrupt.hpp"
#include "lsmbs/core/text.hpp"
#include "lsmbs/io/case.hpp"
#include "lsmbs/runs/mpi.hpp"

namespace lsmbs::app {
namespace {

// --method a,b,…: the methods by name, every one known and given once; the first one's results
// are the gradients, the others are compared with it.
std::vector<lsmbs::SensitivityOptions::Method> parse_methods(const std::string& list) {
  std::vector<std::string> methods;
  for (size_t b = 0, e; b <= list.size(); b = e + 1) {
    e = std::min(list.find(',', b), list.size());
    methods.push_back(list.substr(b, e - b));
  }
  std::vector<lsmbs::SensitivityOptions::Method> parsed;
  for (const auto& m : methods) {
    lsmbs::SensitivityOptions::Method method;
    if (!lsmbs::SensitivityOptions::parse(m, method)) {
      std::string all;
      for (const auto& n : lsmbs::SensitivityOptions::names()) all += (all.empty() ? "" : ", ") + n;
      throw lsmbs::Error("--method " + list + ": '" + m + "' is not a method; expected one of " +
                         all + " (or several, separated by commas)");
    }
    if (std::count(methods.begin(), methods.end(), m) > 1)
      throw lsmbs::Error("--method " + list + ": '" + m + "' is given twice");
    parsed.push_back(method);
  }
  return parsed;
}

// The options of the command line, checked before anything runs; a message names the flag.
lsmbs::SensitivityRunOptions run_options(const CommonArgs& c, const SensitivityArgs& a) {
  const auto methods = parse_methods(a.method);
  lsmbs::SensitivityRunOptions o;
  lsmbs::SensitivityOptions& so = o.options;
  so.method = methods.front();
  o.compare.assign(methods.begin() + 1, methods.end());
  so.threads = a.threads;
  so.adjoint_memory_mb = a.adjoint_memory_mb;
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
  if (auto msg = so.validate(); !msg.empty())
    throw lsmbs::Error(lsmbs::rename_fields(
        msg,
        {{"delta", "--delta"}, {"threads", "--threads"}, {"adjoint_memory", "--adjoint-memory"}}));
  if (a.check) {
    check_gradient_check_options(a.check_options);
    o.check = a.check_options;
  }
  o.out_dir = c.out;
  o.command = c.command_line;
  return o;
}

void print_results(const lsmbs::SensitivityRun& run, const lsmbs::Design& d,
                   const lsmbs::SensitivityRunOptions& o) {
  const lsmbs::SensitivityResult& res = run.result;
  std::printf(
      "lsmbs sensitivity (%s): %s — %ld simulations, %ld steps, %ld factorizations, %ld "
      "back-solves (%ld rhs), %.3f s\n",
      lsmbs::SensitivityOptions::name(o.options.method),
      run.stopped ? "INTERRUPTED"
      : res.ok    ? "complete"
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
  if (run.checked) print_gradient_check(*run.checked, *o.check);
  std::printf("  results in %s\n", o.out_dir.c_str());
}

}  // namespace

int sensitivity_command(const CommonArgs& c, const SensitivityArgs& a) {
  lsmbs::SensitivityRunOptions o = run_options(c, a);
  lsmbs::Case cs = load_case_with_sets(c.case_file, c.sets);
  if (!cs.design)
    throw lsmbs::Error(c.case_file, "/design",
                       "sensitivities need a design section (design variables)");
  if (cs.responses.empty())
    throw lsmbs::Error(c.case_file, "/output/responses",
                       "sensitivities need at least one response");
  const lsmbs::Vec p = design_point(cs, c.sets);
  claim_output(c, *cs.model);
  ProgressLine line(!c.quiet && ::isatty(STDERR_FILENO));
  o.options.progress = line.callback();
  lsmbs::install_interrupt_handlers();  // an interrupt stops the runs at their next step
  const lsmbs::SensitivityRun run = [&] {
    try {
      return lsmbs::run_sensitivity(cs, p, o);
    } catch (const lsmbs::SetupError& e) {
      // the adjoint's memory bound is this command's option, not a value of the case file
      if (e.subject() != "optimization.sensitivity.adjoint_memory_mb") throw;
      char v[32];
      std::snprintf(v, sizeof v, "%g", a.adjoint_memory_mb);
      throw lsmbs::Error(std::string("--adjoint-memory ") + v + ": " + e.reason());
    }
  }();
  line.clear();
  if (lsmbs::mpi::world().rank > 0) return run.exit_code(o.check);  // rank 0 says it
  for (const auto& w : run.result.warnings)
    std::fprintf(stderr, "lsmbs sensitivity: warning: %s\n", w.c_str());
  if (!c.quiet) print_results(run, *cs.design, o);
  if (run.stopped) {
    std::fprintf(stderr, "lsmbs sensitivity: %s; partial results in %s (status interrupted)\n",
                 run.summary["failure"].get<std::string>().c_str(), c.out.c_str());
    return 130;
  }
  if (const auto why = run.failure(o.check); !why.empty())
    std::fprintf(stderr, "lsmbs: %s\n", why.c_str());
  return run.exit_code(o.check);
}

}  // namespace lsmbs::app
