#pragma once
// The one place that draws pictures of data (history.png, convergence.png, methods.png and the
// verification plots), rendered in memory with cairo (Debian libcairo2-dev, fonts from
// fonts-dejavu-core) and written by the project's PNG writer (io/png.hpp, atomic).
//
// No script interpreter is involved: every string a user gave (case, body, measure, response and
// variable names, output paths) is drawn as text and nothing else. Text that is not valid UTF-8 or
// holds control characters is drawn with U+FFFD in their place, and long text is cut with an
// ellipsis to the room it has. (The pictures were drawn by piping scripts to gnuplot before: a
// name with a newline was a gnuplot command, and gnuplot runs shell commands with `system`.)
//
// A picture either is written whole or the call throws (core/error.hpp: an output write failure
// such as a full disk is an OutputError); bad data (no finite point) returns false and writes
// nothing.
#include <string>
#include <vector>

namespace lsmbs {

/// Series colours, in order (then again): blue, red, green, purple, orange, brown.
inline constexpr const char* kSeriesColours[] = {"#1f77b4", "#d62728", "#2ca02c",
                                                 "#9467bd", "#ff7f0e", "#8c564b"};

/// One curve of a plot: the points (x[i], y[i]); points that are not finite, or not positive on a
/// log axis, are not drawn and break the line.
struct PlotSeries {
  std::vector<double> x, y;
  std::string title;
  bool lines = true, points = true;
  int dash = 0;            ///< 0 solid, 1 dashed, 2 dotted
  bool reference = false;  ///< a guide line (a slope), in grey; the data series take the colours
};

/// One set of axes with a legend right of them. Layout (pixels): the plot area spans the columns
/// [kLeft, width − kRight) and the rows [kTop, height − kBottom); its frame is drawn on those
/// borders, and x (y) maps linearly, or logarithmically on a log axis, onto them.
struct PlotSpec {
  std::string png, title, xlabel, ylabel;
  bool logx = false, logy = false;
  double ymin = 0, ymax = 0;  ///< y range when ymax > ymin; otherwise from the data
  std::vector<PlotSeries> series;
  int width = 900, height = 560;
  static constexpr int kLeft = 110, kRight = 190, kTop = 40, kBottom = 64;
};
/// False (nothing written) when no series has a point to draw.
bool plot(const PlotSpec& spec);

/// Panels stacked over one shared x axis: the time-history picture of `simulate` (history.png)
/// and the convergence picture of `optimize`. The layout is fixed so that a reader (or a test) can
/// map pixels back to values: each panel's plot area spans the pixel columns [kLeft, width −
/// kRight) and rows of height panel_height between kTop and kBottom pixels of margin, panels kGap
/// pixels apart; the x range is exactly [x_first, x_last] of the data, and each panel's y range is
/// the [min, max] of its finite values widened by 5 % of max − min on both sides (± 5 % of
/// |value|, or ± 1, when constant).
struct PanelSeries {
  int column = 2;  ///< 1-based column of the rows
  std::string title;
};
struct Panel {
  std::string ylabel;
  std::vector<PanelSeries> series;
};
struct PanelPlotSpec {
  std::string png, title, xlabel;
  std::vector<Panel> panels;
  int width = 900, panel_height = 200;
  bool points = false;  ///< a marker at every row (few rows: optimization evaluations)
  static constexpr int kLeft = 110, kRight = 190, kTop = 40, kBottom = 64, kGap = 16;
};
/// Draws the panels from `rows` (x in column 1); false (nothing written) with fewer than two rows
/// or an empty x range.
bool plot_panels(const PanelPlotSpec& spec, const std::vector<std::vector<double>>& rows);

/// Clustered bars: for each group (x axis, labels turned), one bar per series in the colours of
/// kSeriesColours; NaN draws no bar. The y range holds every bar and 0, widened by 10 % of its
/// span on both sides; a black line marks y = 0. The plot area spans the columns
/// [kLeft, width − kRight) and the rows [kTop, height − kBottom).
struct BarChartSpec {
  std::string png, title, ylabel;
  std::vector<std::string> groups, series;
  std::vector<std::vector<double>> values;  ///< [series][group]
  int width = 900, height = 560;
  static constexpr int kLeft = 110, kRight = 190, kTop = 40, kBottom = 130;
};
/// False (nothing written) when there is nothing to draw.
bool plot_bars(const BarChartSpec& spec);

}  // namespace lsmbs
