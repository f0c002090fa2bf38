#include "app/commands/common.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <set>

#include "lsmbs/core/error.hpp"
#include "lsmbs/core/json_file.hpp"
#include "lsmbs/io/output.hpp"

namespace lsmbs::app {

// "name=value" overrides of design variables.
std::pair<std::string, double> parse_set(const std::string& s) {
  const auto eq = s.find('=');
  if (eq == std::string::npos) throw lsmbs::Error("--set " + s + ": expected name=value");
  try {
    size_t used = 0;
    const double v = std::stod(s.substr(eq + 1), &used);
    if (used != s.size() - eq - 1) throw std::invalid_argument("trailing characters");
    return {s.substr(0, eq), v};
  } catch (const std::exception&) {
    throw lsmbs::Error("--set " + s + ": expected a number after '='");
  }
}

// A run that ends with an exception once it has started (a numerical failure raised deep inside,
// memory exhausted, an internal error) leaves a summary.json with status partial and the reason,
// replacing any earlier summary: exit 1 always comes with results flagged as partial.
void flag_failed_run(const std::string& out, const std::string& cmdline,
                     const std::string& case_file, const std::string& what) {
  try {
    std::filesystem::create_directories(out);
    nlohmann::json S = lsmbs::provenance(cmdline, case_file, "");
    S["status"] = "partial";
    S["failure"] = what;
    lsmbs::write_json_atomic(out + "/summary.json", S);
  } catch (const std::exception&) {  // the folder cannot be written: the message on stderr remains
  }
}

// IDAS tolerances from the command line: checked before anything runs
void check_idas_tolerances(double rtol, double atol) {
  if (!(rtol > 0) || !std::isfinite(rtol) || rtol >= 1)
    throw lsmbs::Error("--rtol " + std::to_string(rtol) +
                       ": expected a relative tolerance in (0, 1)");
  if (!(atol >= 0) || !std::isfinite(atol))
    throw lsmbs::Error("--atol " + std::to_string(atol) +
                       ": expected a non-negative absolute tolerance (0: rtol)");
}

lsmbs::Vec design_point(const lsmbs::Case& cs, const std::vector<std::string>& sets) {
  lsmbs::Vec p = cs.design->initial();
  for (const auto& s : sets) {
    const auto [name, value] = parse_set(s);
    const int k = cs.design->variable_index(name);
    if (k < 0) throw lsmbs::Error("--set " + s + ": unknown design variable '" + name + "'");
    const auto& v = cs.design->variables[k];
    if (!(value >= v.lower && value <= v.upper))
      throw lsmbs::Error("--set " + s + ": outside the bounds [" + std::to_string(v.lower) + ", " +
                         std::to_string(v.upper) + "] of design variable '" + name +
                         "' (the case validates its features over these bounds; widen them in the "
                         "case to go further)");
    p[k] = value;
  }
  return p;
}

void print_gradient_check(const lsmbs::GradientCheckResult& c,
                          const lsmbs::GradientCheckOptions& o) {
  std::printf(
      "  gradient check (central differences along a random direction, 2 simulations): %s\n",
      c.verdict(o).c_str());
  if (!c.ok) {
    std::printf("    %s\n", c.message.c_str());
    return;
  }
  for (const auto& e : c.entries)
    std::printf("    %-24s fd %+.6e  method %+.6e  relative disagreement %.2e\n",
                e.response.c_str(), e.finite_difference, e.method, e.relative_error);
}

}  // namespace lsmbs::app
