// lsmbs simulate: generalized-α (Algorithm 1) or IDAS on the GGL form; history, VTU, summary.
#include "lsmbs/runs/simulate.hpp"

#include <unistd.h>

#include <algorithm>
#include <cstdio>

#include "app/commands/commands.hpp"
#include "app/commands/common.hpp"
#include "app/progress_line.hpp"
#include "lsmbs/core/error.hpp"
#include "lsmbs/core/interrupt.hpp"
#include "lsmbs/io/case.hpp"

namespace lsmbs::app {

int simulate_command(const CommonArgs& c, const SimulateArgs& a) {
  const std::string& case_file = c.case_file;
  const std::string& out = c.out;
  const bool quiet = c.quiet;
  check_idas_tolerances(a.rtol, a.atol);
  lsmbs::Case cs = load_case_with_sets(case_file, c.sets);  // validates everything before writing
  lsmbs::RunOptions ro;
  if (std::any_of(c.sets.begin(), c.sets.end(),
                  [](const std::string& s) { return s.empty() || s[0] != '/'; })) {
    if (!cs.design)
      throw lsmbs::Error(case_file, "/design", "--set needs a design section (design variables)");
    ro.design_point = design_point(cs, c.sets);
    cs.design->apply(ro.design_point, cs.model->params());
  }
  claim_output(c, *cs.model);
  ro.out_dir = out;
  ProgressLine line(!quiet && ::isatty(STDERR_FILENO));
  ro.progress = line.callback();
  ro.command_line = c.command_line;
  ro.idas = a.integrator == "idas";
  ro.idas_options.rtol = a.rtol;
  ro.idas_options.atol = a.atol > 0 ? a.atol : a.rtol;
  ro.idas_options.max_order = a.max_order;
  using ET = lsmbs::IdasOptions::ErrorTest;
  ro.idas_options.error_test = a.error_test == "positions" ? ET::kPositions
                               : a.error_test == "positions+velocities"
                                   ? ET::kPositionsAndVelocities
                                   : ET::kAuto;
  if (c.verbose)
    std::fprintf(stderr, "lsmbs: case '%s': %d DOFs, %d constraint equations, %d nonzeros\n",
                 cs.name.c_str(), cs.model->nq(), cs.model->nc(), cs.model->pattern().nnz());
  lsmbs::install_interrupt_handlers();
  const auto res = lsmbs::run_simulation(cs, ro);
  line.clear();
  const auto& s = res.integrator;
  if (res.interrupted) {
    std::fprintf(stderr, "lsmbs simulate: %s; what was computed is in %s (status partial)\n",
                 s.message.c_str(), out.c_str());
    return 130;
  }
  if (!quiet) {
    std::printf(
        "lsmbs simulate: %s — %ld steps, %ld Newton iterations, %ld factorizations, %.3f s\n",
        s.ok ? "complete" : "FAILED", s.steps, s.newton_iterations, s.factorizations,
        s.wall_seconds);
    if (s.halvings)
      std::printf("  step halvings: %ld (first at t = %g s)\n", s.halvings,
                  s.halving_times.front());
    if (c.verbose && !ro.idas)  // the factorization "auto" chose (summary.json: counts)
      std::printf("  linear solver: %s\n", s.linear_solver.c_str());
    if (res.summary.contains("warnings"))
      for (const auto& w : res.summary["warnings"])
        std::printf("  warning: %s\n", w.get<std::string>().c_str());
    if (s.ok)
      for (const auto& [name, v] : res.responses) std::printf("  %-28s %.10g\n", name.c_str(), v);
    std::printf("  results in %s\n", out.c_str());
  }
  if (!s.ok) {
    std::fprintf(
        stderr,
        "lsmbs: numerical failure: %s\n  (partial results in %s, flagged in summary.json)\n",
        s.message.c_str(), out.c_str());
    return 1;
  }
  return 0;
}

}  // namespace lsmbs::app
