// lsmbs verify: the verification report of a case (every sensitivity method against central
// differences and IDAS, the Δp, time-step and mesh studies), with pass/fail verdicts.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>

#include "app/commands/commands.hpp"
#include "app/commands/common.hpp"
#include "lsmbs/core/text.hpp"

namespace lsmbs::app {

void check_verify_options(const VerifyOptions& vo) {
  if (auto msg = vo.validate(); !msg.empty()) {  // named as the command line spells the option
    const auto colon = msg.find(':');
    std::string option = "--" + msg.substr(0, colon);
    std::replace(option.begin(), option.end(), '_', '-');
    throw Error(option + msg.substr(colon));
  }
}

int verify_command(const CommonArgs& c, VerifyArgs a) {
  VerifyOptions& vo = a.options;
  check_verify_options(vo);
  vo.out_dir = c.out;
  vo.command_line = c.command_line;
  check_sets(c.case_file, c.sets);
  for (const auto& st : c.sets) {
    if (!st.empty() && st[0] == '/')
      vo.case_overrides.push_back(parse_override(st));
    else
      vo.design_overrides.push_back(parse_set(st));
  }
  const auto start = std::chrono::steady_clock::now();
  vo.on_stage = [&](const std::string& what) {  // a line per part: verify runs for a while
    std::fprintf(stderr, "lsmbs verify: %s … (%.1f s)\n", what.c_str(),
                 std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
  };
  vo.on_plan = [&](const std::string& what) {
    std::fprintf(stderr, "lsmbs verify: %s\n", what.c_str());
  };
  // Inside a part, a line about every 10 s (on a terminal or not: a batch job's log shows that a
  // long IDAS reference is moving). LSMBS_PROGRESS_SECONDS sets the interval (a testing hook: 0
  // prints every report).
  double every = 10;
  if (const char* env = std::getenv("LSMBS_PROGRESS_SECONDS")) {
    const auto v = parse_finite_double(env);
    if (!v || *v < 0)
      throw Error("environment variable LSMBS_PROGRESS_SECONDS=" + shown(env) +
                  ": expected a number of seconds >= 0");
    every = *v;
  }
  double last = -1e300;
  vo.on_progress = [&, every](const Progress& pr) {
    const double now =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (now - last < every) return;
    last = now;
    std::fprintf(stderr, "lsmbs verify:   %s t = %.6g of %.6g s (%.0f %%) (%.1f s)\n",
                 pr.label.c_str(), pr.t, pr.t_end, 100 * pr.fraction(), now);
  };
  vo.on_loaded = [&](const Case& cs) { claim_output(c, *cs.model); };
  const auto r = run_verify(c.case_file, vo);
  int notes = 0;
  for (const auto& v : r.summary["verdicts"]) {
    std::printf("  %s\n", v.get<std::string>().c_str());
    notes += v.get<std::string>().rfind("NOTE", 0) == 0;
  }
  const std::string undecided = notes ? " (" + std::to_string(notes) +
                                            (notes == 1 ? " check" : " checks") +
                                            " could not decide: NOTE)"
                                      : "";
  std::printf("lsmbs verify: %s%s — report in %s/report.md\n",
              r.pass ? "all checks pass" : "SOME CHECKS FAIL", undecided.c_str(), c.out.c_str());
  return r.pass ? 0 : 1;
}

}  // namespace lsmbs::app
