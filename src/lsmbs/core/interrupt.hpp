#pragma once
// Clean interruption of long runs: SIGINT/SIGTERM set a flag that runs poll at Newton iterations
// or evaluation boundaries (a simulation then drops the step in progress, an optimization finishes
// the evaluation; both write what they have with status "partial" / "interrupted"); a second
// signal terminates at once.
#include <atomic>
#include <csignal>

namespace lsmbs {

inline std::atomic<int>& interrupt_signal() {
  static std::atomic<int> sig{0};
  return sig;
}

/// The signal that asked to stop (SIGINT, SIGTERM), or 0.
inline int interrupted() { return interrupt_signal().load(std::memory_order_relaxed); }

namespace detail {
extern "C" inline void lsmbs_on_interrupt(int sig) {
  if (interrupt_signal().exchange(sig) != 0) {  // the second one: stop now
    std::signal(sig, SIG_DFL);
    std::raise(sig);
  }
}
}  // namespace detail

/// Installs the handlers (the command line does, before a run).
inline void install_interrupt_handlers() {
  std::signal(SIGINT, detail::lsmbs_on_interrupt);
  std::signal(SIGTERM, detail::lsmbs_on_interrupt);
}

}  // namespace lsmbs
