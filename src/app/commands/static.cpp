// lsmbs static: the static equilibrium of a case at one time (measures, responses, VTU, summary).
#include "lsmbs/runs/static.hpp"

#include <cstdio>

#include "app/commands/commands.hpp"
#include "app/commands/common.hpp"
#include "lsmbs/core/error.hpp"
#include "lsmbs/core/text.hpp"
#include "lsmbs/integrators/static_solver.hpp"
#include "lsmbs/io/case.hpp"

namespace lsmbs::app {

int static_command(const CommonArgs& c, const StaticArgs& a) {
  lsmbs::StaticOptions so;  // the command line's values, checked before the case is loaded
  so.t = a.t;
  so.max_iter = a.max_iter;
  if (auto msg = so.validate(); !msg.empty())
    throw lsmbs::Error(lsmbs::rename_fields(msg, {{"t", "--t"}, {"max_iter", "--max-iter"}}));
  lsmbs::Case cs = load_case_with_sets(c.case_file, c.sets);
  lsmbs::StaticRunOptions o;
  o.out_dir = c.out;
  o.command_line = c.command_line;
  o.t = a.t;
  o.max_iter = a.max_iter;
  if (cs.design) {
    o.design_point = design_point(cs, c.sets);
    cs.design->apply(o.design_point, cs.model->params());
  }
  claim_output(c, *cs.model);
  const auto r = lsmbs::run_static(cs, o);
  if (!c.quiet)
    std::printf("lsmbs static: %s\n  results in %s\n", r.report().c_str(), c.out.c_str());
  if (!r.solver.ok) {
    std::fprintf(stderr, "lsmbs static: no equilibrium found: %s\n", r.solver.message.c_str());
    return 1;
  }
  return 0;
}

}  // namespace lsmbs::app
