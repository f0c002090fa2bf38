// lsmbs verify: the verification report of a case (every sensitivity method against central
// differences and IDAS, the Δp, time-step and mesh studies), with pass/fail verdicts.
#include <algorithm>
#include <chrono>
#include <cstdio>

#include "app/commands/commands.hpp"
#include "app/commands/common.hpp"

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
