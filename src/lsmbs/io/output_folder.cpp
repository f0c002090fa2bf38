#include "lsmbs/io/output_folder.hpp"

#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <set>
#include <utility>
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

namespace {

// The entries of `out` that an lsmbs run writes: the known names, and the first component of each
// path the folder's summary.json lists (a static run's <body>.vtu and model.vtm, a multi-start's
// start_k/ folders).
std::vector<std::filesystem::path> run_entries(const std::string& out) {
  namespace fs = std::filesystem;
  static const std::set<std::string> kFiles = {"summary.json",    "history.csv", "gradients.csv",
                                               "checkpoint.json", "report.md",   "bench.json",
                                               "convergence.png"};
  static const std::set<std::string> kFolders = {"vtu", "final_design"};
  static const std::set<std::string> kExtensions = {".pvd", ".png", ".csv", ".gp", ".vtu", ".vtm"};
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
  listed.erase(ReplacedRun::stash_name());
  std::vector<fs::path> ours;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(out, ec)) {
    const std::string name = e.path().filename().string();
    if (kFiles.count(name) || (e.is_directory() && kFolders.count(name)) ||
        (e.is_regular_file() && kExtensions.count(e.path().extension().string())) ||
        listed.count(name))
      ours.push_back(e.path());
  }
  // summary.json first: a run stopped while the rest moves never leaves the earlier run's summary
  // next to a half-moved folder
  std::stable_partition(ours.begin(), ours.end(),
                        [](const fs::path& p) { return p.filename() == "summary.json"; });
  return ours;
}

}  // namespace

const char* ReplacedRun::stash_name() { return ".lsmbs-replaced-run"; }

ReplacedRun::ReplacedRun(std::string out, std::vector<std::string> names)
    : out_(std::move(out)), names_(std::move(names)) {}

ReplacedRun::ReplacedRun(ReplacedRun&& o) noexcept
    : out_(std::exchange(o.out_, {})), names_(std::move(o.names_)) {}

ReplacedRun& ReplacedRun::operator=(ReplacedRun&& o) noexcept {
  if (this != &o) {
    this->~ReplacedRun();
    out_ = std::exchange(o.out_, {});
    names_ = std::move(o.names_);
  }
  return *this;
}

ReplacedRun::~ReplacedRun() {
  if (out_.empty()) return;
  std::error_code ec;
  std::filesystem::remove_all(std::filesystem::path(out_) / stash_name(), ec);
}

void ReplacedRun::restore() {
  if (out_.empty()) return;
  namespace fs = std::filesystem;
  const fs::path stash = fs::path(out_) / stash_name();
  std::error_code ec;
  // this run's own files: a summary.json it wrote lists them, the known names cover the rest
  for (const auto& p : run_entries(out_)) fs::remove_all(p, ec);
  // the summary last, so that an interrupted restore never shows the earlier summary beside a
  // half-restored folder
  std::vector<std::string> names = names_;
  std::stable_partition(names.begin(), names.end(),
                        [](const std::string& n) { return n != "summary.json"; });
  for (const auto& n : names) fs::rename(stash / n, fs::path(out_) / n, ec);
  fs::remove_all(stash, ec);
  out_.clear();
}

// An output folder that holds an earlier lsmbs run is refused (its files would be mixed with this
// run's) unless --overwrite, which sets the earlier run's files (and only those) aside: restored
// if this run stops on bad input, deleted otherwise. optimize --resume continues the run the
// folder holds.
ReplacedRun claim_output_folder(const std::string& out, bool overwrite, bool resume,
                                const OutputFolderNames& names) {
  namespace fs = std::filesystem;
  std::error_code ec;
  if (resume || !fs::is_directory(out, ec)) return {};
  const fs::path stash = fs::path(out) / ReplacedRun::stash_name();
  fs::remove_all(stash, ec);  // a run killed before it could delete or restore its stash
  const std::vector<fs::path> ours = run_entries(out);
  if (ours.empty()) return {};
  if (!overwrite)
    throw Error(
        names.folder + " " + out + ": the folder holds an earlier run (" +
        ours.front().filename().string() +
        (ours.size() > 1 ? ", … " + std::to_string(ours.size()) + " entries" : std::string()) +
        "); give another folder, or " + names.overwrite + " to replace that run");
  fs::create_directory(stash);
  std::vector<std::string> moved;
  try {
    for (const auto& p : ours) {
      fs::rename(p, stash / p.filename());
      moved.push_back(p.filename().string());
    }
  } catch (...) {  // the folder as it was
    ReplacedRun(out, moved).restore();
    throw;
  }
  return ReplacedRun(out, std::move(moved));
}

}  // namespace lsmbs
