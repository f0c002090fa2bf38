#pragma once
// The output folder of a run, checked before anything runs and claimed once the case has loaded.
//
// lsmbs deletes or replaces only files that an earlier run's summary.json lists as its own
// (summary.json["files"], and summary.json itself); files it did not write are never touched:
//  * a folder whose summary.json lists an earlier run is refused unless the caller asks to replace
//    that run (--overwrite, overwrite=True), which sets exactly the listed files aside (restored if
//    this run stops on bad input, deleted otherwise); a listed folder entry ("start_1/") is the
//    run that folder's own summary.json describes, by the same rule;
//  * a file this run would write that no summary.json lists (a user's history.csv, the files of a
//    run killed before it wrote its summary) is a conflict: the run is refused, naming it, rather
//    than overwrite it;
//  * everything else in the folder (a user's notes.csv, my_plot.png, the case's own tables) stays
//    where it is.
// Used by the command line (-o, --overwrite) and the Python module (out_dir, overwrite=True);
// `names` words the messages for either.
#include <set>
#include <string>
#include <vector>

#include "lsmbs/mbs/model.hpp"

namespace lsmbs {

struct OutputFolderNames {
  std::string folder = "-o";              ///< how the caller names the folder argument
  std::string overwrite = "--overwrite";  ///< … and the option that replaces an earlier run
};

/// Throws Error unless `out` is a folder that exists or can be created, and is writable (nothing
/// is created). The path must be valid UTF-8 (it is recorded in summary.json).
void check_output_folder(const std::string& out, const OutputFolderNames& names = {});

/// The names a run of `model` may write at the top of its output folder: the fixed ones
/// (summary.json, history.csv, vtu/, …) and each body's files (io/output.hpp, body_file_stems).
std::set<std::string> planned_outputs(const Model& model);

/// The earlier run that an overwrite replaces, kept aside in a hidden folder of the output folder
/// until this run is past its input checks. restore() puts it back (the run stopped on bad input:
/// the folder is as it was); otherwise the destructor deletes it.
class ReplacedRun {
 public:
  ReplacedRun() = default;
  ReplacedRun(std::string out, std::vector<std::string> files);
  ReplacedRun(ReplacedRun&& o) noexcept;
  ReplacedRun& operator=(ReplacedRun&& o) noexcept;
  ReplacedRun(const ReplacedRun&) = delete;
  ReplacedRun& operator=(const ReplacedRun&) = delete;
  ~ReplacedRun();
  /// Removes what this run wrote (the files its summary.json lists, if it wrote one) and moves the
  /// earlier run's files back.
  void restore();
  /// The hidden folder's name.
  static const char* stash_name();

 private:
  std::string out_;
  std::vector<std::string> files_;  // the earlier run's files (relative paths), now in the stash
};

/// Claims `out` for a run that may write `planned` (planned_outputs) as described above: refuses
/// an earlier run unless `overwrite`, refuses a conflict with files no summary lists, and sets the
/// earlier run's files aside when overwriting. `resume` (optimize) continues the run the folder
/// holds: nothing is checked or moved.
[[nodiscard]] ReplacedRun claim_output_folder(const std::string& out, bool overwrite, bool resume,
                                              const std::set<std::string>& planned,
                                              const OutputFolderNames& names = {});

/// The files an earlier run in `out` lists as its own (relative paths, summary.json last;
/// recursively through listed folders), existing ones only. Empty when `out` has no readable
/// summary.json written by lsmbs.
std::vector<std::string> listed_run_files(const std::string& out);

}  // namespace lsmbs
