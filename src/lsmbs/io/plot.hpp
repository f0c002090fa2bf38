#pragma once
// The one place that draws pictures of data: PNG plots through gnuplot (Debian package
// gnuplot-nox, installed by scripts/setup-deps.sh). Returns false when gnuplot is missing or
// fails; callers then keep the CSV and say so.
#include <string>
#include <vector>

namespace lsmbs {

struct PlotSeries {
  std::string csv;   ///< comma-separated file with a header line
  int x_column = 1;  ///< 1-based
  int y_column = 2;
  std::string title;
  std::string style = "linespoints";
};

struct PlotSpec {
  std::string png, title, xlabel, ylabel;
  bool logx = false, logy = false;
  double ymin = 0, ymax = 0;  ///< y range when ymax > ymin
  std::vector<PlotSeries> series;
  std::vector<std::string> functions;  ///< extra gnuplot expressions, e.g. "1e-3*x title 'slope 1'"
};

bool plot(const PlotSpec& spec);

/// Runs `gnuplot SCRIPT` without a shell (any path is safe), output discarded; false when gnuplot
/// is missing or fails.
bool run_gnuplot(const std::string& script);
/// A gnuplot double-quoted string literal of s (backslashes and quotes escaped).
std::string gnuplot_quote(const std::string& s);

}  // namespace lsmbs
