#pragma once
// Case — everything a JSON case file defines: the model, the initial state, the integrator
// options, the measures recorded and the responses reported. The format is documented in
// docs/case-format.md. Loading validates every field and throws lsmbs::Error (file, JSON
// path, what was expected) before anything is written.
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "lsmbs/core/error.hpp"
#include "lsmbs/mbs/time_law.hpp"
#include "lsmbs/sensitivity/study.hpp"

namespace lsmbs {

struct OutputSpec {
  int csv_stride = 1;  ///< every n-th grid step in history.csv
  int vtu_stride = 0;  ///< every n-th grid step as VTU (0: none)
};

/// A case file: the Study it defines (model, initial state, options, measures, responses, design)
/// and what only the file has (its name, hash and document, output strides, the optimization
/// section, names of drivers and joints).
struct Case : Study {
  std::string file;  ///< path as given
  std::string name;
  std::string sha256;  ///< of the case file's bytes
  nlohmann::json raw;
  /// simulation.check_constraints: refuse redundant or conflicting constraints at load time
  /// (false only for models that are evaluated, never integrated, e.g. derivative tests).
  bool check_constraints = true;
  OutputSpec output;
  std::map<std::string, std::shared_ptr<const TimeLaw>> drivers;  ///< by driver name
  std::map<std::string, std::vector<int>> joint_rows;             ///< constraint rows by joint name
  nlohmann::json optimization;  ///< the "optimization" section (parsed by parse_optimization)
  /// Values changed before loading (--set /pointer=value): JSON pointer -> value; an empty object
  /// when none. `sha256` stays the file's; summaries record both.
  nlohmann::json overrides = nlohmann::json::object();
};

/// A change of one value of the case document before it is loaded: `lsmbs … --set
/// /simulation/h=1e-3`, `--set /bodies/1/material/E=70e9`. The pointer's parent must exist (an
/// object, or an array holding that index); the loader then checks the changed document as any
/// case file, and an error at the changed value says it came from the override.
struct CaseOverride {
  std::string pointer;   ///< JSON pointer (RFC 6901)
  nlohmann::json value;  ///< any JSON value
  std::string origin;    ///< how it was given, for messages ("--set /simulation/h=1e-3")
};

/// The error of the library (by subject) located in the case file: "design" → /design,
/// "responses" → /output/responses, "optimization.objective" → /optimization/objective, … .
Error locate(const std::string& case_file, const SetupError& e);

/// Loads and validates a case file (paths inside are relative to its folder).
Case load_case(const std::string& path);
/// Same, with values of the document changed first (in order).
Case load_case(const std::string& path, const std::vector<CaseOverride>& overrides);
/// Same from an already parsed document (tests); `base_dir` resolves relative file names.
Case load_case_json(const nlohmann::json& j, const std::string& file_label,
                    const std::string& base_dir);

}  // namespace lsmbs
