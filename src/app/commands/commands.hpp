#pragma once
// The lsmbs commands, one file each. main.cpp parses the command line into these argument
// structs and calls one command; a command loads the case, runs the library, writes the output
// folder, prints, and returns the exit code: 0 success, 1 numerical failure (the results are
// flagged partial), 130 interrupted. Invalid input throws (lsmbs::Error, lsmbs::SetupError:
// exit 2, nothing written).
#include <string>
#include <vector>

#include "lsmbs/io/output_folder.hpp"
#include "lsmbs/runs/bench.hpp"
#include "lsmbs/runs/verify.hpp"
#include "lsmbs/sensitivity/gradient_check.hpp"

namespace lsmbs::app {

/// What every command gets.
struct CommonArgs {
  std::string case_file;
  std::string out = "out";        ///< output folder (-o)
  std::string command_line;       ///< recorded in summary.json
  std::vector<std::string> sets;  ///< --set name=value design-variable overrides
  bool quiet = false, verbose = false;
  bool overwrite = false;  ///< --overwrite: replace the earlier run the folder holds
  bool resume = false;     ///< optimize --resume: continue it
  /// Where claim_output (common.hpp) keeps the earlier run it sets aside, for main to restore on
  /// bad input; null: nothing is claimed (a child of a multi-start claims its own folder)
  ReplacedRun* replaced = nullptr;
};

struct SimulateArgs {
  std::string integrator = "generalized-alpha";  ///< or "idas"
  double rtol = 1e-9, atol = 0;                  ///< IDAS tolerances (atol 0: rtol)
  int max_order = 0;                             ///< IDAS maximum BDF order (0: automatic)
  std::string error_test = "auto";               ///< IDAS error test
};

struct StaticArgs {
  double t = 0;       ///< time at which drivers and loads are evaluated
  int max_iter = 50;  ///< Newton iterations
};

struct GeometryArgs {
  int width = 1600;  ///< PNG width [pixels]
};

struct SensitivityArgs {
  std::string method = "direct-analytic";
  double delta = 1e-6;
  bool absolute = false;
  std::string matrix = "converged";
  bool full_residual = false;
  double rtol = 1e-9, atol = 0;
  int threads = 2;
  double adjoint_memory_mb = 0;  ///< --adjoint-memory (0: no bound)
  bool check = false;            ///< gradient check along a random direction
  GradientCheckOptions check_options;
};

struct OptimizeArgs {
  bool resume = false;
  bool overwrite = false;
  int starts = 0;          ///< >= 1: multi-start from feasible random designs (one child each)
  unsigned long seed = 1;  ///< multi-start: seed of the random initial designs
  int jobs = 2;            ///< multi-start: children run at once
  std::string optimizer;   ///< empty: the case's
  bool check = true;       ///< gradient check at the initial design
  GradientCheckOptions check_options;
};

struct SweepArgs {
  std::vector<std::string> axes;  ///< --axis name=lower:upper[:points]
  int lhs = 0;                    ///< --lhs N: a Latin hypercube of N points (0: the grid)
  unsigned long seed = 1;
  bool gradients = false;
  std::string method = "direct-analytic";
  int jobs = 2;
};

struct VerifyArgs {
  VerifyOptions options;
};

struct BenchArgs {
  BenchOptions options;
  std::vector<std::string> methods;  ///< empty: the default methods; {"none"}: none
};

int simulate_command(const CommonArgs& c, const SimulateArgs& a);
int geometry_command(const CommonArgs& c, const GeometryArgs& a);
int static_command(const CommonArgs& c, const StaticArgs& a);
int sensitivity_command(const CommonArgs& c, const SensitivityArgs& a);
int optimize_command(const CommonArgs& c, const OptimizeArgs& a);
/// Exits 2 (lsmbs::Error naming the option, --idas-rtol …) for invalid verify options.
void check_verify_options(const VerifyOptions& vo);
int verify_command(const CommonArgs& c, VerifyArgs a);
int bench_command(const CommonArgs& c, BenchArgs a);
int sweep_command(const CommonArgs& c, const SweepArgs& a);

}  // namespace lsmbs::app
