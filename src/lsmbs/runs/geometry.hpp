#pragma once
// run_geometry — the `lsmbs geometry` job: maps the case's level-set design at p onto the
// fixed meshes and writes, per designed body, μ_e as VTU and a PNG picture, plus summary.json
// with the mass, ∂m/∂p, the void area and the number of cut elements.
#include <nlohmann/json.hpp>
#include <string>

#include "lsmbs/io/case.hpp"

namespace lsmbs {

struct GeometryRunOptions {
  std::string out_dir;
  int image_width = 1600;
  /// Empty string when valid, otherwise "field: what is expected".
  std::string validate() const;
  std::string command_line;
};

/// Returns the summary (also written to out_dir/summary.json when out_dir is set).
nlohmann::json run_geometry(const Case& cs, const Vec& p, const GeometryRunOptions& o);

}  // namespace lsmbs
