#pragma once
// run_bench — the `lsmbs bench` job: whole-run figures of a case measured in one process:
//  * the floor of a generalized-α step: one residual assembly + one iteration-matrix assembly +
//    one KLU refactorization and solve (averaged over repetitions at the initial state);
//  * the average step of the primal run and its ratio to the floor;
//  * time(primal + sensitivities) / time(primal) for the listed methods (cases with a design);
//  * peak resident memory.
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "lsmbs/io/case.hpp"

namespace lsmbs {

struct BenchOptions {
  std::string out_dir;
  std::vector<std::string> methods = {"direct-analytic", "semi-analytical-central"};
  /// Back-solve matrices timed for the direct methods besides the default (--matrix values)
  std::vector<std::string> matrices = {"last"};
  int repetitions = 20;
  int threads = 2;  ///< SensitivityOptions::threads of the timed sensitivity runs
  /// Empty string when valid, otherwise "field: what is expected".
  std::string validate() const;
  std::string command_line;
  /// Changes to the case document before it loads (--set: JSON pointers, design variables'
  /// initial values).
  std::vector<CaseOverride> overrides;
  /// Called once the case has loaded and passed its checks, before anything is written.
  std::function<void(const Case&)> on_loaded;
};

nlohmann::json run_bench(const std::string& case_file, const BenchOptions& o);

}  // namespace lsmbs
