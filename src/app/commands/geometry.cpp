// lsmbs geometry: the level-set design mapped on the mesh (μ_e VTU and PNG, mass and its gradient).
#include "lsmbs/runs/geometry.hpp"

#include <cstdio>

#include "app/commands/commands.hpp"
#include "app/commands/common.hpp"
#include "lsmbs/core/error.hpp"
#include "lsmbs/io/case.hpp"

namespace lsmbs::app {

int geometry_command(const CommonArgs& c, const GeometryArgs& a) {
  const std::string& case_file = c.case_file;
  const std::string& out = c.out;
  lsmbs::Case cs = load_case_with_sets(case_file, c.sets);
  if (!cs.design)
    throw lsmbs::Error(case_file, "/design", "the case has no design section (nothing to map)");
  const lsmbs::Vec p = design_point(cs, c.sets);
  claim_output(c, *cs.model);
  lsmbs::GeometryRunOptions o;
  o.out_dir = out;
  o.image_width = a.width;
  o.command_line = c.command_line;
  const auto S = lsmbs::run_geometry(cs, p, o);
  for (const auto& w : S["warnings"])
    std::fprintf(stderr, "lsmbs geometry: warning: %s\n", w.get<std::string>().c_str());
  if (!c.quiet) {
    for (const auto& b : S["bodies"])
      if (b.contains("material_volume"))  // a solid body
        std::printf(
            "lsmbs geometry: body '%s': mass %.6f kg, material volume %.6e of %.6e m³, %d of %d "
            "elements cut by a boundary (%d integrated on the sub-grid, within 30 bands of "
            "one)\n",
            b["body"].get<std::string>().c_str(), b["mass"].get<double>(),
            b["material_volume"].get<double>(), b["domain_volume"].get<double>(),
            b["cut_elements"].get<int>(), b["elements"].get<int>(), b["band_elements"].get<int>());
      else
        std::printf(
            "lsmbs geometry: body '%s': mass %.6f kg, void area %.6e m², %d of %d elements cut "
            "by a boundary (%d integrated on the sub-grid, within 30 bands of one)\n",
            b["body"].get<std::string>().c_str(), b["mass"].get<double>(),
            b["void_area"].get<double>(), b["cut_elements"].get<int>(), b["elements"].get<int>(),
            b["band_elements"].get<int>());
    std::printf("  results in %s\n", out.c_str());
  }
  return 0;
}

}  // namespace lsmbs::app
