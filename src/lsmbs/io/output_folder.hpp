#pragma once
// The output folder of a run, checked before anything runs: it must exist or be creatable and be
// writable, and a folder that holds an earlier lsmbs run is refused unless the caller asks to
// replace that run. Used by the command line (-o, --overwrite) and the Python module (out_dir,
// overwrite=True); `names` words the messages for either.
#include <string>
#include <vector>

namespace lsmbs {

struct OutputFolderNames {
  std::string folder = "-o";              ///< how the caller names the folder argument
  std::string overwrite = "--overwrite";  ///< … and the option that replaces an earlier run
};

/// Throws Error unless `out` is a folder that exists or can be created, and is writable (nothing
/// is created).
void check_output_folder(const std::string& out, const OutputFolderNames& names = {});
/// The earlier run that an overwrite replaces, kept aside in a hidden folder of the output folder
/// until this run is past its input checks. restore() puts it back (the run stopped on bad input:
/// the folder is as it was); otherwise the destructor deletes it.
class ReplacedRun {
 public:
  ReplacedRun() = default;
  ReplacedRun(std::string out, std::vector<std::string> names);
  ReplacedRun(ReplacedRun&& o) noexcept;
  ReplacedRun& operator=(ReplacedRun&& o) noexcept;
  ReplacedRun(const ReplacedRun&) = delete;
  ReplacedRun& operator=(const ReplacedRun&) = delete;
  ~ReplacedRun();
  /// Removes what this run wrote and moves the earlier run's files back.
  void restore();
  /// The hidden folder's name.
  static const char* stash_name();

 private:
  std::string out_;
  std::vector<std::string> names_;  // the earlier run's entries, now in the stash
};

/// Refuses a folder that holds an earlier run unless `overwrite`, which sets that run's files (and
/// only those) aside, to be deleted when the returned object goes or restored by it. `resume`
/// (optimize) continues the run the folder holds.
[[nodiscard]] ReplacedRun claim_output_folder(const std::string& out, bool overwrite, bool resume,
                                              const OutputFolderNames& names = {});

}  // namespace lsmbs
