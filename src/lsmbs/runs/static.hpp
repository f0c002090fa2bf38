#pragma once
// A static equilibrium of a case (`lsmbs static`): the model without inertia at one time t
// (drivers and loads evaluated at t), solved by Newton from the case's initial configuration
// (integrators/static_solver.hpp). The outputs are a simulation's with one state: the measures
// at equilibrium (history.csv, one row), the responses aggregated over that one row (a window
// that does not contain t gives NaN), the flexible bodies as VTU, and summary.json.
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "lsmbs/integrators/static_solver.hpp"
#include "lsmbs/io/case.hpp"

namespace lsmbs {

struct StaticRunOptions {
  std::string out_dir;       ///< empty: nothing written
  std::string command_line;  ///< recorded in summary.json
  double t = 0;              ///< time at which drivers and loads are evaluated
  int max_iter = 50;         ///< Newton iterations
  Vec design_point;          ///< recorded (the case's parameters are set by the caller)
  std::string validate() const;
};

struct StaticRunResult {
  StaticResult solver;
  State state;
  std::vector<std::string> columns;
  std::vector<double> measures;  ///< one value per column, at equilibrium
  std::map<std::string, double> responses;
  nlohmann::json summary;
  RunStatus status() const { return solver.status(); }
  std::string report() const;
};

StaticRunResult run_static(const Case& cs, const StaticRunOptions& o = {});

}  // namespace lsmbs
