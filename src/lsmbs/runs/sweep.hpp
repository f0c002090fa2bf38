#pragma once
// run_sweep — `lsmbs sweep` and `lsmbs.sweep(...)`: the case's responses (and, asked for, their
// gradients with respect to the design variables) at the points of a grid or a Latin hypercube
// over named quantities: design variables, model parameters ("spring.stiffness") or any value of
// the case document by JSON pointer ("/simulation/h"). One CSV row per point (sweep.csv: a
// header naming every column, pandas reads it as is); each point is written as it finishes, so
// that a killed sweep resumes (resume) without running the finished points again. The points run
// on the local cores, or over MPI ranks with dynamic load balancing (runs/mpi.hpp), and give the
// same numbers either way.
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "lsmbs/io/case.hpp"
#include "lsmbs/sensitivity/sensitivity.hpp"

namespace lsmbs {

struct SweepAxis {
  /// A design variable's name, a model parameter's name ("spring.stiffness") or a JSON pointer
  /// into the case ("/simulation/h").
  std::string name;
  double lower = 0, upper = 0;
  int points = 0;  ///< grid: values from lower to upper (1: lower alone)
};

struct SweepOptions {
  std::vector<SweepAxis> axes;
  /// 0: the full grid of the axes' points (the last axis fastest); N > 0: a Latin hypercube of N
  /// points over the axes' ranges (std::mt19937_64 seeded with `seed`; the axes' `points` unused)
  int samples = 0;
  unsigned long seed = 1;
  /// Also the gradients of the responses with respect to the design variables, by this method
  /// (its default: direct-analytic).
  bool gradients = false;
  SensitivityOptions sensitivity;
  int jobs = 2;         ///< points at once on this process (without MPI)
  bool resume = false;  ///< continue the sweep out_dir holds (the same plan)
  std::string out_dir;  ///< empty: nothing is written
  std::string command;
  std::function<void(const std::string&)> on_message;  ///< a line per finished point
  std::string validate() const;
};

struct SweepRun {
  std::vector<std::string> columns;         ///< sweep.csv's header
  std::vector<std::vector<double>> points;  ///< per point: the axes' values
  /// Per point, in the points' order: the responses, then (gradients) d(response)/d(variable),
  /// as sweep.csv's columns; NaN for what a failed point did not give (empty: not run here).
  std::vector<std::vector<double>> rows;
  std::vector<double> wall;                    ///< per point: its wall time [s] (NaN: not run here)
  std::vector<std::string> status;             ///< per point: complete, failed, not run
  std::vector<std::string> message;            ///< per point: why it failed
  int completed = 0, failed = 0, skipped = 0;  ///< skipped: finished by an earlier run
  bool interrupted = false;
  nlohmann::json summary;
  /// 0 every point complete; 1 some failed; 130 interrupted (under MPI: rank 0's, on every rank).
  int exit_code() const;
  int ranks_exit = -1;  ///< under MPI: rank 0's exit code, handed to every rank
};

/// Throws Error for an axis that names nothing, bounds that do not fit, or a resume of another
/// plan.
SweepRun run_sweep(const Case& cs, const SweepOptions& o);

}  // namespace lsmbs
