#pragma once
// run_verify — the `lsmbs verify` job (the verification layer): for one case, every
// sensitivity method against the exact direct method, their costs, the Δp study of the
// semi-analytical methods, the time-step study against IDAS, and a mesh study, written as
// OUT/report.md with CSVs and PNG plots, ending with pass/fail lines against stated thresholds.
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <utility>
#include <vector>

#include "lsmbs/core/progress.hpp"
#include "lsmbs/io/case.hpp"

namespace lsmbs {

struct VerifyOptions {
  std::string out_dir;
  bool idas = true;        ///< IDAS column and h study (too slow for long flexible runs)
  bool mesh_study = true;  ///< rectangle meshes only
  double fd_delta = 1e-5;  ///< fd-central step
  bool fd_absolute = false;
  double tol_fd = 1e-5;    ///< direct-analytic vs fd-central
  double tol_semi = 1e-6;  ///< semi-analytical-central vs direct-analytic
  /// mesh study: the grid convergence index of the finest mesh a response may have
  /// (responses/mesh_convergence.hpp)
  double tol_mesh = 1e-2;
  /// IDAS reference: rtol (atol = 1e-3 rtol in units of the model's length scale), and ten times
  /// both for the run that estimates the reference's own error
  double idas_rtol = 1e-10;
  std::string command_line;
  /// Design point as name=value overrides of the initial design (e.g. an interior point where
  /// a tiny start hole has negligible gradients).
  std::vector<std::pair<std::string, double>> design_overrides;
  std::vector<CaseOverride> case_overrides;  ///< values of the case document (--set /pointer=v)
  /// Called as each part of the report starts ("gradients by every method", …; empty: none).
  std::function<void(const std::string&)> on_stage;
  /// Called once, after the primal run, with what the verification will cost: the primal run's
  /// time and the estimate of the rest in simulations (empty: none).
  std::function<void(const std::string&)> on_plan;
  /// Progress of every run inside the parts (IDAS reference included; empty: none).
  ProgressCallback on_progress;
  /// Called once the case has loaded and passed its checks, before anything is written (the
  /// command line claims the output folder there).
  std::function<void(const Case&)> on_loaded;
  /// Empty string when valid, otherwise "field: what is expected".
  std::string validate() const;
};

struct VerifyResult {
  bool pass = true;
  nlohmann::json summary;
};

VerifyResult run_verify(const std::string& case_file, const VerifyOptions& o);

}  // namespace lsmbs
