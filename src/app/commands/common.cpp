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

// The output folder (-o) must be a folder that exists or can be created, and be writable: checked
// before anything runs, without creating it (nothing is written for invalid input).
void check_output_folder(const std::string& out) {
  namespace fs = std::filesystem;
  if (out.empty()) throw lsmbs::Error("-o \"\": expected an output folder name");
  std::error_code ec;
  fs::path p = fs::absolute(out, ec);
  if (ec) throw lsmbs::Error("-o " + out + ": not a usable path (" + ec.message() + ")");
  if (fs::exists(p, ec) && !fs::is_directory(p, ec))
    throw lsmbs::Error("-o " + out + ": exists and is not a folder");
  // the nearest existing ancestor must be a writable folder
  fs::path q = p;
  while (!fs::exists(q, ec) && q.has_parent_path() && q.parent_path() != q) q = q.parent_path();
  if (!fs::is_directory(q, ec))
    throw lsmbs::Error("-o " + out + ": " + q.string() + " is not a folder");
  if (::access(q.c_str(), W_OK) != 0 || q.string().rfind("/proc", 0) == 0 ||
      q.string().rfind("/sys", 0) == 0)
    throw lsmbs::Error("-o " + out + ": cannot create or write in " + q.string());
}

// An output folder that holds an earlier lsmbs run is refused (its files would be mixed with this
// run's) unless --overwrite, which removes the earlier run's files first (and only those);
// optimize --resume continues the run the folder holds.
void claim_output_folder(const std::string& out, bool overwrite, bool resume) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (resume || !fs::is_directory(out, ec)) return;
  static const std::set<std::string> kFiles = {"summary.json",    "history.csv", "gradients.csv",
                                               "checkpoint.json", "report.md",   "bench.json",
                                               "convergence.png"};
  static const std::set<std::string> kFolders = {"vtu", "final_design"};
  static const std::set<std::string> kExtensions = {".pvd", ".png", ".csv", ".gp"};
  std::vector<fs::path> ours;
  for (const auto& e : fs::directory_iterator(out, ec)) {
    const std::string name = e.path().filename().string();
    if (kFiles.count(name) || (e.is_directory() && kFolders.count(name)) ||
        (e.is_regular_file() && kExtensions.count(e.path().extension().string())))
      ours.push_back(e.path());
  }
  if (ours.empty()) return;
  if (!overwrite)
    throw lsmbs::Error(
        "-o " + out + ": the folder holds an earlier run (" + ours.front().filename().string() +
        (ours.size() > 1 ? ", … " + std::to_string(ours.size()) + " entries" : std::string()) +
        "); give another folder, or --overwrite to replace that run");
  // summary.json first: a run stopped while it removes the rest never leaves the earlier run's
  // summary next to a half-removed folder
  std::stable_partition(ours.begin(), ours.end(),
                        [](const fs::path& p) { return p.filename() == "summary.json"; });
  for (const auto& p : ours) fs::remove_all(p);
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
