#include "lsmbs/io/output_folder.hpp"

#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <utility>
#include <vector>

#include "lsmbs/core/error.hpp"
#include "lsmbs/core/text.hpp"
#include "lsmbs/io/output.hpp"

namespace lsmbs {

namespace fs = std::filesystem;

// The output folder (-o) must be a folder that exists or can be created, and be writable: checked
// before anything runs, without creating it (nothing is written for invalid input).
void check_output_folder(const std::string& out, const OutputFolderNames& names) {
  const std::string& o = names.folder;
  if (out.empty()) throw Error(o + " \"\": expected an output folder name");
  if (!valid_utf8(out))
    throw Error(o + " " + shown(out, 4096) +
                ": the folder name is not valid UTF-8 text (summary.json records it)");
  if (out.find('\0') != std::string::npos)
    throw Error(o + ": expected a folder name without a NUL character");
  std::error_code ec;
  fs::path p = fs::absolute(out, ec);
  if (ec) throw Error(o + " " + out + ": not a usable path (" + ec.message() + ")");
  for (const auto& part : p)  // Linux: NAME_MAX 255 bytes a name, PATH_MAX 4096 bytes a path
    if (part.string().size() > 255)
      throw Error(o + " " + displayable_text(out, 80) +
                  ": a folder name is longer than 255 bytes, the file system's limit");
  if (p.string().size() > 3800)
    throw Error(o + " " + displayable_text(out, 80) +
                ": the path is longer than the file system allows once lsmbs adds its own "
                "file names (4096 bytes)");
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

std::set<std::string> planned_outputs(const Model& model) {
  std::set<std::string> p = {
      "summary.json", "history.csv",     "history.png", "gradients.csv",    "checkpoint.json",
      "report.md",    "bench.json",      "methods.csv", "methods.png",      "convergence.png",
      "dp_study.csv", "dp_study.png",    "h_study.csv", "h_study_plot.csv", "h_study.png",
      "starts.csv",   "multistart.json", "vtu",         "final_design",     "final_state.json",
      "conditions",   "sweep.csv",       "sweep.json"};
  p.insert(std::string(kModelVtk) + ".pvd");
  p.insert(std::string(kModelVtk) + ".vtm");
  for (const auto& [name, stem] : body_file_stems(model))
    for (const char* ext : {".pvd", ".vtu", ".png"}) p.insert(stem + ext);
  return p;
}

namespace {

// A listed path is one of the run's own only when it stays inside its folder.
bool inside(const fs::path& rel) {
  return !rel.empty() && rel.is_relative() && *rel.begin() != ".." && *rel.begin() != ".";
}

void collect(const fs::path& root, const fs::path& sub, std::vector<std::string>& files,
             int depth) {
  nlohmann::json S;
  try {
    std::ifstream in(root / sub / "summary.json");
    if (!in) return;
    S = nlohmann::json::parse(in);
  } catch (const std::exception&) {  // not JSON: not a summary of ours
    return;
  }
  if (!S.is_object() || S.value("program", "") != "lsmbs") return;
  std::error_code ec;
  if (S.contains("files") && S["files"].is_array())
    for (const auto& f : S["files"]) {
      if (!f.is_string()) continue;
      const std::string s = f.get<std::string>();
      const fs::path rel = fs::path(s).lexically_normal();
      if (!inside(rel) || rel.filename() == ReplacedRun::stash_name()) continue;
      if (!s.empty() && s.back() == '/') {  // a folder of runs (multi-start): its own summary
        if (depth < 4) collect(root, sub / rel, files, depth + 1);
        continue;
      }
      if (rel == "summary.json") continue;
      if (fs::is_regular_file(root / sub / rel, ec)) files.push_back((sub / rel).string());
    }
  files.push_back((sub / "summary.json").string());  // last: see claim_output_folder
}

// Removes the folders (below `out`) that the files leave empty.
void remove_empty_parents(const fs::path& out, const std::vector<std::string>& files) {
  std::error_code ec;
  for (const auto& f : files)
    for (fs::path d = fs::path(f).parent_path(); !d.empty(); d = d.parent_path()) {
      if (!fs::is_directory(out / d, ec) || !fs::is_empty(out / d, ec)) break;
      fs::remove(out / d, ec);
    }
}

}  // namespace

std::vector<std::string> listed_run_files(const std::string& out) {
  std::vector<std::string> files;
  collect(out, "", files, 0);
  return files;
}

const char* ReplacedRun::stash_name() { return ".lsmbs-replaced-run"; }

ReplacedRun::ReplacedRun(std::string out, std::vector<std::string> files)
    : out_(std::move(out)), files_(std::move(files)) {}

ReplacedRun::ReplacedRun(ReplacedRun&& o) noexcept
    : out_(std::exchange(o.out_, {})), files_(std::move(o.files_)) {}

ReplacedRun& ReplacedRun::operator=(ReplacedRun&& o) noexcept {
  if (this != &o) {
    this->~ReplacedRun();
    out_ = std::exchange(o.out_, {});
    files_ = std::move(o.files_);
  }
  return *this;
}

ReplacedRun::~ReplacedRun() {
  if (out_.empty()) return;
  std::error_code ec;
  fs::remove_all(fs::path(out_) / stash_name(), ec);
}

void ReplacedRun::restore() {
  if (out_.empty()) return;
  const fs::path out(out_), stash = out / stash_name();
  std::error_code ec;
  // what this run wrote, if it got as far as a summary.json
  const std::vector<std::string> own = listed_run_files(out_);
  for (const auto& f : own) fs::remove(out / f, ec);
  remove_empty_parents(out, own);
  // the earlier run's files back, its summary last, so that an interrupted restore never shows
  // the earlier summary beside a half-restored folder
  for (const auto& f : files_) {
    fs::create_directories((out / f).parent_path(), ec);
    fs::rename(stash / f, out / f, ec);
  }
  fs::remove_all(stash, ec);
  out_.clear();
}

ReplacedRun claim_output_folder(const std::string& out, bool overwrite, bool resume,
                                const std::set<std::string>& planned,
                                const OutputFolderNames& names) {
  std::error_code ec;
  if (resume || !fs::is_directory(out, ec)) return {};
  const fs::path root(out), stash = root / ReplacedRun::stash_name();
  // A run killed (SIGKILL, power loss) before it could delete or restore its stash: when it left no
  // summary.json it did not finish, and the earlier run it was replacing is put back (its files
  // replace the same-named ones the killed run wrote); when it finished, the stash is deleted.
  if (fs::exists(stash, ec)) {
    if (!fs::exists(root / "summary.json", ec))
      for (const auto& f : listed_run_files(stash.string())) {
        fs::create_directories((root / f).parent_path(), ec);
        fs::rename(stash / f, root / f, ec);
      }
    fs::remove_all(stash, ec);
  }
  const std::vector<std::string> earlier = listed_run_files(out);
  std::set<std::string> earlier_top;  // the top-level entries the earlier run's files are in
  for (const auto& f : earlier) earlier_top.insert(fs::path(f).begin()->string());
  // entries this run would write that no summary lists as an earlier run's
  std::vector<std::string> conflicts;
  for (const auto& e : fs::directory_iterator(out, ec)) {
    const std::string name = e.path().filename().string();
    const bool planned_name =
        planned.count(name) || (name.rfind("start_", 0) == 0 && e.is_directory(ec));
    if (!planned_name || earlier_top.count(name) == 0) {
      if (planned_name) conflicts.push_back(name);
      continue;
    }
    // a folder the earlier run wrote into (vtu/): files in it that it does not list
    if (e.is_directory(ec))
      for (const auto& g : fs::recursive_directory_iterator(e.path(), ec)) {
        if (!g.is_regular_file(ec)) continue;
        const std::string rel = fs::relative(g.path(), root, ec).string();
        if (std::find(earlier.begin(), earlier.end(), rel) == earlier.end())
          conflicts.push_back(rel);
      }
  }
  if (!conflicts.empty()) {
    std::sort(conflicts.begin(), conflicts.end());
    std::string list = conflicts.front();
    for (size_t k = 1; k < conflicts.size() && k < 4; ++k) list += ", " + conflicts[k];
    if (conflicts.size() > 4) list += ", … (" + std::to_string(conflicts.size()) + " in all)";
    const std::string whose =
        earlier.empty()
            ? ", which this run would write, and no summary.json there lists as a run's own"
            : ", which this run would write; the earlier run in this folder (its summary.json) "
              "does not list " +
                  std::string(conflicts.size() == 1 ? "it" : "them") + " as its own";
    throw Error(names.folder + " " + out + ": holds " + list + whose +
                ": lsmbs takes such files for yours and never replaces them (not even with " +
                names.overwrite + "): move " + (conflicts.size() == 1 ? "it" : "them") +
                ", or give another folder");
  }
  if (earlier.empty()) return {};
  if (!overwrite)
    throw Error(names.folder + " " + out + ": the folder holds an earlier run (summary.json, " +
                std::to_string(earlier.size() - 1) + " more files it lists); give another " +
                "folder, or " + names.overwrite +
                " to replace that run (only the files its summary.json lists)");
  // summary.json first: a run stopped while the rest moves never leaves the earlier run's summary
  // next to a half-moved folder
  std::vector<std::string> order = earlier;
  std::stable_partition(order.begin(), order.end(), [](const std::string& f) {
    return fs::path(f).filename() == "summary.json";
  });
  std::vector<std::string> moved;
  try {
    for (const auto& f : order) {
      fs::create_directories((stash / f).parent_path());
      fs::rename(root / f, stash / f);
      moved.push_back(f);
    }
  } catch (...) {  // the folder as it was
    ReplacedRun(out, moved).restore();
    throw;
  }
  remove_empty_parents(root, earlier);
  std::stable_partition(moved.begin(), moved.end(), [](const std::string& f) {
    return fs::path(f).filename() != "summary.json";
  });
  return ReplacedRun(out, std::move(moved));
}

}  // namespace lsmbs
