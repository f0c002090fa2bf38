#pragma once
// run_simulation — the `lsmbs simulate` job as a library call: integrates a Case with the
// generalized-α scheme, records every measure at every grid step, aggregates the responses,
// and (when an output folder is given) writes history.csv, VTU/PVD series and summary.json.
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "lsmbs/integrators/idas_ggl.hpp"
#include "lsmbs/io/case.hpp"
#include "lsmbs/sensitivity/sensitivity.hpp"

namespace lsmbs {

struct SimulationResult {
  IntegratorSummary integrator;
  IdasStats idas;            ///< when run with IDAS
  IdasOptions idas_options;  ///< the options IDAS ran with (output grid and final time: the case's)
  /// With IDAS: the time-integral responses from IDAS quadratures (continuous-time values).
  std::vector<QuadratureResponse> quadratures;
  std::vector<double> times;                 ///< grid times, starting at t0
  std::vector<std::vector<double>> history;  ///< per grid time: measure columns
  std::vector<std::string> columns;
  /// Each response as one number (a per-step response: its largest value); NaN when the run did
  /// not reach t_end.
  std::map<std::string, double> responses;
  /// Per-step responses: every value of the window, and the step times (NaN: not reached).
  std::map<std::string, std::vector<double>> per_step, per_step_times;
  std::map<std::string, int> response_counts;  ///< steps in each response's window
  State final_state;
  bool interrupted = false;  ///< stopped by SIGINT/SIGTERM (partial)
  nlohmann::json summary;    ///< what summary.json contains
  /// A case with service conditions: each condition's run (its history, responses, summary), in
  /// the case's order; `responses` then holds every condition's as "<condition>.<response>" (and
  /// the combined ones), and the output folder a folder per condition under conditions/.
  std::vector<std::pair<std::string, SimulationResult>> conditions;
  RunStatus status() const;
  std::string report() const;  ///< the integrator's report, then the responses
  /// Column of the history by name (throws if unknown).
  std::vector<double> column(const std::string& name) const;
};

struct RunOptions {
  std::string out_dir;        ///< empty: nothing written
  ProgressCallback progress;  ///< called at every step (empty: none)
  std::string command_line;   ///< recorded in summary.json
  bool idas = false;          ///< integrate with IDAS (GGL) instead of generalized-α
  IdasOptions idas_options = IdasOptions::reference();
  /// Design point the case's parameters were set to (recorded in summary.json; empty: the
  /// case's initial design, if it has one).
  Vec design_point;
  /// Empty string when valid, otherwise "field: what is expected".
  std::string validate() const;
};

/// The IDAS tolerances a user gives (the command line's --rtol/--atol, Python's rtol/atol; atol 0
/// stands for rtol): "" when valid, else "rtol: what is expected" or "atol: what is expected".
std::string idas_tolerance_error(double rtol, double atol);

/// A simulation of the case (of each of its service conditions, at once on threads: their results
/// do not depend on it).
SimulationResult run_simulation(const Case& cs, const RunOptions& ro = {});

}  // namespace lsmbs
