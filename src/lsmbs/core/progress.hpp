#pragma once
// Progress of a long run, reported to whoever drives it (the command line draws a status line,
// Python calls a function). The library only fills a Progress and calls the callback; how often
// and where it is shown is the caller's choice.
#include <functional>
#include <string>

namespace lsmbs {

struct Progress {
  std::string label;  ///< e.g. "simulation 3/11" when a method runs several simulations; "IDAS"
  double t = 0;       ///< time reached [s]
  double t_end = 0;   ///< final time of the run [s]
  long step = 0;      ///< steps taken (0 for IDAS output times)
  int newton_iterations = 0;  ///< Newton iterations of the last step (generalized-α)
  double fraction() const { return t_end > 0 ? t / t_end : 0.0; }
};

/// Called at every step of a time integration (empty: no progress reporting).
using ProgressCallback = std::function<void(const Progress&)>;

}  // namespace lsmbs
