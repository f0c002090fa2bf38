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

/// Panels stacked over one shared x axis: the time-history picture of `simulate` (history.png).
/// The layout is fixed so that a reader (or a test) can map pixels back to values: each panel's
/// plot area spans the pixel columns [kLeft, width − kRight) and rows of height panel_height
/// between kTop and kBottom pixels of margin, panels kGap pixels apart; the x range is exactly
/// [x_first, x_last] of the data, and each panel's y range is the [min, max] of its finite values
/// widened by 5 % of max − min on both sides (± 5 % of |value|, or ± 1, when constant).
struct PanelSeries {
  int column = 2;  ///< 1-based column of the CSV (and of the rows)
  std::string title;
};
struct Panel {
  std::string ylabel;
  std::vector<PanelSeries> series;
};
struct PanelPlotSpec {
  std::string png, csv, title, xlabel;
  std::vector<Panel> panels;
  int width = 900, panel_height = 200;
  static constexpr int kLeft = 110, kRight = 190, kTop = 40, kBottom = 64, kGap = 16;
};
/// Series colours, in order (then again): blue, red, green, purple, orange, brown.
inline constexpr const char* kSeriesColours[] = {"#1f77b4", "#d62728", "#2ca02c",
                                                 "#9467bd", "#ff7f0e", "#8c564b"};
/// Draws the panels from `rows` (the rows of spec.csv, x in column 1); false when gnuplot is
/// missing or fails (no picture is left then).
bool plot_panels(const PanelPlotSpec& spec, const std::vector<std::vector<double>>& rows);

/// Clustered bars: for each group (x axis, labels turned), one bar per series in the colours of
/// kSeriesColours; NaN draws no bar. The y range holds every bar and 0, widened by 10 %.
struct BarChartSpec {
  std::string png, title, ylabel;
  std::vector<std::string> groups, series;
  std::vector<std::vector<double>> values;  ///< [series][group]
  int width = 900, height = 560;
};
/// False when gnuplot is missing or fails (no picture is left then).
bool plot_bars(const BarChartSpec& spec);

/// Runs `gnuplot SCRIPT` without a shell (any path is safe), output discarded; false when gnuplot
/// is missing or fails.
bool run_gnuplot(const std::string& script);
/// A gnuplot double-quoted string literal of s (backslashes and quotes escaped).
std::string gnuplot_quote(const std::string& s);

}  // namespace lsmbs
