#pragma once
// Clean interruption of long runs: SIGINT/SIGTERM/SIGHUP set a flag that runs poll at Newton
// iterations or evaluation boundaries (a simulation then drops the step in progress, an
// optimization finishes the evaluation; both write what they have with status "partial" /
// "interrupted"); a second signal terminates at once.
#include <atomic>
#include <csignal>
#include <cstdlib>
#include <string>

#include "lsmbs/core/error.hpp"

namespace lsmbs {

inline std::atomic<int>& interrupt_signal() {
  static std::atomic<int> sig{0};
  return sig;
}

/// The signal that asked to stop (SIGINT, SIGTERM, SIGHUP), or 0.
inline int interrupted() { return interrupt_signal().load(std::memory_order_relaxed); }

namespace detail {
extern "C" inline void lsmbs_on_interrupt(int sig) {
  if (interrupt_signal().exchange(sig) != 0) {  // the second one: stop now
    std::signal(sig, SIG_DFL);
    std::raise(sig);
  }
}
}  // namespace detail

/// A phase that cannot return a partial result (a gradient check's simulations, the writing of
/// outputs) ends by throwing this once an interrupt was requested; the command line then flags
/// the run "interrupted" and exits with 130. A NumericalFailure, so that code which turns failed
/// simulations into a failed result does the same for an interrupted one (and checks
/// interrupted() to tell them apart).
class Interrupted : public NumericalFailure {
 public:
  explicit Interrupted(const std::string& during)
      : NumericalFailure("interrupted by signal " + std::to_string(interrupted()) + " " + during) {}
};

/// Throws Interrupted when an interrupt was requested; `during` says where ("while writing
/// history.csv").
inline void throw_if_interrupted(const std::string& during) {
  if (interrupted()) throw Interrupted(during);
}

/// Testing hook (docs/verification.md): with LSMBS_TEST_SIGNAL=POINT, POINT:TERM or POINT:HUP in
/// the environment, the process sends itself SIGINT (SIGTERM, SIGHUP) the first time it reaches the
/// named point, so that a test interrupts a given phase without depending on timing. The points:
/// gradient-check, adjoint-backward, adjoint-recompute, verify:<stage number>, write-outputs.
inline void signal_point(const char* point) {
  static std::atomic<bool> fired{false};
  const char* spec = std::getenv("LSMBS_TEST_SIGNAL");
  if (!spec || fired.load()) return;
  const std::string s = spec, p = point;
  const bool term = s == p + ":TERM", hup = s == p + ":HUP";
  if ((s == p || s == p + ":INT" || term || hup) && !fired.exchange(true))
    std::raise(term ? SIGTERM : hup ? SIGHUP : SIGINT);
}

/// Installs the handlers (the command line does, before a run): SIGINT (Ctrl-C), SIGTERM, and
/// SIGHUP (the terminal closed), which ended a run at once, with no summary.json and its files
/// unlisted (the folder then refused the next run).
inline void install_interrupt_handlers() {
  std::signal(SIGINT, detail::lsmbs_on_interrupt);
  std::signal(SIGTERM, detail::lsmbs_on_interrupt);
  std::signal(SIGHUP, detail::lsmbs_on_interrupt);
}

}  // namespace lsmbs
