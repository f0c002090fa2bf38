#pragma once
// ProgressLine — one self-overwriting status line on stderr for long commands on a terminal:
// time, step and Newton iterations of a simulation. Disabled, it costs one branch; enabled, it
// redraws at most ten times a second so that printing never shows up in the step cost.
#include <chrono>
#include <cstdarg>
#include <cstdio>

#include "app/terminal.hpp"
#include "lsmbs/core/progress.hpp"

namespace lsmbs::app {

class ProgressLine {
 public:
  explicit ProgressLine(bool enabled = false) : enabled_(enabled) {}
  bool enabled() const { return enabled_; }

  /// Redraws the line (printf format) unless the last redraw was less than 0.1 s ago; `force`
  /// redraws regardless (e.g. at the end of a phase).
  __attribute__((format(printf, 3, 4))) void update(bool force, const char* fmt, ...) {
    if (!enabled_) return;
    const auto now = std::chrono::steady_clock::now();
    if (!force && drawn_ && now - last_ < std::chrono::milliseconds(100)) return;
    last_ = now;
    drawn_ = true;
    std::va_list ap;
    va_start(ap, fmt);
    raw_control("\r\033[K");  // carriage return, erase to the end of the line
    std::vfprintf(stderr, fmt, ap);
    va_end(ap);
    std::fflush(stderr);
  }
  /// Erases the line so that ordinary output can follow.
  void clear() {
    if (!enabled_ || !drawn_) return;
    raw_control("\r\033[K");
    drawn_ = false;
  }
  /// The library's progress reports drawn on this line (empty when disabled: no calls at all).
  ProgressCallback callback() {
    if (!enabled_) return {};
    return [this](const Progress& p) {
      if (p.step > 0)
        update(false, "%s t = %.5f s (%3.0f %%)  step %ld  Newton %d", p.label.c_str(), p.t,
               100.0 * p.fraction(), p.step, p.newton_iterations);
      else
        update(false, " %s t = %.5f s (%3.0f %%)", p.label.c_str(), p.t, 100.0 * p.fraction());
    };
  }

 private:
  bool enabled_ = false;
  bool drawn_ = false;
  std::chrono::steady_clock::time_point last_{};
};

}  // namespace lsmbs::app
