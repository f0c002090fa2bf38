#pragma once
// The output folder of a run, checked before anything runs: it must exist or be creatable and be
// writable, and a folder that holds an earlier lsmbs run is refused unless the caller asks to
// replace that run. Used by the command line (-o, --overwrite) and the Python module (out_dir,
// overwrite=True); `names` words the messages for either.
#include <string>

namespace lsmbs {

struct OutputFolderNames {
  std::string folder = "-o";              ///< how the caller names the folder argument
  std::string overwrite = "--overwrite";  ///< … and the option that replaces an earlier run
};

/// Throws Error unless `out` is a folder that exists or can be created, and is writable (nothing
/// is created).
void check_output_folder(const std::string& out, const OutputFolderNames& names = {});
/// Refuses a folder that holds an earlier run unless `overwrite`, which removes that run's files
/// (and only those: summary.json first). `resume` (optimize) continues the run the folder holds.
void claim_output_folder(const std::string& out, bool overwrite, bool resume,
                         const OutputFolderNames& names = {});

}  // namespace lsmbs
