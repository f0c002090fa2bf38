// lsmbs bench: the step cost of a case against its floor (residual, iteration matrix, KLU), the
// overheads of the sensitivity methods, and the peak memory (bench.json).
#include <cstdio>

#include "app/commands/commands.hpp"
#include "app/commands/common.hpp"
#include "lsmbs/core/error.hpp"
#include "lsmbs/sensitivity/sensitivity.hpp"

namespace lsmbs::app {

int bench_command(const CommonArgs& c, BenchArgs a) {
  BenchOptions& bo = a.options;
  bo.out_dir = c.out;
  bo.command_line = c.command_line;
  if (!a.methods.empty()) bo.methods = a.methods;
  if (bo.methods.size() == 1 && bo.methods[0] == "none") bo.methods.clear();
  if (bo.matrices.size() == 1 && bo.matrices[0] == "none") bo.matrices.clear();
  for (const auto& m : bo.methods) {
    SensitivityOptions::Method mm;
    if (!SensitivityOptions::parse(m, mm))
      throw Error("--methods " + m + ": unknown sensitivity method");
  }
  for (const auto& m : bo.matrices) {
    SensitivityOptions::Matrix mm;
    if (!SensitivityOptions::parse_matrix(m, mm))
      throw Error("--matrices " + m + ": expected last, converged or refined");
  }
  bo.overrides = case_overrides(c.case_file, c.sets, /*design_as_initial=*/true);
  bo.on_loaded = [&](const Case& cs) { claim_output(c, *cs.model); };
  const auto J = run_bench(c.case_file, bo);
  std::printf(
      "lsmbs bench: step %.3f ms, floor %.3f ms (residual %.3f + matrix %.3f + %s %.3f): "
      "ratio %.2f\n",
      1e3 * J["primal"]["seconds_per_step"].get<double>(),
      1e3 * J["floor_seconds"]["total"].get<double>(),
      1e3 * J["floor_seconds"]["residual"].get<double>(),
      1e3 * J["floor_seconds"]["iteration_matrix"].get<double>(),
      J["model"]["linear_solver"].get<std::string>() == "umfpack" ? "UMFPACK"
      : J["model"]["linear_solver"].get<std::string>() == "amg"   ? "AMG-GMRES"
                                                                  : "KLU",
      1e3 * J["floor_seconds"]["factor_and_solve"].get<double>(),
      J["primal"]["step_over_floor"].get<double>());
  for (auto it = J["sensitivities"].begin(); it != J["sensitivities"].end(); ++it)
    std::printf("  %-26s %.2f x primal\n", it.key().c_str(),
                it.value()["over_primal"].get<double>());
  std::printf("  peak memory %.1f MB; results in %s\n", J["peak_rss_kb"].get<double>() / 1024,
              c.out.c_str());
  return 0;
}

}  // namespace lsmbs::app
