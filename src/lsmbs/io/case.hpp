#pragma once
// Case — everything a JSON case file defines: the model, the initial state, the integrator
// options, the measures recorded and the responses reported. The format is documented in
// docs/case-format.md. Loading validates every field and throws lsmbs::Error (file, JSON
// path, what was expected) before anything is written.
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "lsmbs/geometry/design.hpp"
#include "lsmbs/integrators/generalized_alpha.hpp"
#include "lsmbs/mbs/model.hpp"
#include "lsmbs/responses/measure.hpp"

namespace lsmbs {

struct OutputSpec {
  int csv_stride = 1;  ///< every n-th grid step in history.csv
  int vtu_stride = 0;  ///< every n-th grid step as VTU (0: none)
};

struct Case {
  std::string file;     ///< path as given
  std::string name;
  std::string sha256;   ///< of the case file's bytes
  nlohmann::json raw;
  std::unique_ptr<Model> model;
  State initial;
  GeneralizedAlphaOptions simulation;
  /// simulation.check_constraints: refuse redundant or conflicting constraints at load time
  /// (false only for models that are evaluated, never integrated, e.g. derivative tests).
  bool check_constraints = true;
  OutputSpec output;
  std::vector<std::unique_ptr<Measure>> measures;
  std::vector<ResponseSpec> responses;
  std::map<std::string, std::shared_ptr<const TimeLaw>> drivers;  ///< by driver name
  std::map<std::string, std::vector<int>> joint_rows;              ///< constraint rows by joint name
  nlohmann::json optimization;     ///< the "optimization" section (parsed by parse_optimization)
  std::unique_ptr<Design> design;  ///< null when the case has no "design" section; when present,
                                   ///< the model parameters hold the initial design

  /// Column names of the measure history (in the order measures are evaluated).
  std::vector<std::string> measure_columns() const;
};

/// Loads and validates a case file (paths inside are relative to its folder).
Case load_case(const std::string& path);
/// Same from an already parsed document (tests); `base_dir` resolves relative file names.
Case load_case_json(const nlohmann::json& j, const std::string& file_label, const std::string& base_dir);

}  // namespace lsmbs
