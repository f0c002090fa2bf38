#include "lsmbs/io/output_folder.hpp"

#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <vector>

#include "lsmbs/core/error.hpp"

namespace lsmbs {

// The output folder (-o) must be a folder that exists or can be created, and be writable: checked
// before anything runs, without creating it (nothing is written for invalid input).
void check_output_folder(const std::string& out, const OutputFolderNames& names) {
  const std::string& o = names.folder;
  namespace fs = std::filesystem;
  if (out.empty()) throw Error(o + " \"\": expected an output folder name");
  std::error_code ec;
  fs::path p = fs::absolute(out, ec);
  if (ec) throw Error(o + " " + out + ": not a usable path (" + ec.message() + ")");
  if (fs::exists(p, ec) && !fs::is_directory(p, ec))
    throw Error(o + " " + out + ": exists and is not a folder");
  // the nearest existing ancestor must be a writable folder
  fs::path q = p;
  while (!fs::exists(q, ec) && q.has_parent_path() && q.parent_path() != q) q = q.parent_path();
  if (!fs::is_directory(q, ec)) throw Error(o + " " + out + ": " + q.string() + " is not a folder");
  if (::access(q.c_str(), W_OK) != 0 || q.string().rfind("/proc", 0) == 0 ||
      q.string().rfind("/sys", 0) == 0)
    throw Error(o + " " + out + ": cannot create or write in " + q.string());
}

// An output folder that holds an earlier lsmbs run is refused (its files would be mixed with this
// run's) unless --overwrite, which removes the earlier run's files first (and only those);
// optimize --resume continues the run the folder holds.
void claim_output_folder(const std::string& out, bool overwrite, bool resume,
                         const OutputFolderNames& names) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (resume || !fs::is_directory(out, ec)) return;
  static const std::set<std::string> kFiles = {"summary.json",    "history.csv", "gradients.csv",
                                               "checkpoint.json", "report.md",   "bench.json",
                                               "convergence.png"};
  static const std::set<std::string> kFolders = {"vtu", "final_design"};
  static const std::set<std::string> kExtensions = {".pvd", ".png", ".csv", ".gp", ".vtu", ".vtm"};
  // what the earlier run's summary.json lists is its own too (a static run's <body>.vtu and
  // model.vtm, a multi-start's start_k/ folders): the first component of each listed path
  std::set<std::string> listed;
  try {
    const auto S = nlohmann::json::parse(std::ifstream(fs::path(out) / "summary.json"));
    if (S.is_object() && S.contains("files") && S["files"].is_array())
      for (const auto& f : S["files"])
        if (f.is_string()) {
          const fs::path rel = fs::path(f.get<std::string>()).lexically_normal();
          if (!rel.empty() && rel.is_relative() && *rel.begin() != "..")
            listed.insert(rel.begin()->string());
        }
  } catch (const std::exception&) {  // no summary, or not ours: the names above decide
  }
  std::vector<fs::path> ours;
  for (const auto& e : fs::directory_iterator(out, ec)) {
    const std::string name = e.path().filename().string();
    if (kFiles.count(name) || (e.is_directory() && kFolders.count(name)) ||
        (e.is_regular_file() && kExtensions.count(e.path().extension().string())) ||
        listed.count(name))
      ours.push_back(e.path());
  }
  if (ours.empty()) return;
  if (!overwrite)
    throw Error(
        names.folder + " " + out + ": the folder holds an earlier run (" +
        ours.front().filename().string() +
        (ours.size() > 1 ? ", … " + std::to_string(ours.size()) + " entries" : std::string()) +
        "); give another folder, or " + names.overwrite + " to replace that run");
  // summary.json first: a run stopped while it removes the rest never leaves the earlier run's
  // summary next to a half-removed folder
  std::stable_partition(ours.begin(), ours.end(),
                        [](const fs::path& p) { return p.filename() == "summary.json"; });
  for (const auto& p : ours) fs::remove_all(p);
}

}  // namespace lsmbs
