// lsmbs sweep: the command line of run_sweep (runs/sweep.hpp): responses (and gradients) at the
// points of a grid or a Latin hypercube over design variables, model parameters or values of the
// case, in sweep.csv, one row per point as it finishes.
#include "lsmbs/runs/sweep.hpp"

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "app/commands/commands.hpp"
#include "app/commands/common.hpp"
#include "lsmbs/core/error.hpp"
#include "lsmbs/io/case.hpp"
#include "lsmbs/runs/mpi.hpp"

namespace lsmbs::app {
namespace {

// --axis name=lower:upper[:points]
lsmbs::SweepAxis parse_axis(const std::string& s, bool grid) {
  const auto eq = s.rfind('=');
  if (eq == std::string::npos || eq == 0)
    throw lsmbs::Error("--axis " + s + ": expected name=lower:upper" + (grid ? ":points" : ""));
  lsmbs::SweepAxis a;
  a.name = s.substr(0, eq);
  const std::string range = s.substr(eq + 1);
  std::vector<std::string> parts;
  for (size_t b = 0, e; b <= range.size(); b = e + 1) {
    e = std::min(range.find(':', b), range.size());
    parts.push_back(range.substr(b, e - b));
  }
  auto number = [&](const std::string& t) {
    char* end = nullptr;
    const double v = std::strtod(t.c_str(), &end);
    if (t.empty() || *end != '\0' || !std::isfinite(v))
      throw lsmbs::Error("--axis " + s + ": '" + t + "' is not a finite number");
    return v;
  };
  if (parts.size() != (grid ? 3u : 2u))
    throw lsmbs::Error("--axis " + s + ": expected name=lower:upper" +
                       (grid ? ":points (a grid; with --lhs N: name=lower:upper)"
                             : " (with --lhs, no number of points)"));
  a.lower = number(parts[0]);
  a.upper = number(parts[1]);
  if (grid) {
    const double n = number(parts[2]);
    if (n < 1 || n != std::floor(n) || n > 100000)
      throw lsmbs::Error("--axis " + s + ": expected a number of points in 1..100000");
    a.points = static_cast<int>(n);
  }
  return a;
}

}  // namespace

int sweep_command(const CommonArgs& c, const SweepArgs& a) {
  lsmbs::SweepOptions o;
  for (const auto& s : a.axes) o.axes.push_back(parse_axis(s, a.lhs == 0));
  o.samples = a.lhs;
  o.seed = a.seed;
  o.gradients = a.gradients;
  if (!lsmbs::SensitivityOptions::parse(a.method, o.sensitivity.method))
    throw lsmbs::Error("--method " + a.method + ": not a sensitivity method");
  o.sensitivity.threads = 1;  // the points run at once
  o.jobs = a.jobs;
  o.resume = c.resume;
  o.out_dir = c.out;
  o.command = c.command_line;
  if (auto msg = o.validate(); !msg.empty()) throw lsmbs::Error("sweep: " + msg);
  const lsmbs::Case cs = load_case_with_sets(c.case_file, c.sets);
  if (o.gradients && !cs.design)
    throw lsmbs::Error(c.case_file, "/design", "--gradients needs design variables");
  claim_output(c, *cs.model);
  // a line per finished point on a terminal (or with --verbose); else the final line only
  if (!c.quiet && (c.verbose || ::isatty(STDOUT_FILENO)))
    o.on_message = [](const std::string& line) { std::printf("%s\n", line.c_str()); };
  const lsmbs::SweepRun run = lsmbs::run_sweep(cs, o);
  if (lsmbs::mpi::world().rank == 0 && !c.quiet)
    std::printf("lsmbs sweep: %d points complete, %d failed, %d finished before; %s/sweep.csv\n",
                run.completed, run.failed, run.skipped, c.out.c_str());
  if (run.interrupted)
    std::fprintf(stderr, "lsmbs sweep: interrupted; --resume runs the points not finished\n");
  return run.exit_code();
}

}  // namespace lsmbs::app
