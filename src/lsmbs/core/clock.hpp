#pragma once
// Wall-clock seconds and the process's peak memory, for benchmarks (lsmbs bench, bench/).
#include <sys/resource.h>

#include <chrono>

namespace lsmbs {

/// Seconds on the steady clock (differences only).
inline double now_seconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

/// The peak resident set size of this process [kB] (getrusage's ru_maxrss on Linux).
inline long peak_rss_kb() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_maxrss;
}

}  // namespace lsmbs
